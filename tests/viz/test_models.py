"""How many widget models a page of views holds (issue 46: the studio's first view). A page that opens receives every
open model of its kernel and builds each one before it shows, so the count is what the first view pays for; it is
counted here in a kernel-less Python, where ipywidgets keeps every open model in ``Widget.widgets``. No time is
measured: ``posekit bench studio`` times the first view."""

from __future__ import annotations

import warnings
from collections import Counter

import numpy as np
import pytest

from posekit.viz import SkeletonViewer
from posekit.viz.viewer import LOOK_COLOUR, SELECTED_COLOUR


def _open_models() -> dict:
    import ipywidgets

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)  # Widget.widgets: the registry of open models
        return dict(ipywidgets.Widget.widgets)


def _made_by(build):
    """``build()``'s value and the models it left open, counted by class name."""
    before = _open_models()
    value = build()
    return value, Counter(type(m).__name__ for k, m in _open_models().items() if k not in before)


def _hex(colour: str) -> np.ndarray:
    return np.array([int(colour[k:k + 2], 16) / 255 for k in (1, 3, 5)])


@pytest.fixture
def fresh_shared(monkeypatch):
    """The shared models as a fresh kernel has them: none yet. A test that ran before in the same process (another
    page of views) has made the page's shared Layouts and Styles already, and the page would reuse them uncounted."""
    from posekit.viz import shared

    monkeypatch.setattr(shared, "_MODELS", {})
    monkeypatch.setattr(shared, "_HOLDERS", {})


def test_the_studio_page_holds_under_360_widget_models(tmp_path, fresh_shared):
    """The app's page (four views, five effectors, the left hand selected) with four classical solvers: the learned
    ones of the default page change no model, only the time it takes to load them.

    Before sharing, the page held 653 models: 155 ``Layout``s (one per widget), a ``Style`` per widget, and each
    view's own materials, index buffers, drag sphere, shadow and controls (94 models a view). Now a view without
    controls holds its scene alone (scene, camera, two lights, three groups, nine meshes and lines on eight
    geometries, their four position and colour buffers, orbit, picker, renderer: 32); the page holds 289. 360 leaves
    room for a few more controls, not for a return of one Layout per widget or of controls per view."""
    from posekit.viz.studio_app import app_studio

    (studio, _), made = _made_by(lambda: app_studio(solvers="fabrik,dls,ccd,fabrik-constrained", export_dir=tmp_path))
    assert len(studio.editor.viewers) == 4 and len(studio.editor.rows) == 5
    total = sum(made.values())
    assert total < 360, made
    assert made["Layout"] <= 30, made  # one per distinct layout, not one per widget
    styles = {k: n for k, n in made.items() if k.endswith("Style")}
    assert styles and max(styles.values()) == 1, styles  # one per kind of widget


def test_a_view_without_controls_holds_its_scene_alone_and_makes_its_controls_when_asked(sample, fresh_shared):
    s = sample.skeleton
    pose = sample.global_pos[0]
    _, first = _made_by(lambda: SkeletonViewer(s, pose))  # the first view makes the models every view shares
    hand = s.names[s.index("left_hand")]
    v, second = _made_by(lambda: SkeletonViewer(s, pose, controls=False))
    assert sum(second.values()) <= 35, second  # 94 before: its scene (32) and nothing else
    assert "FloatSlider" not in second and "Layout" not in second and "MeshLambertMaterial" not in second, second
    # 94 before, with the page's first Layouts, Styles and materials; 89 with the page-side watcher (drag end, slider
    # focus) and the wrapping rows of the one-screen layout
    assert sum(first.values()) <= 90, first
    v.select(hand)  # a double-click on this view: the joint turns yellow; the controls follow when made
    assert v.controls.layout.display == "none"  # made now, hidden as before
    assert v.joint_select.value == hand and not v.sliders[0].disabled
    np.testing.assert_allclose([sl.value for sl in v.sliders], pose[s.index(hand)], atol=v.SLIDER_STEP)
    v.drag_mode.value = True  # drag in 3D turned on by code: the view gets its drag pickers then
    assert len(v.renderer.controls) == 5 and not v.orbit.enabled
    v._grab.distance = 1.0
    v._on_grab({"new": list(pose[s.index(hand)] - v._offset)})
    assert v.dragging == hand


def test_joint_markers_share_a_material_and_a_selection_recolours_only_its_joint(sample):
    """Every view's joints, targets and look-at markers are drawn with one material model (its bones with one, its
    lines with one); the colour of each sphere is in the view's own colour array, so selecting a joint turns it
    yellow in its own view only, the other joints stay blue and the look-at markers orange."""
    s = sample.skeleton
    pose = sample.global_pos[0]
    head, hand = s.names[s.index("head")], s.names[s.index("left_hand")]
    views = [SkeletonViewer(s, pose, ghost=pose, controls=k == 0) for k in range(2)]
    for v in views:
        v.set_targets({hand: pose[s.index(hand)] + 0.1}, look_at={head: pose[s.index(head)] + [0, 0, 1]})
    a, b = (v._figure for v in views)
    spheres = a.joints.material
    assert all(m.material is spheres for f in (a, b) for m in (f.joints, f.targets, f.looks))
    assert a.bones.material is b.bones.material and a.rays.material is b.rays.material is b.triads.material
    assert views[0]._ghost_joints.mesh.material is views[1]._ghost_joints.mesh.material
    assert a.joints.geometry.attributes["index"] is b.joints.geometry.attributes["index"]  # the same triangles
    assert a._shared["color"] is not b._shared["color"]  # each view its own colours

    views[0].select(hand)
    V = len(a.unit)

    def joint_colours(f):
        return np.asarray(f._shared["color"].array)[f._rows["joints"]].reshape(s.n_joints, V, 3)

    k = s.index(hand)
    yellow, blue = _hex(SELECTED_COLOUR), joint_colours(b)[0, 0]
    assert np.allclose(joint_colours(a)[k], yellow, atol=1e-6)
    assert np.allclose(np.delete(joint_colours(a), k, axis=0), blue, atol=1e-6)
    assert np.allclose(joint_colours(b), blue, atol=1e-6) and not np.allclose(blue, yellow, atol=0.1)
    for f in (a, b):
        assert np.allclose(np.asarray(f._shared["color"].array)[f._rows["looks"]], _hex(LOOK_COLOUR), atol=1e-6)


def test_a_buffer_no_view_holds_any_more_is_closed(sample):
    """The triangle indices of a marker count are shared by the views that show as many markers and closed when
    none does (a view that changed its markers many times holds no buffer of the old counts)."""
    import ipywidgets

    ipywidgets.Widget.close_all()  # no view of an earlier test holds a buffer (shared models closed are made anew)
    s = sample.skeleton
    pose = sample.global_pos[0]
    v = SkeletonViewer(s, pose, controls=False)
    names = [s.names[s.index(r)] for r in ("left_hand", "right_hand", "head")]
    v.set_targets({names[0]: pose[0]})
    one = v._figure.targets.geometry.attributes["index"]
    for n in (2, 3, 2):
        v.set_targets({m: pose[0] for m in names[:n]})
    assert one.comm is None  # closed: no view shows one target
    two = v._figure.targets.geometry.attributes["index"]
    w = SkeletonViewer(s, pose, controls=False)
    w.set_targets({m: pose[0] for m in names[:2]})
    assert w._figure.targets.geometry.attributes["index"] is two
    v.set_targets({})
    assert two.comm is not None  # the other view still shows two targets

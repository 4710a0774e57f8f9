"""The widgets' Python side (the browser side is tests/viz/test_browser.py)."""

import numpy as np
import pytest

from posekit.data.cases import build_cases
from posekit.ik import effector_set
from posekit.ik.registry import make_solver
from posekit.viz import SkeletonViewer, SolverPanel


def test_viewer_updates_buffers_not_scene(sample):
    v = SkeletonViewer(sample.skeleton, sample.global_pos[0])
    children = v.scene.children
    f = v._figure
    attr, normals, colours = (f._shared[k] for k in ("position", "normal", "color"))
    parts = [f.bones, f.joints, f.targets, f.looks, f.rays, f.triads]
    assert all(m.geometry.attributes["position"] is attr for m in parts)  # one array for the whole figure
    v.set_pose(sample.global_pos[50])
    assert v.scene.children is children and all(m.geometry.attributes["position"] is attr for m in parts)
    assert f._shared["normal"] is normals and f._shared["color"] is colours  # a pose sends positions only
    # each bone is a ring of vertices round the parent and one round the child, at the bone's radius
    b = f._tubes
    rings = f.part("bones").reshape(-1, 2, b.sides, 3)
    pos = sample.global_pos[50]
    np.testing.assert_allclose(rings[:, 1].mean(1), pos[b.pairs[:, 1]], atol=1e-5)
    np.testing.assert_allclose(rings[:, 0].mean(1), pos[b.pairs[:, 0]], atol=1e-5)
    np.testing.assert_allclose(np.linalg.norm(rings[:, 1] - pos[b.pairs[:, 1]][:, None], axis=-1), b.radius, atol=1e-5)
    axis = pos[b.pairs[:, 1]] - pos[b.pairs[:, 0]]
    radial = rings[:, 1] - pos[b.pairs[:, 1]][:, None]
    assert np.abs(np.einsum("bsk,bk->bs", radial, axis)).max() < 1e-5  # rings square to the bone
    assert f.bones.material.flatShading  # the bones' normals are made on the GPU, from the positions
    joints, mesh = f.part("joints").copy(), f.joints
    f.layout(2, 1, 0)  # room for new markers: new arrays, the same meshes, the skeleton where it was
    assert f.joints is mesh and f._shared["position"] is not attr and np.array_equal(f.part("joints"), joints)


def _drawn_meshes(obj):
    """Every mesh or line object under ``obj`` whose object and material are both visible (what three.js draws)."""
    import pythreejs as three

    out = []
    if getattr(obj, "visible", True) is False:
        return out
    if isinstance(obj, (three.Mesh, three.LineSegments)) and obj.material.visible:
        out.append(obj)
    for child in getattr(obj, "children", ()):
        out += _drawn_meshes(child)
    return out


def test_a_view_needs_three_shader_programs_and_never_draws_the_drag_sphere(sample):
    """A software-rendered browser compiles each shader program once per view and draws every visible mesh in every
    frame: the view's meshes and lines use three programs (flat-shaded bones, lit vertex-coloured spheres,
    vertex-coloured lines) whatever is shown, and the sphere the drag pickers hit is never drawn."""
    from posekit.viz.viewer import LOOK_COLOUR, TARGET_COLOUR

    s = sample.skeleton
    v = SkeletonViewer(s, sample.global_pos[0], ghost=sample.global_pos[10])
    pose = sample.global_pos[0]
    head, hand = s.names[s.index("head")], s.names[s.index("left_hand")]
    v.set_targets({hand: pose[s.index(hand)] + 0.1}, look_at={head: pose[s.index(head)] + [0, 0, 1]},
                  rotations={hand: np.eye(3)})
    drawn = _drawn_meshes(v.scene)
    programs = {(type(m.material).__name__, m.material.vertexColors, getattr(m.material, "flatShading", False))
                for m in drawn}
    assert programs == {("MeshPhongMaterial", "VertexColors", True), ("MeshLambertMaterial", "VertexColors", False),
                        ("LineBasicMaterial", "VertexColors", False)}, programs
    f = v._figure
    assert {f.bones, f.joints, f.targets, f.looks, f.rays, f.triads} <= set(drawn)
    sphere = v._drag_sphere
    assert sphere.visible and not sphere.material.visible and sphere not in drawn  # hit by rays, never drawn
    colours = np.asarray(f._shared["color"].array)
    hexrgb = lambda c: np.array([int(c[k:k + 2], 16) / 255 for k in (1, 3, 5)])
    assert np.allclose(colours[f._rows["targets"]], hexrgb(TARGET_COLOUR), atol=1e-6)
    assert np.allclose(colours[f._rows["looks"]], hexrgb(LOOK_COLOUR), atol=1e-6)
    assert np.allclose(colours[f._rows["rays"]], hexrgb(LOOK_COLOUR), atol=1e-6)


def test_selected_joint_is_drawn_larger_and_yellow_in_the_joints_mesh(sample):
    s = sample.skeleton
    v = SkeletonViewer(s, sample.global_pos[0])
    j = s.index("left_hand")
    v.select(j)
    J = v._figure
    V = len(J.unit)
    joint_colours = lambda: np.asarray(J._shared["color"].array)[J._rows["joints"]].reshape(s.n_joints, V, 3)[:, 0]
    colours = joint_colours()
    assert np.allclose(colours[j], [0xf1 / 255, 0xc4 / 255, 0x0f / 255]) and np.allclose(colours[0], colours[1])
    verts = J.part("joints").reshape(s.n_joints, V, 3)
    radius = np.linalg.norm(verts - sample.global_pos[0][:, None], axis=-1)
    np.testing.assert_allclose(radius[j], J.joint_radius * J.HIGHLIGHT_SCALE, rtol=1e-5)
    np.testing.assert_allclose(np.delete(radius, j, axis=0), J.joint_radius, rtol=1e-5)
    v.set_pose(sample.global_pos[40])  # the highlight follows the joint in the same array
    verts = J.part("joints").reshape(s.n_joints, V, 3)
    np.testing.assert_allclose(np.linalg.norm(verts[j] - sample.global_pos[40][j], axis=-1),
                               J.joint_radius * J.HIGHLIGHT_SCALE, rtol=1e-5)
    v.select(None)
    assert J.highlighted is None and np.allclose(joint_colours()[j], colours[0])


def test_the_selected_joints_colour_reaches_the_browser_on_first_display_and_after_a_new_marker(sample):
    """Issue 44: the first selection after the view's arrays were made (a fresh view, or a new marker) sends the
    colour array with the joint in yellow (the kernel's copy held yellow while the browser kept blue: the array
    sent had been changed in place, so the new one looked unchanged)."""
    s = sample.skeleton
    v = SkeletonViewer(s, sample.global_pos[0])
    f = v._figure
    yellow = np.array([0xF1, 0xC4, 0x0F]) / 255

    def sends_yellow(joint):
        sent = []
        f._shared["color"].observe(lambda ch: sent.append(np.asarray(ch["new"])), names="array")
        v.select(joint)
        rows = f._rows["joints"]
        V = len(f.unit)
        k = s.index(joint)
        return bool(sent) and np.allclose(sent[-1][rows][k * V:(k + 1) * V], yellow, atol=1e-6)

    assert sends_yellow("left_wrist")
    v.move_target("head", sample.global_pos[0][s.index("head")] + 0.1)  # a new marker: new arrays
    assert sends_yellow("right_knee")


def test_bones_are_coloured_by_side(sample):
    s = sample.skeleton
    v = SkeletonViewer(s)
    f = v._figure
    colours = np.asarray(f._shared["color"].array)[f._rows["bones"]].reshape(len(f._tubes.pairs), -1, 3)[:, 0]
    side = s.sides()[f._tubes.pairs[:, 1]]
    left, right, centre = (colours[side == k] for k in (1, -1, 0))
    assert len(left) and len(right) and len(centre)
    assert np.ptp(left, axis=0).max() == 0 and np.ptp(right, axis=0).max() == 0
    assert left[0, 2] > left[0, 0] and right[0, 0] > right[0, 2]  # left blue, right red
    assert list(s.sides()[[s.index("left_hip"), s.index("right_hip"), s.index("chest")]]) == [1, -1, 0]


def _in_view(v, pos):
    """Every joint inside the camera's field of view (pinhole model of the viewer's camera)."""
    cam = np.asarray(v.camera.position, float)
    forward = -cam / np.linalg.norm(cam)  # the camera looks at the orbit pivot, the origin
    right = np.cross(forward, [0.0, 1.0, 0.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    rel = pos - v._offset - cam
    depth = rel @ forward
    tan_v = np.tan(np.radians(v.FOV) / 2)
    return bool(np.all(depth > 0) and np.all(np.abs(rel @ up) / depth < tan_v)
                and np.all(np.abs(rel @ right) / depth < tan_v * v.aspect))


def test_camera_keeps_the_pose_framed(sample):
    s = sample.skeleton
    v = SkeletonViewer(s, sample.global_pos[0], width=300, height=330)
    assert _in_view(v, sample.global_pos[0])
    far = sample.global_pos[0] + np.array([3.0, 0.0, -4.0])
    assert not _in_view(v, far)
    v.set_pose(far)  # a pose that walked off: the view follows it
    assert _in_view(v, far)
    # playback: framed on the whole clip, every frame in view without moving the camera again
    frames = sample.global_pos[sample.clip_frames("walk")]
    w = SkeletonViewer(s, frames[0], width=300, height=330)
    w.player(frames)
    cam = list(w.camera.position)
    assert all(_in_view(w, f) for f in frames[::10])
    w.set_pose(frames[-1])
    assert list(w.camera.position) == cam


def test_drag_moves_the_target_across_the_camera_facing_plane(sample):
    from posekit.viz.drag import drag_point

    np.testing.assert_allclose(drag_point([0, 0, 5], [0, 1, 4], [0, 0, 0], [0, 0, 1]), [0, 5, 0])
    assert drag_point([0, 0, 5], [1, 0, 5], [0, 0, 0], [0, 0, 1]) is None  # parallel to the plane
    assert drag_point([0, 0, 5], [0, 0, 6], [0, 0, 0], [0, 0, 1]) is None  # behind the camera
    s = sample.skeleton
    v = SkeletonViewer(s, sample.global_pos[0])
    seen = []
    v.on_target_change(lambda n, p: seen.append((n, p)))
    hand = sample.global_pos[0][s.index("left_wrist")]
    v.drag_mode.value = True
    assert v.orbit.enabled is False
    v.grab(hand + 0.005)  # pressed on the joint
    assert v.dragging == "left_wrist" and v.selected == "left_wrist"
    cam = np.asarray(v.camera.position) + v._offset
    # the browser reports a point on the mouse ray (here: half-way to a point 10 cm right of the hand,
    # seen from the camera); the target goes where the ray meets the plane through the hand
    goal = hand + 0.1 * np.cross(cam - hand, [0, 1, 0]) / np.linalg.norm(np.cross(cam - hand, [0, 1, 0]))
    v.drag_to(cam + 0.5 * (goal - cam))
    assert seen and seen[-1][0] == "left_wrist"
    np.testing.assert_allclose(v.targets["left_wrist"], goal, atol=1e-9)
    v._on_release({"new": [0, 0, 0]})
    np.testing.assert_allclose(v.sliders[0].value, goal[0], atol=v.SLIDER_STEP)  # shown once the mouse is up
    n = len(seen)
    v.drag_to(cam + 0.5 * (hand - cam))
    assert len(seen) == n  # released: moving the mouse no longer drags
    # pressed on the target marker (not the joint): the same target is grabbed again
    v.grab(goal + 0.01)
    assert v.dragging == "left_wrist"
    v.drag_mode.value = False
    assert v.orbit.enabled is True and v.dragging is None


def test_a_drag_keeps_the_camera_until_the_mouse_is_up_and_reset_view_frames_again(sample):
    """Issue 44: dragging a target out of the framed region used to step the camera back mid-drag, so each pixel
    moved the target further (a 120 px drag lifted a hand 1.94 m): the camera now waits for the release. *reset view*
    frames the pose from the front again, looking at it, after any orbit."""
    from posekit.viz.drag import drag_point

    s = sample.skeleton
    v = SkeletonViewer(s, sample.global_pos[0])
    hand = sample.global_pos[0][s.index("left_wrist")]
    v.drag_mode.value = True
    v.grab(hand)
    cam0 = list(v.camera.position)
    camera = np.asarray(cam0, float) + v._offset
    for k in range(1, 6):  # the mouse ray through points ever higher above the hand: the target leaves the frame
        through = camera + 0.5 * (hand + [0.0, 0.4 * k, 0.0] - camera)
        v.drag_to(through)
        assert list(v.camera.position) == cam0, f"the camera moved during the drag, at step {k}"
        # where the ray from the camera of the grab meets the drag plane: the same scale all along
        np.testing.assert_allclose(v.targets["left_wrist"], drag_point(camera, through, *v._drag_plane), atol=1e-9)
    assert v.targets["left_wrist"][1] > hand[1] + 1.5
    v._on_release({"new": [0, 0, 0]})
    assert np.linalg.norm(v.camera.position) > np.linalg.norm(cam0)  # released: the view takes the target in
    v.camera.position = [4.0, 0.5, -1.0]  # the user orbited behind the character
    v.reset_button.click()
    pos = np.asarray(v.camera.position)
    np.testing.assert_allclose(pos / np.linalg.norm(pos), v.VIEW_DIRECTION, atol=1e-9)
    # three.js' lookAt: the camera's -Z axis points at the pivot (the origin of the scene frame)
    x, y, z, w = v.camera.quaternion
    forward = -np.array([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)])
    np.testing.assert_allclose(forward, -pos / np.linalg.norm(pos), atol=1e-9)


def test_target_sliders_are_fine_and_centred_on_the_joint(sample):
    s = sample.skeleton
    v = SkeletonViewer(s, sample.global_pos[0])
    v.select("right_ankle")
    ankle = sample.global_pos[0][s.index("right_ankle")]
    for sl, c in zip(v.sliders, ankle):
        assert sl.step == 0.001 and sl.min <= c - 0.49 and sl.max >= c + 0.49 and sl.max - sl.min < 1.01
    # a target moved far away from code: the range follows it
    v.move_target("right_ankle", ankle + [2.0, 0.0, 0.0])
    assert v.sliders[0].min <= ankle[0] + 2.0 <= v.sliders[0].max
    # stored under the joint's name whatever the caller used (a role here)
    v.move_target("left_hand", [0.1, 1.0, 0.3])
    assert "left_wrist" in v.targets and "left_hand" not in v.targets


def test_viewer_selection_sliders_and_callbacks(sample):
    s = sample.skeleton
    v = SkeletonViewer(s, sample.global_pos[0])
    seen = []
    v.on_target_change(lambda name, p: seen.append((name, p)))
    v.select("left_hand")
    assert v.selected == "left_wrist" and "left_wrist" in v.status.value
    v.sliders[1].value = v.sliders[1].value + 0.2
    assert seen and seen[-1][0] == "left_wrist"
    np.testing.assert_allclose(v.targets["left_wrist"][1], sample.global_pos[0][s.index("left_wrist"), 1] + 0.2)
    # a double-click near a joint selects it; one that hits nothing (distance None) changes nothing
    v._on_pick({"new": [0.0, 0.0, 0.0]})
    assert v.selected == "left_wrist"
    v.picker.distance = 2.0
    v._on_pick({"new": list(sample.global_pos[0][s.index("head")] - v._offset + 0.01)})
    assert v.selected == "head"


def test_a_second_double_click_on_the_same_pixel_selects_again(sample):
    """Issue 44: double-click a joint, choose another in the list, double-click the same pixel again: the first
    joint is selected again (the browser reports a point only when it changes, so the kernel resets it)."""
    s = sample.skeleton
    v = SkeletonViewer(s, sample.global_pos[0])
    v.picker.distance = 2.0
    at = list(sample.global_pos[0][s.index("head")] - v._offset + 0.01)
    v.picker.point = at  # what the browser sends
    assert v.selected == "head"
    v.joint_select.value = "left_knee"
    v.picker.point = at
    assert v.selected == "head"


def test_selection_alone_creates_no_target_and_idle_sliders_show_nothing(sample):
    s = sample.skeleton
    v = SkeletonViewer(s, sample.global_pos[0])
    # nothing selected: the dropdown says so and the sliders are off, with no number shown
    assert v.joint_select.label == "(none)" and v.selected is None
    assert all(sl.disabled and not sl.readout for sl in v.sliders)
    seen = []
    v.on_target_change(lambda name, p: seen.append(name))
    v.select("left_elbow")
    assert all(not sl.disabled and sl.readout for sl in v.sliders)
    # the browser snaps each value to the slider's step grid and sends it back: not a move
    for sl in v.sliders:
        sl.value = sl.min + round((sl.value - sl.min) / sl.step) * sl.step
    assert not seen and v.targets == {} and "away" not in v.status.value
    v.sliders[0].value += 0.05
    joint = sample.global_pos[0][s.index("left_elbow")]
    assert seen == ["left_elbow"] and "cm away" in v.status.value
    assert abs(np.linalg.norm(v.targets["left_elbow"] - joint) - 0.05) < v.SLIDER_STEP
    v.joint_select.value = ""
    assert v.selected is None and all(sl.disabled for sl in v.sliders)


def test_viewer_refuses_bad_poses(sample):
    v = SkeletonViewer(sample.skeleton)
    with pytest.raises(ValueError, match=r"expected shape \(18, 3\)"):
        v.set_pose(np.zeros((17, 3)))
    with pytest.raises(ValueError, match="NaN"):
        v.set_ghost(np.full((18, 3), np.nan))
    with pytest.raises(ValueError, match="unknown joint"):
        v.set_targets({"tail": [0, 0, 0]})


def test_player_steps_through_frames(sample):
    v = SkeletonViewer(sample.skeleton)
    frames = sample.global_pos[sample.clip_frames("walk")]
    box = v.player(frames, 1 / 30)
    box.children[1].value = 10
    np.testing.assert_allclose(v.pose, frames[10])


def test_solver_panel_resolves_on_target_moves(sample):
    s = sample.skeleton
    cases = build_cases(sample, 3)
    panel = SolverPanel(s, {n: make_solver(n, s) for n in ("fabrik", "dls")}, cases.pose(0),
                        effector_set(s, "2", cases.target_pos[0]), truth=cases.target_pos[0])
    target = cases.target_pos[0][s.index("left_hand")] + np.array([0.05, 0.05, 0.0])
    panel.move_target("left_hand", target)
    for name in ("fabrik", "dls"):
        res = panel.results[name]
        assert res.converged, name
        np.testing.assert_allclose(panel.viewers[name].pose[s.index("left_hand")], target, atol=1e-3)
        assert panel.labels[name].value.startswith("<b>✓ reached</b><table"), panel.labels[name].value
    # a target out of every solver's reach is reported as not reached, each status on its own lines
    panel.move_target("left_hand", target + np.array([0.0, 5.0, 0.0]))
    for name in ("fabrik", "dls"):
        label = panel.labels[name].value
        assert not panel.results[name].converged and label.startswith("<b>✗ not reached</b><table"), label
        assert label.count("<tr>") == 3 and ">iterations<" in label and " ms<" in label


def test_a_panel_offers_only_joints_every_solver_takes_and_an_added_target_can_be_removed(sample):
    """Issue 44: lesson 03's panel gave any joint touched by a slider a new effector, which its network (trained for
    fixed joint sets) refused, and nothing but re-running the cell recovered. A panel now offers the joints of its
    effectors and those every solver accepts one more effector on (FABRIK: all; a fixed-set solver: none);
    a double-click on another joint says why it is not offered and selects nothing; *remove target* takes an added
    effector away. A viewer can offer a chosen few (lesson 02: the rig's handles)."""
    from posekit.ik import Effector, Pose, make_solver
    from posekit.viz import SolverPanel

    s, P = sample.skeleton, sample.global_pos[0]
    hands = ["left_wrist", "right_wrist"]
    fabrik = make_solver("fabrik", s)

    class HandsOnly:  # a learned solver made for one joint set (as lesson 03's network)
        kinds, needs_start = ("position",), True

        def solve(self, start, effectors):
            if sorted(s.names[s.index(e.joint)] for e in effectors) != sorted(hands):
                raise ValueError("no network for this joint set")
            return fabrik.solve(start, effectors)

    effectors = [Effector(j, P[s.index(j)]) for j in hands]
    free = SolverPanel(s, {"fabrik": fabrik, "again": make_solver("fabrik", s)}, Pose(P), effectors)
    assert len(free.viewers["fabrik"].joint_select.options) == len(free.viewers["fabrik"].body) + 1
    panel = SolverPanel(s, {"net": HandsOnly(), "fabrik": fabrik}, Pose(P), effectors)
    v = panel.viewers["net"]
    assert sorted(o[1] for o in v.joint_select.options) == ["", "left_wrist", "right_wrist"]
    with pytest.raises(ValueError, match="not offered"):
        v.select("left_elbow")
    v.picker.distance = 1.0
    v._on_pick({"new": list(P[s.index("left_elbow")] - v._offset)})
    assert v.selected is None and "left_elbow is not offered" in v.status.value
    v.drag_mode.value = True
    v.grab(P[s.index("left_knee")])
    assert v.dragging is None and set(panel.effectors) == set(hands)
    v._on_pick({"new": list(P[s.index("left_wrist")] - v._offset)})
    assert v.selected == "left_wrist"
    # in the free panel a slider adds an effector on the elbow; every view solves it, and it can be taken away
    f = free.viewers["fabrik"]
    f.select("left_elbow")
    f.sliders[1].value += 0.05
    assert "left_elbow" in free.effectors and not isinstance(free.results["again"], Exception)
    free.remove_button.click()
    assert set(free.effectors) == set(hands) and "left_elbow" not in f.targets
    rig = SkeletonViewer(s, P, selectable=["left_hand", "right_ankle"])  # roles or names
    assert sorted(o[1] for o in rig.joint_select.options) == ["", "left_wrist", "right_ankle"]


def test_effector_editor_edits_every_kind_and_re_solves():
    """Lesson 05's EffectorEditor: effectors of all three kinds added, turned, loosened and removed; every
    change re-solves each solver; a solver that refuses a kind gets only the kinds it honours."""
    from posekit.data import load_bandai_mini
    from posekit.ik import Pose
    from posekit.evaluation.effector_scores import rest_starts
    from posekit.evaluation.effector_cases import load_benchmark
    from posekit.rotations import geodesic_distance
    from posekit.viz import EffectorEditor

    m = load_bandai_mini()
    s = m.skeleton
    five = load_benchmark("5point", m)
    q, r = rest_starts(five, m)
    ed = EffectorEditor(s, {"ProtoRes": make_solver("protores", s), "FABRIK": make_solver("fabrik", s)},
                        Pose.from_rotations(s, q[0], r[0]), effectors=five.effectors(0), truth=five.global_pos[0])
    assert len(ed.effectors) == 5 and all(not isinstance(v, Exception) for v in ed.results.values())
    before = ed.results["ProtoRes"].pose.global_pos.copy()
    k = ed.add("Head", "rotation")
    assert ed.effectors[k].kind == "rotation" and ed.results["ProtoRes"].kinds[-1] == "rotation"
    assert len(ed.results["FABRIK"].kinds) == 5  # FABRIK gets the position effectors only
    ed.set_rotation(k, yaw=90)
    turned = ed.effectors[k].target
    assert np.degrees(geodesic_distance(turned, ed.rows[k]["base"])) == pytest.approx(90, abs=1e-6)
    look = ed.add("Hand_L", "look_at")
    assert ed.effectors[look].kind == "look_at" and np.isclose(np.linalg.norm(ed.effectors[look].axis), 1)
    ed.move_target(look, ed.effectors[look].target + [0.0, 0.5, 0.0])
    v = ed.viewers["ProtoRes"]  # the look-at target: an orange marker and a ray from the hand to it
    assert set(v.look_targets) == {"Hand_L"} and v._figure.looks.visible and v._figure.rays.visible
    ray = v._figure.part("rays")
    hand = ed.results["ProtoRes"].pose.global_pos[s.index("Hand_L")]
    assert np.allclose(ray[0], hand, atol=1e-5) and np.allclose(ray[1], ed.effectors[look].target, atol=1e-5)
    assert v._figure.counts == (5, 1, 1)  # five magenta position targets, one orange look-at, one rotation
    from posekit.viz.viewer import TRIAD_LENGTH

    tri = v._figure.part("triads")[:6].reshape(3, 2, 3)  # the head's triad's centre lines: (axis, start/tip, xyz)
    head = ed.results["ProtoRes"].pose.global_pos[s.index("Head")]
    assert np.allclose(tri[:, 0], head, atol=1e-5)
    assert np.allclose(tri[:, 1] - head, TRIAD_LENGTH * v.rotation_targets["Head"].T, atol=1e-5)  # columns: axes
    # issue 44: 20 cm axes, each drawn as five parallel lines 4 mm apart (WebGL lines are one pixel wide)
    strands = v._figure.part("triads").reshape(5, 3, 2, 3)
    lines = strands[:, :, 1] - strands[:, :, 0]
    assert TRIAD_LENGTH >= 0.2 and np.allclose(lines[1:], lines[:1], atol=1e-5)
    assert 0.003 < np.linalg.norm(strands[1, 0, 0] - strands[0, 0, 0]) < 0.006
    ed.set_tolerance(0, 1.0)
    assert ed.effectors[0].tolerance == pytest.approx(0.1)
    assert not np.allclose(ed.results["ProtoRes"].pose.global_pos, before)
    with pytest.raises(ValueError, match=r"\[0, 1\]"):
        ed.set_tolerance(0, 2.0)
    with pytest.raises(ValueError, match="not a rotation"):
        ed.set_rotation(0, yaw=10)
    with pytest.raises(ValueError, match="unknown effector kind"):
        ed.add("Head", "orientation")
    ed.remove(k)
    assert len(ed.effectors) == 6 and all(e.kind != "rotation" for e in ed.effectors)
    ed.first.move_target("Foot_L", five.global_pos[0, s.index("Foot_L")] + [0.3, 0.0, 0.0])  # a slider move
    foot = next(e for e in ed.effectors if e.joint == "Foot_L" and e.kind == "position")
    assert np.allclose(foot.target, five.global_pos[0, s.index("Foot_L")] + [0.3, 0.0, 0.0])
    ed.first.move_target("Toes_R", [0.0, 0.0, 0.0])  # a joint without an effector gets a position one
    assert ed.effectors[-1].joint == "Toes_R" and ed.effectors[-1].kind == "position"
    with pytest.raises(ValueError, match="already has a position effector"):
        ed.add("Hand_R", "position")
    with pytest.raises(ValueError, match="already has a look-at effector"):
        ed.add("Hand_L", "rotation")
    ed.add("UpperArm_R", "position", target=[40.0, 1.0, 0.0])
    assert not isinstance(ed.results["ProtoRes"], Exception), ed.results["ProtoRes"]
    assert "UpperArm_R" in ed.results["ProtoRes"].info["out_of_range"]


def test_dragging_an_orange_marker_moves_the_look_at_target():
    """A joint with a position and a look-at effector: pressing on its orange marker drags the point it looks
    at (the position target stays); pressing on the red one drags the position target."""
    from posekit.data import load_bandai_mini
    from posekit.ik import Pose
    from posekit.viz import EffectorEditor

    m = load_bandai_mini()
    s = m.skeleton
    start = Pose.from_rotations(s, m.local_rot[0], m.root_pos[0])
    ed = EffectorEditor(s, {"dls": make_solver("dls", s), "fabrik": make_solver("fabrik", s)}, start)
    head = start.global_pos[s.index("Head")]
    ed.add("Head", "position", target=head)
    ed.add("Head", "look_at")
    look0 = ed.rows[1]["target"].copy()
    v = ed.first
    v.grab(look0 + 0.01)
    assert v.dragging == "Head" and v.dragging_look
    cam = np.asarray(v.camera.position) + v._offset
    goal = look0 + np.array([0.3, 0.0, 0.0])
    goal = goal - ((goal - look0) @ (cam - look0)) / np.sum((cam - look0) ** 2) * (cam - look0)  # in the plane
    v.drag_to(cam + 0.5 * (goal - cam))
    np.testing.assert_allclose(ed.rows[1]["target"], goal, atol=1e-9)
    np.testing.assert_allclose(ed.rows[0]["target"], head)
    np.testing.assert_allclose(v.look_targets["Head"], goal, atol=1e-9)
    assert "dls" in ed.results and ed.results["dls"].kinds == ("position", "look_at")
    v._on_release({"new": [0, 0, 0]})
    v.grab(head + 0.005)
    assert v.dragging == "Head" and not v.dragging_look
    v.drag_to(cam + 0.5 * (head + [0.0, 0.05, 0.0] - cam))
    assert not np.allclose(ed.rows[0]["target"], head) and np.allclose(ed.rows[1]["target"], goal)


def test_a_lone_viewer_drags_its_orange_markers_joint_target(sample):
    """A lone viewer (lesson 00's, no session, nobody listening to look-at moves): a drag on an orange look-at
    marker moves the joint's position target (created at the drag's point), its look-at point stays, and the target
    listeners hear it, as before the views read their markers from a session; Escape puts it back (no target)."""
    s = sample.skeleton
    v = SkeletonViewer(s, sample.global_pos[0])
    head = sample.global_pos[0][s.index("head")]
    look0 = head + np.array([0.0, 0.0, 1.0])
    v.set_targets({}, look_at={"head": look0})
    seen = []
    v.on_target_change(lambda name, p: seen.append((name, p.copy())))
    v.grab(look0 + 0.01)
    assert v.dragging == "head" and not v.dragging_look
    cam = np.asarray(v.camera.position) + v._offset
    goal = look0 + np.array([0.3, 0.0, 0.0])
    goal = goal - ((goal - look0) @ (cam - look0)) / np.sum((cam - look0) ** 2) * (cam - look0)  # in the plane
    v.drag_to(cam + 0.5 * (goal - cam))
    np.testing.assert_allclose(v.targets["head"], goal, atol=1e-9)
    np.testing.assert_allclose(v.look_targets["head"], look0)
    assert seen and seen[-1][0] == "head" and np.allclose(seen[-1][1], goal, atol=1e-9)
    v.cancel_drag()  # Escape: the target the drag made goes again, the look-at point stays
    assert v.dragging is None and "head" not in v.targets
    np.testing.assert_allclose(v.look_targets["head"], look0)


def test_values_sent_back_unchanged_move_nothing_and_a_move_changes_one_axis(sample):
    """Issue 27: selecting joints one after another never moves a target: the browser sending back a slider's own
    value (or its snap to the step grid) is zero steps. A move changes its own axis only, and a slider pushed to an
    end re-centres on its value."""
    s = sample.skeleton
    v = SkeletonViewer(s, sample.global_pos[0])
    seen = []
    v.on_target_change(lambda name, p: seen.append((name, p.copy())))
    v.select("left_wrist")
    v.sliders[1].value += 0.3  # a user move: a target above the wrist
    wrist = v.targets["left_wrist"].copy()
    assert len(seen) == 1
    for other in ("left_knee", "chest", "left_wrist"):
        old = list(v.sliders)
        v.select(other)
        assert not set(old) & set(v.sliders)  # new slider models for every selection
        for sl in old + v.sliders:  # the browser sends back what each model holds, snapped to its grid
            sl.value = float(sl.min + round((sl.value - sl.min) / sl.step) * sl.step)
    assert len(seen) == 1 and set(v.targets) == {"left_wrist"}, seen
    np.testing.assert_array_equal(v.targets["left_wrist"], wrist)
    assert [sl.value for sl in v.sliders] == pytest.approx(wrist, abs=v.SLIDER_STEP / 2)
    z = v.sliders[2]
    z.value += 0.1
    np.testing.assert_allclose(v.targets["left_wrist"], wrist + [0.0, 0.0, 0.1])
    assert v.sliders[2] is z  # its own move does not replace the slider (the browser keeps its focus)
    top = v.sliders[1].max
    v.sliders[1].value = top  # pushed to the top: new sliders, centred on the new value
    assert v.targets["left_wrist"][1] == pytest.approx(top, abs=v.SLIDER_STEP) and v.sliders[1].max > top + 0.4


def test_a_press_on_the_previous_selections_slider_moves_the_new_joint_one_step(sample):
    """Issue 44: select one joint, then another, and press before the browser shows the new sliders: the press
    arrives on the old slider model, with the old joint's value plus one step. It moves the joint selected now by
    one step on that axis, never to the old joint's value, and the sliders are made anew to show it."""
    s = sample.skeleton
    v = SkeletonViewer(s, sample.global_pos[0])
    seen = []
    v.on_target_change(lambda name, p: seen.append((name, p.copy())))
    v.select("left_knee")
    knee_sliders = list(v.sliders)
    knee_y = knee_sliders[1].value  # what the browser shows until the new sliders arrive
    v.select("right_wrist")
    wrist_sliders = list(v.sliders)
    hand = sample.global_pos[0][s.index("right_wrist")]
    for k in range(1, 6):  # five presses on the knee's y slider, still on screen
        knee_sliders[1].value = knee_y + k * v.SLIDER_STEP
        assert seen[-1][0] == "right_wrist"
        np.testing.assert_allclose(v.targets["right_wrist"], hand + [0.0, k * v.SLIDER_STEP, 0.0], atol=1e-12)
    assert "left_knee" not in v.targets
    assert v.sliders[1] is not wrist_sliders[1] and v.sliders[1].value == pytest.approx(hand[1] + 0.005, abs=6e-4)
    wrist_sliders[1].value = wrist_sliders[1].value + v.SLIDER_STEP  # and one on the first wrist sliders
    np.testing.assert_allclose(v.targets["right_wrist"], hand + [0.0, 0.006, 0.0], atol=1e-12)
    assert len(seen) == 6


def test_quick_moves_back_and_forth_after_a_selection_all_move(sample):
    """Right, left, right by one step within a second of selecting a joint (a student tapping the arrow keys, or
    ``posekit bench studio``): every press moves the target by one step."""
    s = sample.skeleton
    v = SkeletonViewer(s, sample.global_pos[0])
    seen = []
    v.on_target_change(lambda name, p: seen.append(round(float(p[0]), 6)))
    v.select("head")
    v.select("left_wrist")
    x0, j0 = v.sliders[0].value, sample.global_pos[0][s.index("left_wrist"), 0]
    for x in (x0 + 0.001, x0, x0 + 0.001, x0):
        v.sliders[0].value = x
    assert seen == [round(j0 + d, 6) for d in (0.001, 0.0, 0.001, 0.0)]
    assert v.targets["left_wrist"][0] == pytest.approx(j0)


def test_helper_joints_are_not_selectable_and_markers_stay_pickable():
    from posekit.data import load_bandai_mini
    from posekit.viz.meshes import PICK_BOUND

    m = load_bandai_mini()
    v = SkeletonViewer(m.skeleton, m.global_pos[0])
    assert "joint_Root" not in [o[0] for o in v.joint_select.options]
    with pytest.raises(ValueError, match="helper joint"):
        v.select("joint_Root")
    assert v._nearest_joint(m.global_pos[0][0]) != "joint_Root"  # a double-click at the origin point
    # every pickable mesh's buffer spans the far corners, so the browser's bounding sphere holds every pose
    pos = v._figure.part("corners")
    assert np.allclose(pos, [[-PICK_BOUND] * 3, [PICK_BOUND] * 3])
    v.set_pose(m.global_pos[0] + [5.0, 0.0, 0.0])
    assert np.allclose(v._figure.part("corners"), pos)


def test_a_target_outside_the_view_brings_the_camera_along(sample):
    v = SkeletonViewer(sample.skeleton, sample.global_pos[0])
    r0 = v._radius
    far = sample.global_pos[0][sample.skeleton.index("left_wrist")] + [0.0, 2.5, 0.0]
    v.set_targets({"left_wrist": far})
    assert np.linalg.norm(far - v._offset) <= 1.05 * v._radius and v._radius > r0


def test_a_solver_that_ignores_a_kind_says_so_and_names_the_worst_joint():
    from posekit.data import load_bandai_mini
    from posekit.ik import Effector, Pose

    m = load_bandai_mini()
    s = m.skeleton
    start = Pose.from_rotations(s, m.local_rot[0], m.root_pos[0])
    P = start.global_pos
    effs = [Effector("Hand_L", P[s.index("Hand_L")] + [0.0, 0.1, 0.0]),
            Effector("Head", P[s.index("Head")] + [0.0, 0.0, 1.0], "look_at", axis=[0.0, 0.0, 1.0])]
    panel = SolverPanel(s, {n: make_solver(n, s) for n in ("fabrik", "dls")}, start, effs)
    fabrik, dls = panel.labels["fabrik"].value, panel.labels["dls"].value
    assert "look-at ignored" in fabrik and "✓" not in fabrik and "(Hand_L)" in fabrik
    assert "look-at not measured" in fabrik, fabrik  # issue 57: the error figure says what it leaves out
    assert "ignored" not in dls and "°" in dls
    assert panel.results["fabrik"].kinds == ("position",)  # FABRIK was given the position effector only
    assert set(panel.viewers["dls"].look_targets) == {"Head"} and set(panel.viewers["dls"].targets) == {"Hand_L"}


def test_antialiasing_is_on_unless_posekit_antialias_is_0(sample, monkeypatch):
    """Browsers without a GPU draw smoother views at a price: POSEKIT_ANTIALIAS=0 (make studio STUDIO_ANTIALIAS=0)
    turns multisampling off for every viewer; an explicit argument wins over the environment."""
    import subprocess
    from pathlib import Path

    monkeypatch.delenv("POSEKIT_ANTIALIAS", raising=False)
    assert SkeletonViewer(sample.skeleton, controls=False).renderer._antialias is True
    monkeypatch.setenv("POSEKIT_ANTIALIAS", "0")
    assert SkeletonViewer(sample.skeleton, controls=False).renderer._antialias is False
    assert SkeletonViewer(sample.skeleton, controls=False, antialias=True).renderer._antialias is True
    monkeypatch.setenv("POSEKIT_ANTIALIAS", "1")
    assert SkeletonViewer(sample.skeleton, controls=False).renderer._antialias is True
    root = Path(__file__).resolve().parents[2]
    dry = subprocess.run(["make", "-n", "-C", str(root), "studio", "STUDIO_ANTIALIAS=0"], capture_output=True, text=True)
    assert dry.returncode == 0 and 'POSEKIT_ANTIALIAS="0"' in dry.stdout, dry.stdout + dry.stderr
    dry = subprocess.run(["make", "-n", "-C", str(root), "studio"], capture_output=True, text=True)
    assert "POSEKIT_ANTIALIAS" not in dry.stdout


def test_make_studio_keeps_studio_pool_kernels_preheated():
    """make studio: Voila keeps STUDIO_POOL kernels with the page already run for the next visitors (default
    posekit.viz.studio_app.STUDIO_POOL, issue 65: three arriving at once); STUDIO_POOL=N keeps N, for a class."""
    import subprocess
    from pathlib import Path

    from posekit.viz.studio_app import STUDIO_POOL

    root = Path(__file__).resolve().parents[2]
    dry = subprocess.run(["make", "-n", "-C", str(root), "studio"], capture_output=True, text=True)
    assert dry.returncode == 0 and f"--preheat_kernel=True --pool_size={STUDIO_POOL} " in dry.stdout, \
        dry.stdout + dry.stderr
    dry = subprocess.run(["make", "-n", "-C", str(root), "studio", "STUDIO_POOL=30"], capture_output=True, text=True)
    assert "--preheat_kernel=True --pool_size=30 " in dry.stdout, dry.stdout


# ---- the architecture diagram (lesson 05) ----------------------------------------------------------------------


def _texts(ax):
    return " ".join(t.get_text() for t in ax.texts)


def test_the_protores_diagram_states_the_sizes_of_the_network_it_is_given():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from posekit.models.protores.blocks import ProtoResConfig
    from posekit.viz.diagram import draw_protores

    ax = draw_protores(ProtoResConfig(21, width=256, blocks=3, layers=3), n_effectors=5)
    text = _texts(ax)
    assert "5 effector tokens" in text and "71 numbers each" in text and "3 layers of 256" in text
    assert "21 x 3 positions" in text and "21 x 6 rotations" in text and "width 256, 21 body joints" in text
    assert sum("block\n" in t.get_text() for t in ax.texts) == 3  # one box per encoder block
    plt.close("all")
    other = draw_protores(ProtoResConfig(17, width=64, blocks=2, layers=4, embed=16), n_effectors=3)
    text = _texts(other)
    assert "3 effector tokens" in text and "39 numbers each" in text and "4 layers of 64" in text
    assert "17 x 3 positions" in text and sum("block\n" in t.get_text() for t in other.texts) == 2
    plt.close("all")


def test_the_protores_diagram_refuses_another_architecture_and_an_empty_request():
    from posekit.models.protores.blocks import ProtoResConfig
    from posekit.viz.diagram import draw_protores

    with pytest.raises(ValueError, match="expected a config with arch 'protores', got 'transformer'"):
        draw_protores(ProtoResConfig(21, arch="transformer"))
    with pytest.raises(ValueError, match="at least 1 effector, got 0"):
        draw_protores(ProtoResConfig(21), n_effectors=0)


def test_a_release_the_page_reports_ends_the_drag_and_the_view_takes_the_target_in(sample):
    """Issue 57: the page's watcher (posekit.viz.page_watch) reports a release anywhere, outside the view or the
    window; the kernel lets go at once (hovering then moves nothing) and the camera takes the far target in. It knows
    whether *drag in 3D* is on and whether a drag is held (the switch carries DRAG_HELD_CLASS meanwhile)."""
    from posekit.viz.drag import DRAG_HELD_CLASS

    s = sample.skeleton
    v = SkeletonViewer(s, sample.global_pos[0])
    moves = []
    v.on_target_change(lambda name, p: moves.append(p))
    hand = sample.global_pos[0][s.index("left_wrist")]
    assert v.page_watch.scope in v.renderer._dom_classes and v.page_watch.scope in v.controls._dom_classes
    v.drag_mode.value = True
    assert v.page_watch.armed and not v.page_watch.holding
    v.grab(hand)
    assert v.page_watch.holding and DRAG_HELD_CLASS in v.drag_mode._dom_classes
    cam0 = list(v.camera.position)
    camera = np.asarray(cam0, float) + v._offset
    v.drag_to(camera + 0.5 * (hand + [0.0, 2.0, 0.0] - camera))  # far up, out of the framed region
    v.page_watch._on_page_message(v.page_watch, {"event": "release", "why": "pointerup"}, [])
    assert v.dragging is None and not v.page_watch.holding and DRAG_HELD_CLASS not in v.drag_mode._dom_classes
    assert np.linalg.norm(v.camera.position) > np.linalg.norm(cam0)  # the view widened once let go
    n = len(moves)
    v.drag_to(camera + 0.5 * (hand - camera))  # hovering with no button down
    assert len(moves) == n
    v.page_watch._on_page_message(v.page_watch, {"event": "release", "why": "blur"}, [])  # again: nothing
    v.drag_mode.value = False
    assert not v.page_watch.armed

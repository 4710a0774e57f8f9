"""The posing studio's Python side (the Voila app in a browser: tests/viz/test_studio_browser.py): key frames
and in-betweens, BVH export of every kind of pose, setup files, undo/redo and bad input."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from posekit.data import load_bandai_mini
from posekit.data.cases import build_cases
from posekit.ik import Effector, effector_set, make_solver
from posekit.ik.keyframes import inbetween_effectors, interpolate_effectors, slerp, solve_sequence, write_poses_bvh
from posekit.io.bvh import BVHError, read_bvh
from posekit.rotations import geodesic_distance, quat_to_matrix, random_rotations


@pytest.fixture(scope="module")
def bandai():
    m = load_bandai_mini()
    return m, build_cases(m, 4, seed=0, start="same-clip")


@pytest.fixture(scope="module")
def studio(bandai, tmp_path_factory):
    from posekit.viz import PosingStudio

    m, cases = bandai
    s = m.skeleton
    return PosingStudio(s, cases.pose(0), ["fabrik", "protores"], effector_set(s, "5", cases.target_pos[0]),
                        export_dir=tmp_path_factory.mktemp("studio"))


def test_slerp_is_the_constant_speed_shorter_arc():
    q = random_rotations((2,), 3)
    R0, R1 = quat_to_matrix(q[0]), quat_to_matrix(q[1])
    total = geodesic_distance(R0, R1)
    for s in (0.0, 0.3, 0.5, 1.0):
        Rs = quat_to_matrix(slerp(q[0], q[1], s))
        assert np.isclose(geodesic_distance(R0, Rs), s * total, atol=1e-7)
        np.testing.assert_allclose(quat_to_matrix(slerp(q[0], -q[1], s)), Rs, atol=1e-9)  # -q is the same rotation


def test_inbetweens_interpolate_every_kind(bandai):
    m, cases = bandai
    s = m.skeleton
    q = random_rotations((2,), 5)
    a = [Effector("Hand_L", [0.0, 1.0, 0.0]), Effector("Chest", q[0], "rotation", tolerance=0.01),
         Effector("Head", [0.0, 1.6, 1.0], "look_at", axis=[0, 0, 1])]
    b = [Effector("Head", [1.0, 1.6, 0.0], "look_at", axis=[1, 0, 0]), Effector("Hand_L", [0.4, 1.2, 0.0]),
         Effector("Chest", q[1], "rotation", tolerance=0.03)]  # the same effectors in another order
    mid = interpolate_effectors(s, a, b, 0.5)
    assert [e.kind for e in mid] == ["position", "rotation", "look_at"]
    np.testing.assert_allclose(mid[0].target, [0.2, 1.1, 0.0])
    np.testing.assert_allclose(mid[1].tolerance, 0.02)
    R = mid[1].target
    assert np.isclose(geodesic_distance(R, quat_to_matrix(q[0])), geodesic_distance(R, quat_to_matrix(q[1])))
    np.testing.assert_allclose(mid[2].axis, np.array([1, 0, 1]) / np.sqrt(2), atol=1e-12)
    smooth = interpolate_effectors(s, a, b, 0.25, ease="smooth")
    np.testing.assert_allclose(smooth[0].target[0], 0.4 * (3 * 0.25 ** 2 - 2 * 0.25 ** 3))
    frames = inbetween_effectors(s, [a, b, a], 4)
    assert len(frames) == 11 and frames[0] is not frames[5] and frames[5] == b and frames[10] == a
    with pytest.raises(ValueError, match=r"different effectors \(only in the first: Head look-at"):
        interpolate_effectors(s, a, a[:2], 0.5)
    with pytest.raises(ValueError, match="at least two keys"):
        inbetween_effectors(s, [a], 3)
    with pytest.raises(ValueError, match="unknown ease"):
        interpolate_effectors(s, a, b, 0.5, ease="bouncy")


@pytest.mark.parametrize("name", ["fabrik", "dls", "protores", "neural"])
def test_animated_bvh_reads_back_to_the_solved_poses(bandai, tmp_path, name):
    """Positions-only solvers (FABRIK, neural) get rotations and, where needed, position channels; the file
    reads back through posekit's reader to every frame's pose."""
    m, cases = bandai
    s = m.skeleton
    keys = [effector_set(s, "5", cases.target_pos[k]) for k in range(3)]
    results = solve_sequence(make_solver(name, s), cases.pose(0), inbetween_effectors(s, keys, 5, "smooth"))
    assert len(results) == 13
    path = tmp_path / f"{name}.bvh"
    write_poses_bvh(path, s, [r.pose for r in results], cases.pose(0), frame_time=1 / 24)
    back = read_bvh(path)
    assert back.n_frames == 13 and np.isclose(back.frame_time, 1 / 24) and list(back.skeleton.names) == list(s.names)
    np.testing.assert_allclose(back.global_positions(), np.stack([r.pose.global_pos for r in results]), atol=1e-6)
    text = path.read_text()
    assert text.startswith("HIERARCHY\nROOT joint_Root") and "MOTION\nFrames: 13\nFrame Time: 0.041666667" in text
    # the root has 6 channels; a rotation solver needs no position channel anywhere else
    moved = [ch for ch in back.channels[1:] if "Xposition" in ch]
    assert back.channels[0][:3] == ("Xposition", "Yposition", "Zposition")
    if name in ("dls", "protores"):
        assert not moved


def test_studio_undo_redo_coalesces_drags(studio):
    ed = studio.editor
    n0, steps0 = len(ed.rows), len(studio.history)
    t0 = ed.rows[0]["target"].copy()
    for k in range(5):  # one drag: five moves in quick succession are one step
        ed.move_target(0, t0 + [0.02 * (k + 1), 0.0, 0.0])
    assert len(studio.history) == steps0 + 1
    ed.add("Chest", "rotation")
    ed.set_rotation(len(ed.rows) - 1, yaw=20.0)
    assert len(studio.history) == steps0 + 3 and len(ed.rows) == n0 + 1
    studio.undo()
    np.testing.assert_allclose(ed.rows[-1]["euler"], 0.0)
    studio.undo()
    assert len(ed.rows) == n0
    studio.undo()
    np.testing.assert_allclose(ed.rows[0]["target"], t0)
    for name in studio.solvers:  # undo re-solved every view
        assert not isinstance(studio.editor.results[name], Exception)
    assert studio.undo_button.disabled is (studio.position == 0)
    studio.redo(); studio.redo(); studio.redo()
    assert len(ed.rows) == n0 + 1 and ed.rows[-1]["euler"][0] == 20.0 and studio.redo_button.disabled
    studio.undo(); studio.undo(); studio.undo()  # leave it as it was for the next tests
    # a new change after undo drops the redo steps
    ed.move_target(1, ed.rows[1]["target"] + [0.0, 0.01, 0.0])
    assert studio.position == len(studio.history) - 1


def test_a_slow_drag_in_a_view_is_one_undo_step(studio):
    """A drag in 3D whose moves reach the kernel seconds apart (a loaded machine solving every view between them) is
    still one step: undo brings back the target and the view's camera as before the press. Timing alone split it
    (moves more than a second apart were steps of their own), and undo went back to the middle of the drag."""
    session, viewer = studio.session, next(iter(studio.editor.viewers.values()))
    ticks = iter(np.arange(1000) * 3.0)  # every reading of the clock three seconds after the last
    clock, session.clock = session.clock, lambda: float(next(ticks))
    try:
        steps0, row0 = len(studio.history), studio.editor.rows[0]
        joint, t0, camera0 = row0["joint"], row0["target"].copy(), studio._cameras()
        viewer.drag_mode.value = True
        viewer.grab(t0)
        assert viewer.dragging == joint
        eye = np.asarray(viewer.camera.position, float) + viewer._offset
        for k in range(4):
            viewer.drag_to(eye + 0.5 * (t0 + [0.0, 0.05 * (k + 1), 0.0] - eye))
        viewer.page_watch._on_page_message(viewer.page_watch, {"event": "release", "why": "pointerup"}, [])
        viewer.drag_mode.value = False
        assert len(studio.history) == steps0 + 1 and studio.editor.rows[0]["target"][1] > t0[1] + 0.05
        studio.undo()
        np.testing.assert_allclose(studio.editor.rows[0]["target"], t0)
        assert studio._cameras() == camera0
    finally:
        session.clock = clock


def test_studio_setup_round_trip_and_bad_files(studio, tmp_path):
    ed = studio.editor
    ed.add("Head", "look_at", lam=0.3)
    path = studio.save(tmp_path / "setup.json")
    saved = json.loads(path.read_text())
    assert saved["format"] == "posekit-effector-setup" and saved["solvers"] == ["fabrik", "protores"]
    assert saved["effectors"][-1]["kind"] == "look_at" and saved["effectors"][-1]["lam"] == 0.3
    assert "download setup.json" in studio.message.value
    ed.remove(len(ed.rows) - 1)
    studio.load(path)
    assert ed.setup() == saved["effectors"]
    before = ed.setup()
    bad = {
        "broken.json": ('{"format": "posekit-effector-setup",\n "version": 1\n "effectors": []}', r"line 3, column 2"),
        "other.json": ('{"hello": 1}', "not a posekit effector setup"),
        "joint.json": (json.dumps({**saved, "effectors": [{"joint": "Tail", "kind": "position", "target": [0, 0, 0]}]}),
                       "effector 1: unknown joint 'Tail'"),
        "shape.json": (json.dumps({**saved, "effectors": [{"joint": "Hips", "kind": "position", "target": [0, 0]}]}),
                       r"'target' must be \(3,\) finite numbers"),
        "kind.json": (json.dumps({**saved, "effectors": [{"joint": "Hips", "kind": "pointing", "target": [0, 0, 0]}]}),
                      "unknown kind 'pointing'"),
        "rot.json": (json.dumps({**saved, "effectors": [{"joint": "Hips", "kind": "rotation", "base": np.ones((3, 3)).tolist()}]}),
                     "not a rotation matrix"),
        "skeleton.json": (json.dumps({**saved, "skeleton": ["a", "b"]}), "made for another skeleton"),
    }
    for name, (text, message) in bad.items():
        (tmp_path / name).write_text(text)
        with pytest.raises(ValueError, match=message):
            studio.load(tmp_path / name)
        assert ed.setup() == before, name  # nothing lost
    # the button path shows the message instead of raising
    studio.setup_path.value = str(tmp_path / "broken.json")
    studio._safely(lambda: studio.load(studio.setup_path.value), "setup")
    assert "line 3, column 2" in studio.message.value and ed.setup() == before
    # an upload (bytes from the browser) goes the same way
    studio._on_upload({"new": ({"name": "x.json", "content": memoryview(b"\xff\xfe")},)})
    assert "not a text file" in studio.message.value
    studio._on_upload({"new": ({"name": "s.json", "content": memoryview(path.read_bytes())},)})
    assert studio.message.value.startswith("loaded s.json")
    ed.remove(len(ed.rows) - 1)


def test_studio_exports_bvh_png_and_reads_a_start_pose(studio, bandai, tmp_path):
    m, cases = bandai
    for name in studio.solvers:
        p = studio.export_bvh(tmp_path / f"{name}.bvh", solver=name)
        np.testing.assert_allclose(read_bvh(p).global_positions()[0], studio.editor.results[name].pose.global_pos,
                                   atol=1e-6)
        assert "read back within 0.000 mm" in studio.message.value
    png = studio.export_png(tmp_path / "views.png")
    from PIL import Image

    with Image.open(png) as im:
        assert im.size[0] >= 600 and im.size[1] >= 300
    # a start pose from a BVH file (here one we wrote), and a malformed one that changes nothing
    write_poses_bvh(tmp_path / "start.bvh", m.skeleton, [cases.pose(2)], cases.pose(2))
    studio.load_start_bvh(tmp_path / "start.bvh")
    np.testing.assert_allclose(studio.start.global_pos, cases.pose(2).global_pos, atol=1e-6)
    (tmp_path / "bad.bvh").write_text("HIERARCHY\nROOT Hips\n{\n  OFFSET 0 zero 0\n")
    with pytest.raises(BVHError, match=r"bad.bvh:4: "):
        studio.load_start_bvh(tmp_path / "bad.bvh")
    np.testing.assert_allclose(studio.start.global_pos, cases.pose(2).global_pos, atol=1e-6)
    studio._on_upload({"new": ({"name": "bad.bvh", "content": memoryview((tmp_path / "bad.bvh").read_bytes())},)})
    assert "bad.bvh:4: " in studio.message.value
    write_poses_bvh(tmp_path / "start0.bvh", m.skeleton, [cases.pose(0)], cases.pose(0))
    studio.load_start_bvh(tmp_path / "start0.bvh")  # back to the fixture's start for the next tests


def test_studio_timeline_builds_and_exports_an_animation(studio, tmp_path):
    ed = studio.editor
    studio.clear_keys()
    with pytest.raises(ValueError, match="at least two keys"):
        studio.build_animation()
    studio.add_key()
    hand = [i for i, r in enumerate(ed.rows) if r["joint"] == "Hand_L"][0]
    ed.move_target(hand, ed.rows[hand]["target"] + [0.0, 0.3, 0.0])
    studio.add_key()
    ed.add("Chest", "rotation")
    with pytest.raises(ValueError, match="same effectors as the first"):
        studio.add_key()
    ed.remove(len(ed.rows) - 1)
    studio.inbetweens.value = 6
    frames = studio.build_animation("fabrik")
    assert len(frames) == 8 and all(r.converged for r in frames)
    assert studio.timeline_viewer is not None and studio.timeline_box.children
    p = studio.export_animation(tmp_path / "anim.bvh")
    back = read_bvh(p)
    assert back.n_frames == 8
    np.testing.assert_allclose(back.global_positions(), np.stack([r.pose.global_pos for r in frames]), atol=1e-6)
    studio.clear_keys()


def test_studio_solver_choice_and_a_failing_solver(studio, bandai):
    from posekit.ik.registry import register, unregister

    with pytest.raises(ValueError, match="choose 2 to 4 solvers"):
        studio.set_solvers(["fabrik"])
    with pytest.raises(ValueError, match="unknown solver"):
        studio.set_solvers(["fabrik", "nope"])
    setup = studio.editor.setup()
    studio.set_solvers(["dls", "ccd", "protores-transformer"])
    assert studio.solvers == ["dls", "ccd", "protores-transformer"] and studio.editor.setup() == setup
    assert len(studio.editor.viewers) == 3 and "protores-transformer" in studio.summary.value

    class Broken:
        kinds, needs_start = ("position",), True

        def __init__(self, skeleton):
            self.skeleton = skeleton

        def solve(self, start, effectors):
            raise RuntimeError("kaput")

    register("broken-test", Broken)
    try:
        studio.available.append("broken-test")
        studio.set_solvers(["fabrik", "broken-test"])
        assert isinstance(studio.editor.results["broken-test"], RuntimeError)
        assert "RuntimeError: kaput" in studio.editor.labels["broken-test"].value
        assert "failed: kaput" in studio.summary.value
        assert studio.editor.results["fabrik"].converged  # the others keep working
        ed = studio.editor
        ed.move_target(0, ed.rows[0]["target"] + [0.05, 0.0, 0.0])
        assert studio.editor.results["fabrik"].converged
    finally:
        studio.available.remove("broken-test")
        unregister("broken-test")
        studio.set_solvers(["fabrik", "protores"])


def test_bench_studio_refuses_bad_configurations_before_starting_anything():
    from posekit.bench.studio import rapid_updates, run

    with pytest.raises(ValueError, match="give 2-4 registered solvers"):
        run(updates=10, configs=["fabrik"])
    with pytest.raises(ValueError, match=r"unknown: nope"):
        run(updates=10, configs=["fabrik,nope"])
    with pytest.raises(ValueError, match="at least 1"):
        rapid_updates(None, 0)
    from posekit.bench.studio import class_sessions
    from posekit.cli import main

    with pytest.raises(ValueError, match="--sessions and --updates must be at least 1"):
        class_sessions(0)
    assert main(["bench", "studio", "--sessions", "two"]) == 2
    with pytest.raises(ValueError, match="--first-views: expected at least 1 page, got 0"):
        run(updates=10, first_views=0)
    assert main(["bench", "studio", "--first-views", "0"]) == 2


def test_skeleton_sides_from_names():
    from posekit.skeleton import Skeleton

    names = ["Hips", "LeftUpLeg", "RightUpLeg", "Spine", "Hand_L", "Hand_R", "left_foot", "LThumb", "Head"]
    parents = [-1, 0, 0, 0, 3, 3, 1, 4, 3]
    s = Skeleton(names, np.array(parents), np.zeros((len(names), 3)))
    assert list(s.sides()) == [0, 1, -1, 0, 1, -1, 1, 1, 0]


def test_app_studio_is_lesson_06s_studio(tmp_path):
    """What make studio shows: lesson 06's held-out case and first four solvers, the left hand selected."""
    from posekit.viz.studio_app import SOLVERS, app_studio

    studio, refused = app_studio(export_dir=tmp_path)
    assert refused == {} and list(studio.editor.solvers) == list(SOLVERS)
    assert studio.editor.first.selected == "Hand_L"
    assert all(r.converged for r in studio.editor.results.values())


def test_each_page_of_the_app_writes_into_a_folder_of_its_own(tmp_path, monkeypatch):
    """make studio gives every student a kernel of their own in one working folder: each page's setups, uploads
    and exports go to a folder of its own, so one student's save, or broken upload of a file of the same name,
    never changes what another loads or wrote."""
    from posekit.viz.studio_app import EXPORTS, app_studio

    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("POSEKIT_EXPORTS_DIR", raising=False)  # the app's own default: EXPORTS in the working folder
    a, _ = app_studio(solvers="fabrik,dls")
    b, _ = app_studio(solvers="fabrik,dls")
    assert a.export_dir != b.export_dir and a.export_dir.parent == b.export_dir.parent == Path(EXPORTS)
    assert not (tmp_path / EXPORTS).exists()  # nothing is made before a page writes
    rows = len(a.editor.rows)
    a.save_button.click()  # each saves to the setup file its page offers
    b.editor.remove(rows - 1)
    b.save_button.click()
    assert a.setup_path.value == b.setup_path.value == "setup.json" and str(b.export_dir) in b.message.value
    a.load_button.click()
    assert len(a.editor.rows) == rows and len(b.editor.rows) == rows - 1
    # and nothing outside a page's folder: not another page's folder, nor any path of the server
    for path in (f"../{b.export_dir.name}/setup.json", str(tmp_path / "elsewhere.json"), "", "."):
        a.setup_path.value = path
        a.save_button.click()
        assert "give a file name in this page" in a.message.value, (path, a.message.value)
    assert not (tmp_path / "elsewhere.json").exists()
    b.load_button.click()  # b's file untouched
    assert len(b.editor.rows) == rows - 1 and "loaded" in b.message.value
    # a uploads a start pose; b uploads a broken file of the same name
    write_poses_bvh(tmp_path / "start.bvh", a.skeleton, [a.start], a.start)
    good = (tmp_path / "start.bvh").read_bytes()
    a._on_upload({"new": ({"name": "start.bvh", "content": memoryview(good)},)})
    b._on_upload({"new": ({"name": "start.bvh", "content": memoryview(b"HIERARCHY\nROOT Hips\n{\n")},)})
    assert "start.bvh:" in b.message.value and "start.bvh:" not in a.message.value
    assert (a.export_dir / "start.bvh").read_bytes() == good
    assert sorted(p.name for p in (tmp_path / EXPORTS).iterdir()) == sorted([a.export_dir.name, b.export_dir.name])


def test_app_studio_lets_its_data_set_go_before_it_hands_memory_back(tmp_path, monkeypatch):
    """The app keeps the skeleton and its held-out case, not the data set it read them from, and the data set is
    gone by the time the app hands freed memory back to the system (else a studio kernel counts it, about 35 MB,
    for as long as it lives)."""
    import gc
    import weakref

    import posekit.data.sources as sources
    import posekit.viz.studio_app as app

    opened, open_dataset, gone_when_handed_back = [], sources.open_dataset, []

    def tracked(*args, **kwargs):
        motions = open_dataset(*args, **kwargs)
        opened.append(weakref.ref(motions))
        return motions

    def hand_back():
        gc.collect()
        gone_when_handed_back.append(all(ref() is None for ref in opened))

    monkeypatch.setattr(sources, "open_dataset", tracked)
    monkeypatch.setattr(app, "_return_freed_memory", hand_back)
    studio, _ = app.app_studio(solvers="fabrik,dls", export_dir=tmp_path)
    assert len(opened) == 1 and gone_when_handed_back == [True]
    assert studio.editor.first.selected == "Hand_L"


def test_app_studio_on_another_skeleton_leaves_out_the_learned_solvers(tmp_path, monkeypatch):
    """Another data set (STUDIO_DATA): the shipped learned models, made for the Bandai skeleton, are left out by
    name with the reason; FABRIK and DLS pose it; unknown names are refused with the registered ones."""
    from posekit.viz.studio_app import app_studio, refused_note

    monkeypatch.setenv("POSEKIT_STUDIO_DATA", "sample")
    studio, refused = app_studio(export_dir=tmp_path)
    assert list(studio.editor.solvers) == ["fabrik", "dls"]
    assert {"protores+dls", "latent-opt+dls", "neural"} <= set(refused)
    assert "fabrik" in studio.available and "protores" not in studio.available
    assert "left out (made for another skeleton): " in refused_note(refused)
    with pytest.raises(ValueError, match="unknown solver.*'nope'.*registered: fabrik"):
        app_studio("sample", "fabrik,nope", export_dir=tmp_path)


def test_a_move_reaches_the_browser_as_every_views_pose_then_the_update_counter(studio, monkeypatch):
    """The update counter (the summary, which ``posekit bench studio`` and the browser tests read as "every view
    is drawn") is the last message of a target move, after exactly one position array per view: the first
    view, whose slider moved, included."""
    import ipywidgets as w

    ed = studio.editor
    first = ed.first
    first.select(ed.rows[0]["joint"])
    sent = []
    real = w.Widget._send
    monkeypatch.setattr(w.Widget, "_send", lambda self, msg, buffers=None: (sent.append((self, msg)),
                                                                            real(self, msg, buffers))[1])
    x = first.sliders[0]
    x._handle_msg({"content": {"data": {"method": "update", "state": {"value": x.value + 0.002}, "buffer_paths": []}},
                   "buffers": []})
    widgets = [s for s, _ in sent]
    arrays = {name: v._figure._shared["position"] for name, v in ed.viewers.items()}
    assert widgets[-1] is studio.summary and "update" in sent[-1][1]["state"]["value"]
    for name, a in arrays.items():
        assert sum(s is a for s in widgets) == 1, f"{name}: expected one position array per move"
    assert first.status in widgets and widgets.index(first.status) < len(widgets) - 1


def test_make_lab_and_make_studio_pass_the_websocket_setting():
    # the Makefile names the connection class itself (make cannot import it): the commands it would run must carry
    # exactly the flags posekit.viz.websocket gives, for JupyterLab and for Voila
    import shutil
    import subprocess

    from posekit.viz.websocket import server_flags

    if shutil.which("make") is None:
        pytest.skip("make is not installed")
    root = Path(__file__).resolve().parents[2]
    lines = subprocess.run(["make", "-n", "lab", "studio"], cwd=root, capture_output=True, text=True,
                           check=True).stdout.replace("\\\n", " ").splitlines()
    lab = [line for line in lines if "jupyter lab notebooks/" in line]
    studio = [line for line in lines if "voila studio.ipynb" in line]
    assert len(lab) == 1 and server_flags("lab")[0] in lab[0].split(), lab
    assert len(studio) == 1 and server_flags("voila")[0] in studio[0].split(), studio


def test_the_summary_names_the_effectors_a_solver_ignored(bandai, tmp_path):
    """Issue 44: with a look-at and a rotation effector, FABRIK (positions only) reaches its five targets; the
    "All solvers" summary says so as its view does ("5 of 7 reached · rotation, look-at ignored"), never with a
    ✓ (issue 57: an ignored effector is unmet), and its view's error figure says which kinds it did not measure."""
    import re

    from posekit.viz import PosingStudio

    m, cases = bandai
    s = m.skeleton
    studio = PosingStudio(s, cases.pose(0), ["fabrik", "dls"], effector_set(s, "5", cases.target_pos[0]),
                          export_dir=tmp_path)
    studio.editor.add("Chest", "rotation")
    studio.editor.add("Neck", "look_at")
    rows = dict(re.findall(r"<td[^>]*>([^<]+)</td><td[^>]*>(.*?)</td></tr>", studio.summary.value))
    assert studio.editor.results["fabrik"].converged
    assert "5 of 7 reached" in rows["fabrik"] and "rotation, look-at ignored" in rows["fabrik"], rows["fabrik"]
    view = studio.editor.labels["fabrik"].value
    assert "5 of 7 reached" in view and "rotation, look-at ignored" in view
    assert "✓" not in rows["fabrik"] and "✓" not in view, (rows["fabrik"], view)
    # the summary's columns line up: every solved row has its name, mark, errors and time in cells of their own
    cells = re.findall(r"<tr>(.*?)</tr>", studio.summary.value)
    assert [c.count("<td") for c in cells] == [4, 4], cells
    assert "rotation, look-at not measured" in view, view
    assert "ignored" not in rows["dls"], rows["dls"]  # DLS honours every kind


def test_a_message_shows_beside_its_control_and_clears_at_the_next_success(studio, tmp_path):
    """Issue 44: ticking seven solvers and pressing *compare* (lesson 06's own words) is refused on the line beside
    *compare*, not at the page's foot; the next action that succeeds clears it and says its own on its row; the
    busy sign is drawn by CSS, not an emoji a browser without an emoji font shows as a box."""
    from posekit.viz.studio import BUSY_SIGN

    lines = studio.message.lines
    ticked = [c for c in studio.checks.values() if not c.value][:5]
    for c in ticked:
        c.value = True
    try:
        studio.compare_button.click()
        assert "choose 2 to 4 solvers" in lines["solvers"].value
        assert not any(lines[r].value for r in ("setup", "export", "timeline"))
        row = next(b for b in studio.widget.children if lines["solvers"] in getattr(b, "children", ())
                   or any(lines["solvers"] in getattr(c, "children", ()) for c in getattr(b, "children", ())))
        assert studio.compare_button in row.children[1].children  # the same box as the button
    finally:
        for c in ticked:
            c.value = False
    studio.setup_path.value = str(tmp_path / "s.json")
    studio.save_button.click()
    assert lines["solvers"].value == "" and "saved" in lines["setup"].value
    assert set(lines) == {"solvers", "setup", "export", "timeline"}
    with studio.working():
        # text a Debian browser's fonts hold (DejaVu: "…"), no emoji (U+23F3 and above)
        assert "posekit-spin" in studio.busy.value and all(ord(ch) < 0x2300 for ch in studio.busy.value)
    assert "⏳" not in BUSY_SIGN


def test_undo_brings_back_the_camera_with_the_pose(studio):
    """Issue 44: a target moved far widens the camera; undo puts the pose *and* every view's camera back, redo the
    widened one."""
    ed = studio.editor
    before = {n: list(v.camera.position) for n, v in ed.viewers.items()}
    ed.move_target(0, ed.rows[0]["target"] + [0.0, 3.0, 0.0])
    after = {n: list(v.camera.position) for n, v in ed.viewers.items()}
    assert all(np.linalg.norm(after[n]) > np.linalg.norm(before[n]) + 0.5 for n in before), (before, after)
    studio.undo()
    for n, v in studio.editor.viewers.items():
        np.testing.assert_allclose(v.camera.position, before[n], err_msg=n)
    studio.redo()
    for n, v in studio.editor.viewers.items():
        np.testing.assert_allclose(v.camera.position, after[n], err_msg=n)
    studio.undo()

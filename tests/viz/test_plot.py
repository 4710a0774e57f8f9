"""The static pose figures (posekit.viz.plot): true to the world (a rotation of it, never a mirror image), left and
right told apart, only the body drawn, no legend on a panel, compared panels on one scale, strips with a scale bar."""

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402

from posekit.data.metrics import body_joints  # noqa: E402
from posekit.viz.meshes import SIDE_COLOURS  # noqa: E402
from posekit.viz.plot import SCALE_BAR_M, SIDE_LABELS, drawn_bones, plot_pose, plot_strip, to_mpl  # noqa: E402


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


def _segments(ax):
    """Every 3D line of the axes as its (2, 3) end points in matplotlib's data coordinates (world z, x, y)."""
    return [np.array(line.get_data_3d()).T for line in ax.get_lines()]


def test_a_helper_root_is_no_bone_and_no_joint(mini):
    skel, pose = mini.skeleton, mini.global_pos[100]
    root = 0
    assert root not in body_joints(skel)  # Bandai's joint_Root: a point on the floor, not the body
    bones = drawn_bones(skel)
    assert len(bones) == len(body_joints(skel)) - 1 and all(root not in b for b in bones)
    ax = plot_pose(skel, pose)
    segs = _segments(ax)
    assert len(segs) == len(bones)
    root_mpl = np.array(to_mpl(pose[root]))
    assert not any(np.allclose(s, root_mpl) for seg in segs for s in seg)  # no bone ends at the floor point
    (dots,) = ax.collections
    assert len(dots._offsets3d[0]) == len(body_joints(skel))


def test_a_skeleton_rooted_at_the_pelvis_draws_every_bone(skel, sample):
    assert len(body_joints(skel)) == skel.n_joints
    ax = plot_pose(skel, sample.global_pos[0])
    assert len(_segments(ax)) == skel.n_joints - 1


def test_the_legend_goes_above_the_figure_never_on_a_panel(mini):
    skel, p = mini.skeleton, mini.global_pos[[100, 200]]
    fig = plt.figure(figsize=(8, 3.5))
    axes = [fig.add_subplot(1, 2, k + 1, projection="3d") for k in range(2)]
    plot_pose(skel, p[0], ax=axes[0], ghost=p[1], label="solved", ghost_label="true pose")
    plot_pose(skel, p[1], ax=axes[1], targets=p[0][[5, 9]], target_label="targets")
    assert all(a.get_legend() is None for a in axes)
    assert len(fig.legends) == 1  # one for the figure, every entry of its panels
    (legend,) = fig.legends
    assert [t.get_text() for t in legend.get_texts()] == ["true pose", "solved", "targets", *SIDE_LABELS.values()]
    renderer = fig.canvas.get_renderer()
    box = legend.get_window_extent(renderer)
    assert box.y0 >= max(a.get_window_extent(renderer).y1 for a in axes) - 1e-6


def test_without_labels_the_legend_is_the_side_key_alone(mini):
    ax = plot_pose(mini.skeleton, mini.global_pos[0])
    assert ax.get_legend() is None
    (legend,) = ax.figure.legends
    assert [t.get_text() for t in legend.get_texts()] == ["left side", "right side", "centre"]


def test_a_skeleton_without_sides_gets_no_legend():
    from types import SimpleNamespace

    bare = SimpleNamespace(parents=np.array([-1, 0, 1]), n_joints=3)
    ax = plot_pose(bare, np.array([[0.0, 0, 0], [0, 1, 0], [0, 2, 0]]))
    assert ax.get_legend() is None and not ax.figure.legends


def test_bones_are_coloured_by_the_side_of_the_body(mini):
    from matplotlib.colors import to_hex

    skel = mini.skeleton
    ax = plot_pose(skel, mini.global_pos[100], ghost=mini.global_pos[200])
    bones = drawn_bones(skel)
    lines = ax.get_lines()
    ghost, pose = lines[:len(bones)], lines[len(bones):]
    assert {to_hex(line.get_color()) for line in ghost} == {to_hex("0.6")}  # the ghost stays grey
    for (a, b), line in zip(bones, pose):
        name = skel.names[b]
        want = 1 if name.endswith("_L") else -1 if name.endswith("_R") else 0  # Bandai's Hand_L is the left hand
        assert to_hex(line.get_color()) == SIDE_COLOURS[want], name
    one = plot_pose(skel, mini.global_pos[100], color="C2")  # a colour given: one colour, no key
    assert {to_hex(line.get_color()) for line in one.get_lines()} == {to_hex("C2")}
    assert not one.figure.legends


def test_every_strip_panel_has_a_scale_bar_and_the_same_scale(mini):
    fig = plot_strip(mini.skeleton, mini.global_pos[[0, 500, 1000]], titles=["a", "b", "c"])
    assert len(fig.axes) == 3
    for ax in fig.axes:
        bars = [s for s in _segments(ax) if np.allclose(s[:, :2], s[0, :2]) and np.isclose(np.ptp(s[:, 2]), SCALE_BAR_M)]
        assert len(bars) == 1, "one vertical bar of SCALE_BAR_M metres per panel"
        x, y, z = bars[0][0]
        # from the default front-left camera: the cube's front (largest world z) at the character's right (smallest x)
        assert (x, y, z) == (ax.get_xlim()[1], ax.get_ylim()[0], ax.get_zlim()[0])
        assert any(t.get_text().strip() == f"{SCALE_BAR_M:g} m" for t in ax.texts)
    assert any(f"black bar: {SCALE_BAR_M:g} m" in t.get_text() for t in fig.texts)
    assert any("seen from the front-left" in t.get_text() for t in fig.texts)
    sizes = {round(float(np.ptp(lim)), 9) for ax in fig.axes for lim in (ax.get_xlim(), ax.get_ylim(), ax.get_zlim())}
    assert len(sizes) == 1, "one scale for x, y and z in every panel"


def test_a_shared_strip_shows_every_panel_in_one_frame(mini):
    fig = plot_strip(mini.skeleton, mini.global_pos[[0, 40, 80]], frame="shared")
    limits = {(ax.get_xlim(), ax.get_ylim(), ax.get_zlim()) for ax in fig.axes}
    assert len(limits) == 1


def test_a_bare_parents_skeleton_draws_every_joint():
    from types import SimpleNamespace

    bare = SimpleNamespace(parents=np.array([-1, 0, 1]), n_joints=3)  # what a recorded still carries
    pose = np.array([[0.0, 0, 0], [0, 1, 0], [0, 2, 0]])
    assert drawn_bones(bare) == [(0, 1), (1, 2)]
    assert drawn_bones(bare, body=[1, 2]) == [(1, 2)]
    assert len(_segments(plot_pose(bare, pose, body=[1, 2]))) == 1


# ---------------------------------------------------------------------------------------------- true to the world
def _raised_left_hand():
    """A small figure facing +Z (posekit.conventions): its left hand (+x) raised above its head, its right hand low."""
    from posekit.skeleton import Skeleton

    names = ("pelvis", "chest", "head", "left_hand", "right_hand")
    parents = [-1, 0, 1, 1, 1]
    pose = np.array([[0.0, 1.0, 0.0], [0.0, 1.4, 0.0], [0.0, 1.65, 0.05], [0.35, 1.9, 0.05], [-0.3, 1.1, 0.05]])
    offsets = pose - pose[np.maximum(parents, 0)]
    offsets[0] = pose[0]
    return Skeleton(names, parents, offsets), pose


def _screen(ax, pts_mpl):
    """Display coordinates (pixels) and matplotlib's projected depth of points given in the axes' data order."""
    from mpl_toolkits.mplot3d import proj3d

    ax.figure.canvas.draw()
    x, y, z = proj3d.proj_transform(*np.asarray(pts_mpl, float).T, ax.get_proj())
    return ax.transData.transform(np.c_[x, y]), np.asarray(z)


def _drawn_joints(ax):
    """The joint dots of the one pose drawn on ``ax``, in the skeleton's joint order, matplotlib's data coordinates."""
    (dots,) = ax.collections
    return np.array(dots._offsets3d, float).T


@pytest.mark.parametrize("side, on_the_right", [("front", True), ("back", False)])
def test_the_left_hand_is_on_the_side_a_viewer_sees_it(side, on_the_right):
    # a person facing you has their left hand on your right; seen from behind, on your left
    from posekit.viz.plot import view_azim

    skel, pose = _raised_left_hand()
    ax = plot_pose(skel, pose, elev=10, azim=view_azim(side))
    px, _ = _screen(ax, _drawn_joints(ax))
    left, right, head = px[skel.index("left_hand")], px[skel.index("right_hand")], px[skel.index("head")]
    assert left[1] > head[1] > right[1]  # the raised hand is the highest thing drawn: y is up on the image
    assert (left[0] > head[0] > right[0]) == on_the_right


@pytest.mark.parametrize("elev, azim", [(12, 30), (12, -70), (40, 150), (-20, -120), (5, 95)])
def test_every_view_is_a_rotation_of_the_world_never_a_mirror(elev, azim):
    # world axes x, y, z drawn from any camera must keep their handedness: with u the image's right, v its up
    # and w towards the viewer, det [u v w] of the drawn world axes is positive (a mirror makes it negative)
    from types import SimpleNamespace

    bare = SimpleNamespace(parents=np.array([-1, 0, 0, 0]), n_joints=4)
    pose = np.array([[0.0, 1.0, 0.0], [0.5, 1.0, 0.0], [0.0, 1.5, 0.0], [0.0, 1.0, 0.5]])  # origin, +x, +y, +z
    ax = plot_pose(bare, pose, elev=elev, azim=azim)
    px, depth = _screen(ax, _drawn_joints(ax))
    # which way matplotlib's projected depth grows towards the viewer, read off a plain axes (no posekit in it)
    probe = plt.figure().add_subplot(projection="3d")
    probe.view_init(elev=0, azim=0)  # the camera on matplotlib's +x axis
    _, d = _screen(probe, [[0, 0, 0], [1, 0, 0]])
    towards_viewer = np.sign(d[1] - d[0])
    screen = px[1:] - px[0]  # rows: world x, y, z drawn, in pixels
    towards = towards_viewer * (depth[1:] - depth[0])  # their depth, in matplotlib's own units
    # scaling a column by a positive number keeps the determinant's sign: bring both to unit length
    frame = np.c_[screen / np.linalg.norm(screen), towards / np.linalg.norm(towards)]
    assert np.linalg.det(frame) > 0.05

"""The static pose figures (posekit.viz.plot): only the body is drawn, no legend sits on a panel, strips carry a
scale bar."""

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402

from posekit.data.metrics import body_joints  # noqa: E402
from posekit.viz.plot import SCALE_BAR_M, drawn_bones, plot_pose, plot_strip  # noqa: E402


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


def _segments(ax):
    """Every 3D line of the axes as its (2, 3) end points in matplotlib's (x, z, y) order."""
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
    root_mpl = pose[root][[0, 2, 1]]
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
    assert [t.get_text() for t in legend.get_texts()] == ["true pose", "solved", "targets"]
    renderer = fig.canvas.get_renderer()
    box = legend.get_window_extent(renderer)
    assert box.y0 >= max(a.get_window_extent(renderer).y1 for a in axes) - 1e-6


def test_no_legend_without_labels(mini):
    ax = plot_pose(mini.skeleton, mini.global_pos[0])
    assert ax.get_legend() is None and not ax.figure.legends


def test_every_strip_panel_has_a_scale_bar(mini):
    fig = plot_strip(mini.skeleton, mini.global_pos[[0, 500, 1000]], titles=["a", "b", "c"])
    assert len(fig.axes) == 3
    for ax in fig.axes:
        bars = [s for s in _segments(ax) if np.allclose(s[:, :2], s[0, :2]) and np.isclose(np.ptp(s[:, 2]), SCALE_BAR_M)]
        assert len(bars) == 1, "one vertical bar of SCALE_BAR_M metres per panel"
        x, y, z = bars[0][0]
        assert (x, y, z) == (ax.get_xlim()[0], ax.get_ylim()[0], ax.get_zlim()[0])
        assert any(t.get_text().strip() == f"{SCALE_BAR_M:g} m" for t in ax.texts)
    assert any(f"black bar: {SCALE_BAR_M:g} m" in t.get_text() for t in fig.texts)


def test_a_bare_parents_skeleton_draws_every_joint():
    from types import SimpleNamespace

    bare = SimpleNamespace(parents=np.array([-1, 0, 1]), n_joints=3)  # what a recorded still carries
    pose = np.array([[0.0, 0, 0], [0, 1, 0], [0, 2, 0]])
    assert drawn_bones(bare) == [(0, 1), (1, 2)]
    assert drawn_bones(bare, body=[1, 2]) == [(1, 2)]
    assert len(_segments(plot_pose(bare, pose, body=[1, 2]))) == 1

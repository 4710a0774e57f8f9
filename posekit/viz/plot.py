"""Static matplotlib pose figures (they show on GitHub and in rendered docs, unlike the 3D widget).

Introduced in ``notebooks/00_skeletons_and_poses.ipynb``. World axes: :mod:`posekit.conventions`
(Y up); matplotlib's 3D axes are Z up, so world ``(x, y, z)`` is drawn at ``(x, z, y)``.

Only the body is drawn: a helper root such as Bandai's ``joint_Root`` (a point on the floor that carries the
world position, :func:`posekit.data.metrics.body_joints`) is neither a joint nor the end of a bone, so no
"third leg" runs from the pelvis to the floor. A legend never sits on a panel: it goes above the figure, one
for all its panels. A strip's panels carry a scale bar, since they show no tick labels.
"""

from __future__ import annotations

import numpy as np

from ..data.metrics import body_joints
from ..skeleton import Skeleton

__all__ = ["plot_pose", "plot_strip", "drawn_bones", "SCALE_BAR_M"]

SCALE_BAR_M = 0.5
"""Length of a strip panel's scale bar, metres."""


def _body(skeleton, body=None) -> np.ndarray:
    """The joints drawn: ``body`` when given, else the skeleton's body joints (all of them for a skeleton that
    has no roles to tell its pelvis, such as a bare ``parents`` array)."""
    if body is not None:
        return np.asarray(body, dtype=int)
    if hasattr(skeleton, "pelvis"):
        return body_joints(skeleton)
    return np.arange(skeleton.n_joints)


def drawn_bones(skeleton, body=None) -> list[tuple[int, int]]:
    """The ``(parent, child)`` joint pairs :func:`plot_pose` draws as bones: both ends body joints.

    Parameters
    ----------
    skeleton : Skeleton
    body : sequence of int, optional
        The joints that make up the body; default :func:`posekit.data.metrics.body_joints`.

    Returns
    -------
    list of (int, int)
    """
    keep = set(int(j) for j in _body(skeleton, body))
    return [(int(skeleton.parents[j]), j) for j in range(1, skeleton.n_joints)
            if j in keep and int(skeleton.parents[j]) in keep]


def _to_mpl(p):
    p = np.asarray(p, dtype=float)
    return p[..., 0], p[..., 2], p[..., 1]


def plot_pose(skeleton: Skeleton, global_pos, ax=None, color="C0", ghost=None, ghost_color="0.6",
              targets=None, title: str | None = None, elev: float = 12, azim: float = -70,
              joints: bool = True, label: str | None = None, ghost_label: str | None = None,
              target_label: str | None = None, body=None):
    """Draw one pose (or several overlaid) as bones and joints on a 3D axes.

    Parameters
    ----------
    skeleton : Skeleton
    global_pos : ndarray, shape (J, 3) or (K, J, 3), metres
    ax : mpl_toolkits.mplot3d.Axes3D, optional
        Created when not given.
    ghost : ndarray, shape (J, 3), optional
        A second pose drawn in ``ghost_color`` (e.g. the ground truth).
    targets : ndarray, shape (T, 3), optional
        Target markers (red crosses).
    label, ghost_label, target_label : str, optional
        Legend entries for the pose, the ghost and the targets; when any is given, one legend for the whole
        figure is drawn above it (never over a panel), holding every entry given to its panels so far.
    body : sequence of int, optional
        The joints to draw; default the body joints (a helper root is left out, and so is its bone).

    Returns
    -------
    ax
    """
    import matplotlib.pyplot as plt

    pos = np.asarray(global_pos, dtype=float)
    if pos.shape[-2:] != (skeleton.n_joints, 3):
        raise ValueError(f"global_pos: expected shape (J, 3) or (K, J, 3) with J={skeleton.n_joints}, got {pos.shape}")
    if ax is None:
        fig = plt.figure(figsize=(4, 4))
        ax = fig.add_subplot(projection="3d")
    poses = pos.reshape(-1, skeleton.n_joints, 3)
    keep = _body(skeleton, body)
    bones = drawn_bones(skeleton, keep)
    everything = [poses[:, keep].reshape(-1, 3)]

    def draw(p, c, alpha, lw, lab=None):
        for k, (a, b) in enumerate(bones):
            xs, ys, zs = _to_mpl(np.stack([p[a], p[b]]))
            ax.plot(xs, ys, zs, color=c, alpha=alpha, lw=lw, label=lab if k == 0 else None)
        if joints:
            ax.scatter(*_to_mpl(p[keep]), color=c, alpha=alpha, s=8, depthshade=False)

    if ghost is not None:
        g = np.asarray(ghost, dtype=float).reshape(-1, skeleton.n_joints, 3)
        everything.append(g[:, keep].reshape(-1, 3))
        for k, p in enumerate(g):
            draw(p, ghost_color, 0.8, 1.5, ghost_label if k == 0 else None)
    for k, p in enumerate(poses):
        draw(p, color, 1.0 if len(poses) == 1 else 0.35 + 0.65 * (k + 1) / len(poses), 2.0,
             label if k == len(poses) - 1 else None)
    if targets is not None:
        t = np.asarray(targets, dtype=float).reshape(-1, 3)
        everything.append(t)
        ax.scatter(*_to_mpl(t), color="red", marker="x", s=40, depthshade=False, label=target_label)
    pts = np.concatenate(everything)
    centre = 0.5 * (pts.min(0) + pts.max(0))
    half = 0.5 * max(float(np.ptp(pts, axis=0).max()), 0.5)
    cx, cy, cz = _to_mpl(centre)
    ax.set_xlim(cx - half, cx + half)
    ax.set_ylim(cy - half, cy + half)
    ax.set_zlim(cz - half, cz + half)
    ax.set_box_aspect((1, 1, 1))
    from matplotlib.ticker import MaxNLocator

    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):  # few, small ticks: full ones overlap on a 4-inch axes
        axis.set_major_locator(MaxNLocator(3))
    ax.tick_params(labelsize=7, pad=-2)
    ax.set_xlabel("x (m)", fontsize=8, labelpad=-6)
    ax.set_ylabel("z (m)", fontsize=8, labelpad=-6)
    ax.set_zlabel("y, up (m)", fontsize=8, labelpad=-6)
    ax.view_init(elev=elev, azim=azim)
    if title:
        ax.set_title(title)
    if label or ghost_label or target_label:
        _figure_legend(ax.figure)
    return ax


def _figure_legend(fig) -> None:
    """One legend above the figure for every labelled entry of its axes (replacing an earlier one), so that
    no legend covers a panel's data."""
    entries = {}
    for a in fig.axes:
        for h, lab in zip(*a.get_legend_handles_labels()):
            entries.setdefault(lab, h)
    for old in list(fig.legends):
        old.remove()
    fig.legend(list(entries.values()), list(entries), loc="lower center", bbox_to_anchor=(0.5, 1.0),
               ncol=len(entries), fontsize=8, frameon=False, handlelength=1.5)


def _scale_bar(ax, length: float = SCALE_BAR_M) -> None:
    """A vertical bar of ``length`` metres at the front left corner of the panel's floor, labelled."""
    x0, y0, z0 = ax.get_xlim()[0], ax.get_ylim()[0], ax.get_zlim()[0]
    ax.plot([x0, x0], [y0, y0], [z0, z0 + length], color="k", lw=2.5, solid_capstyle="butt")
    ax.text(x0, y0, z0 + 0.5 * length, f" {length:g} m", fontsize=7, ha="left", va="center")


def plot_strip(skeleton: Skeleton, poses, titles=None, elev: float = 12, azim: float = -70, size: float = 2.6,
               scale_m: float = SCALE_BAR_M):
    """A row of poses, each on its own 3D axes (for a tour of clips), each with a scale bar.

    Parameters
    ----------
    poses : ndarray, shape (K, J, 3)
    titles : list of str, optional
    scale_m : float
        Length of every panel's scale bar (a black vertical bar at the panel's front left floor corner), metres.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    poses = np.asarray(poses, dtype=float)
    fig = plt.figure(figsize=(size * len(poses), size + 0.4))
    for k, p in enumerate(poses):
        ax = fig.add_subplot(1, len(poses), k + 1, projection="3d")
        plot_pose(skeleton, p, ax=ax, title=None if titles is None else titles[k], elev=elev, azim=azim)
        ax.set_xticklabels([])  # a strip shows shapes: numbers and axis names on every small panel only crowd it
        ax.set_yticklabels([])
        ax.set_zticklabels([])
        ax.set_xlabel("")
        ax.set_ylabel("")
        ax.set_zlabel("")
        _scale_bar(ax, scale_m)
    # tight_layout cannot measure 3D axes; fixed margins keep every panel whole
    fig.subplots_adjust(left=0.0, right=1.0, bottom=0.08, top=0.92, wspace=0.02)
    fig.text(0.5, 0.01, f"each panel framed on its own pose, one scale for x, y and z (y up); black bar: {scale_m:g} m", ha="center",
             fontsize=8, color="0.35")
    return fig

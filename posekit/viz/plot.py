"""Static matplotlib pose figures (they show on GitHub and in rendered docs, unlike the 3D widget).

Introduced in ``notebooks/00_skeletons_and_poses.ipynb``. World axes: :mod:`posekit.conventions`
(Y up); matplotlib's 3D axes are Z up, so world ``(x, y, z)`` is drawn at ``(x, z, y)``.
"""

from __future__ import annotations

import numpy as np

from ..skeleton import Skeleton

__all__ = ["plot_pose", "plot_strip"]


def _to_mpl(p):
    p = np.asarray(p, dtype=float)
    return p[..., 0], p[..., 2], p[..., 1]


def plot_pose(skeleton: Skeleton, global_pos, ax=None, color="C0", ghost=None, ghost_color="0.6",
              targets=None, title: str | None = None, elev: float = 12, azim: float = -70,
              joints: bool = True, label: str | None = None, ghost_label: str | None = None,
              target_label: str | None = None):
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
        Legend entries for the pose, the ghost and the targets; a legend is drawn when any is given.

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
    everything = [poses.reshape(-1, 3)]

    def draw(p, c, alpha, lw, lab=None):
        for j in range(1, skeleton.n_joints):
            a, b = p[skeleton.parents[j]], p[j]
            xs, ys, zs = _to_mpl(np.stack([a, b]))
            ax.plot(xs, ys, zs, color=c, alpha=alpha, lw=lw, label=lab if j == 1 else None)
        if joints:
            ax.scatter(*_to_mpl(p), color=c, alpha=alpha, s=8, depthshade=False)

    if ghost is not None:
        g = np.asarray(ghost, dtype=float).reshape(-1, skeleton.n_joints, 3)
        everything.append(g.reshape(-1, 3))
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
        ax.legend(loc="upper left", fontsize=7, frameon=False, handlelength=1.2)
    return ax


def plot_strip(skeleton: Skeleton, poses, titles=None, elev: float = 12, azim: float = -70, size: float = 2.6):
    """A row of poses, each on its own 3D axes (for a tour of clips).

    Parameters
    ----------
    poses : ndarray, shape (K, J, 3)
    titles : list of str, optional

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
    # tight_layout cannot measure 3D axes; fixed margins keep every panel whole
    fig.subplots_adjust(left=0.0, right=1.0, bottom=0.08, top=0.92, wspace=0.02)
    fig.text(0.5, 0.01, "each panel framed on its own pose, one scale for x, y and z (metres; y up)", ha="center",
             fontsize=8, color="0.35")
    return fig

"""Static matplotlib pose figures (they show on GitHub and in rendered docs, unlike the 3D widget).

Introduced in ``notebooks/00_skeletons_and_poses.ipynb``.

**Axes, true to the world.** World axes are those of :mod:`posekit.conventions`: right-handed, Y up, a character
facing +Z has its left at +X. Matplotlib's 3D axes are right-handed too, with Z up, so world ``(x, y, z)`` is drawn
at matplotlib's ``(z, x, y)`` (:func:`to_mpl`): a cyclic relabelling, which is a rotation (determinant +1), never a
reflection, so no figure is a mirror image. (Swapping two axes, world ``(x, y, z)`` at ``(x, z, y)``, would be one.)
With this mapping a camera's azimuth ``azim`` (degrees) is its angle around the up axis from the front of a
character facing +Z towards that character's left: 0 in front, 90 at its left, 180 behind, -90 at its right
(:func:`view_azim`, :func:`view_side`); ``elev`` is the camera's height above the floor's plane, degrees. The
default view, ``elev=12, azim=30``, looks from the **front-left**. A person facing the camera has their left hand
on the image's right, as in a photograph.

**Left and right told apart.** Bones are coloured by the side of the body of their child joint
(:func:`posekit.skeleton.joint_sides`, the names mirroring swaps): left dark blue, right dark red, centre grey, the
colours of the 3D viewer (:data:`posekit.viz.meshes.SIDE_COLOURS`), with a key. A ghost pose stays grey, targets
are red crosses.

Only the body is drawn: a helper root such as Bandai's ``joint_Root`` (a point on the floor that carries the
world position, :func:`posekit.data.metrics.body_joints`) is neither a joint nor the end of a bone, so no
"third leg" runs from the pelvis to the floor. A legend never sits on a panel: it goes above the figure, one
for all its panels. Every panel has one scale for x, y and z; panels that are compared share one frame
(:func:`pose_frame`, ``plot_pose(..., frame=...)``) or, in a strip, at least one scale; a strip's panels carry a
scale bar, since they show no tick labels.
"""

from __future__ import annotations

import weakref

import numpy as np

from ..data.metrics import body_joints
from ..skeleton import Skeleton, joint_sides
from .meshes import SIDE_COLOURS

__all__ = ["plot_pose", "plot_strip", "drawn_bones", "pose_frame", "to_mpl", "view_azim", "view_side", "VIEWS",
           "SIDE_LABELS", "SCALE_BAR_M"]

SCALE_BAR_M = 0.5
"""Length of a strip panel's scale bar, metres."""

VIEWS = {"front": 0.0, "front-left": 45.0, "left": 90.0, "back-left": 135.0, "back": 180.0, "back-right": -135.0,
         "right": -90.0, "front-right": -45.0}
"""Named camera sides around a character facing +Z -> matplotlib azimuth, degrees (with :func:`to_mpl`'s mapping)."""

SIDE_LABELS = {1: "left side", -1: "right side", 0: "centre"}
"""The key's entry for each side of the body (+1 left, -1 right, 0 central: :func:`posekit.skeleton.joint_sides`)."""

_ENTRIES = weakref.WeakKeyDictionary()  # axes -> [(label, handle)] given to plot_pose, in drawing order
_KEYS = weakref.WeakKeyDictionary()  # axes -> the sides whose colours its bones show


def to_mpl(p):
    """World points in matplotlib's 3D data coordinates: world ``(x, y, z)`` drawn at ``(z, x, y)``.

    A rotation (a cyclic relabelling of the axes, determinant +1): Y up becomes matplotlib's Z up, and a
    right-handed world stays right-handed (:mod:`posekit.conventions`).

    Parameters
    ----------
    p : array_like, shape (..., 3), metres
        World points.

    Returns
    -------
    tuple of three ndarrays, each shape (...)
        Matplotlib's ``xs, ys, zs`` (world z, x and y).
    """
    p = np.asarray(p, dtype=float)
    return p[..., 2], p[..., 0], p[..., 1]


_to_mpl = to_mpl


def view_azim(side: str) -> float:
    """Matplotlib's azimuth (degrees) of a camera on ``side`` of a character facing +Z.

    Parameters
    ----------
    side : str
        One of :data:`VIEWS`: ``"front"``, ``"front-left"``, ``"left"``, ``"back-left"``, ``"back"``,
        ``"back-right"``, ``"right"``, ``"front-right"`` (the character's own left and right).

    Returns
    -------
    float
        ``azim`` for :func:`plot_pose` / :func:`plot_strip`: the camera's angle from the character's front
        towards its left.
    """
    if side not in VIEWS:
        raise ValueError(f"side: expected one of {', '.join(VIEWS)}, got {side!r}")
    return VIEWS[side]


def view_side(azim: float) -> str:
    """The named side (:data:`VIEWS`) nearest to a camera at azimuth ``azim`` degrees, e.g. 30 -> ``"front-left"``.

    Parameters
    ----------
    azim : float
        Matplotlib's azimuth with :func:`to_mpl`'s mapping, degrees.

    Returns
    -------
    str
        The side of a character facing +Z that the camera looks from.
    """
    gap = {name: abs((float(azim) - a + 180.0) % 360.0 - 180.0) for name, a in VIEWS.items()}
    return min(gap, key=gap.get)


def pose_frame(*points, min_size: float = 0.5):
    """One frame (a cube) around every point given, for panels that are compared: pass it to each panel's
    :func:`plot_pose` (``frame=``) so that all show the same place at the same scale.

    Parameters
    ----------
    *points : array_like, each shape (..., 3), metres
        World points: poses, targets.
    min_size : float
        Smallest edge of the cube, metres (a single point still gets a readable frame).

    Returns
    -------
    centre : ndarray, shape (3,), metres
        The cube's centre, world coordinates.
    half : float
        Half its edge, metres (one scale for x, y and z).
    """
    pts = np.concatenate([np.asarray(p, dtype=float).reshape(-1, 3) for p in points])
    centre = 0.5 * (pts.min(0) + pts.max(0))
    half = 0.5 * max(float(np.ptp(pts, axis=0).max()), float(min_size))
    return centre, half


def _sides(skeleton):
    """Each joint's side (+1 left, -1 right, 0 central), shape (J,), or None when the skeleton's names tell none."""
    if callable(getattr(skeleton, "sides", None)):
        sides = np.asarray(skeleton.sides(), dtype=int)
    elif getattr(skeleton, "names", None) is not None and len(skeleton.names) == skeleton.n_joints:
        sides = joint_sides(skeleton.names)
    else:
        return None
    return sides if np.any(sides != 0) else None


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


def plot_pose(skeleton: Skeleton, global_pos, ax=None, color=None, ghost=None, ghost_color="0.6",
              targets=None, title: str | None = None, elev: float = 12, azim: float = 30,
              joints: bool = True, label: str | None = None, ghost_label: str | None = None,
              target_label: str | None = None, body=None, frame=None):
    """Draw one pose (or several overlaid) as bones and joints on a 3D axes, true to the world's handedness.

    World ``(x, y, z)`` is drawn at matplotlib's ``(z, x, y)`` (:func:`to_mpl`, a rotation: never a mirror image).
    Bones are coloured by side of the body (left blue, right red, centre grey) with a key above the figure.

    Parameters
    ----------
    skeleton : Skeleton
        Or any object with ``parents`` and ``n_joints`` (and ``names``, for the side colours).
    global_pos : ndarray, shape (J, 3) or (K, J, 3), metres
        World positions (:mod:`posekit.conventions`); K poses are overlaid, the last one strongest.
    ax : mpl_toolkits.mplot3d.Axes3D, optional
        Created when not given.
    color : str, optional
        One colour for every bone and joint of the pose; default: colours by side of the body
        (:data:`posekit.viz.meshes.SIDE_COLOURS`), or ``"C0"`` for a skeleton whose names tell no side.
    ghost : ndarray, shape (J, 3), optional
        A second pose drawn in ``ghost_color`` (e.g. the ground truth).
    targets : ndarray, shape (T, 3), optional
        Target markers (red crosses).
    elev, azim : float
        The camera, degrees: ``azim`` is its angle from the front of a character facing +Z towards its left
        (:func:`view_azim`: 0 front, 90 left, 180 behind); the default 30 looks from the front-left.
    label, ghost_label, target_label : str, optional
        Legend entries for the pose, the ghost and the targets. One legend for the whole figure is drawn above
        it (never over a panel), holding every entry given to its panels so far and the side colours' key.
    body : sequence of int, optional
        The joints to draw; default the body joints (a helper root is left out, and so is its bone).
    frame : (ndarray of shape (3,), float), optional
        The panel's cube, world centre and half edge in metres (:func:`pose_frame`): give compared panels the
        same one. Default: a cube around what this panel draws.

    Returns
    -------
    ax
    """
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

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
    sides = _sides(skeleton) if color is None else None
    entries = _ENTRIES.setdefault(ax, [])

    def draw(p, colours, dots, alpha, lw):
        lines = []
        for (a, b), c in zip(bones, colours):
            xs, ys, zs = to_mpl(np.stack([p[a], p[b]]))
            lines += ax.plot(xs, ys, zs, color=c, alpha=alpha, lw=lw)
        if joints:
            ax.scatter(*to_mpl(p[keep]), color=dots, alpha=alpha, s=8, depthshade=False)
        return lines

    if sides is None:
        bone_colours = [color or "C0"] * len(bones)
        joint_colours = [color or "C0"] * len(keep)
    else:
        bone_colours = [SIDE_COLOURS[int(sides[b])] for _, b in bones]
        joint_colours = [SIDE_COLOURS[int(sides[j])] for j in keep]
    if ghost is not None:
        g = np.asarray(ghost, dtype=float).reshape(-1, skeleton.n_joints, 3)
        everything.append(g[:, keep].reshape(-1, 3))
        for k, p in enumerate(g):
            lines = draw(p, [ghost_color] * len(bones), [ghost_color] * len(keep), 0.8, 1.5)
            if k == 0 and ghost_label and lines:
                entries.append((ghost_label, lines[0]))
    for k, p in enumerate(poses):
        lines = draw(p, bone_colours, joint_colours, 1.0 if len(poses) == 1 else 0.35 + 0.65 * (k + 1) / len(poses), 2.0)
        if k == len(poses) - 1 and label and lines:
            if sides is None:
                entries.append((label, lines[0]))
            else:  # the pose's entry shows its side colours side by side
                shown = sorted({int(sides[b]) for _, b in bones}, reverse=True)
                entries.append((label, tuple(Line2D([], [], color=SIDE_COLOURS[s], lw=2.0) for s in shown)))
    if sides is not None and bones:
        _KEYS.setdefault(ax, set()).update(int(sides[b]) for _, b in bones)
    if targets is not None:
        t = np.asarray(targets, dtype=float).reshape(-1, 3)
        everything.append(t)
        crosses = ax.scatter(*to_mpl(t), color="red", marker="x", s=40, depthshade=False)
        if target_label:
            entries.append((target_label, crosses))
    centre, half = pose_frame(*everything) if frame is None else (np.asarray(frame[0], float), float(frame[1]))
    cx, cy, cz = to_mpl(centre)
    ax.set_xlim(cx - half, cx + half)
    ax.set_ylim(cy - half, cy + half)
    ax.set_zlim(cz - half, cz + half)
    ax.set_box_aspect((1, 1, 1))
    from matplotlib.ticker import MaxNLocator

    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):  # few, small ticks: full ones overlap on a 4-inch axes
        axis.set_major_locator(MaxNLocator(3))
    ax.tick_params(labelsize=7, pad=-2)
    ax.set_xlabel("z, forward (m)", fontsize=8, labelpad=-6)  # matplotlib's x, y, z: world z, x, y (to_mpl)
    ax.set_ylabel("x, left (m)", fontsize=8, labelpad=-6)
    ax.set_zlabel("y, up (m)", fontsize=8, labelpad=-6)
    ax.view_init(elev=elev, azim=azim)
    if title:
        ax.set_title(title)
    if entries or _KEYS.get(ax):
        _figure_legend(ax.figure)
    return ax


def _figure_legend(fig) -> None:
    """One legend above the figure for every entry of its axes (replacing an earlier one), then the key of the
    side colours its bones show, so that no legend covers a panel's data."""
    from matplotlib.legend_handler import HandlerTuple
    from matplotlib.lines import Line2D

    entries, keys = {}, set()
    for a in fig.axes:
        for lab, h in _ENTRIES.get(a, []):
            entries.setdefault(lab, h)
        for h, lab in zip(*a.get_legend_handles_labels()):  # anything else a caller labelled
            entries.setdefault(lab, h)
        keys |= _KEYS.get(a, set())
    for s in (1, -1, 0):
        if s in keys:
            entries.setdefault(SIDE_LABELS[s], Line2D([], [], color=SIDE_COLOURS[s], lw=2.0))
    for old in list(fig.legends):
        old.remove()
    if not entries:
        return
    width_in = fig.get_size_inches()[0]
    ncol = len(entries) if 1.3 * len(entries) <= width_in else max(1, int(width_in // 1.3))
    fig.legend(list(entries.values()), list(entries), loc="lower center", bbox_to_anchor=(0.5, 1.0),
               ncol=ncol, fontsize=8, frameon=False, handlelength=1.5,
               handler_map={tuple: HandlerTuple(ndivide=None, pad=0.0)})


def _scale_bar(ax, length: float = SCALE_BAR_M) -> None:
    """A vertical bar of ``length`` metres at the floor corner of the panel's cube that is nearest the viewer on
    the image's left (from the default front-left camera: the front of the cube, at the character's right),
    labelled."""
    a = np.radians(ax.azim)
    towards_camera = np.array([np.cos(a), np.sin(a)])  # matplotlib's x, y of the camera's direction
    image_right = np.array([-np.sin(a), np.cos(a)])
    near_left = towards_camera - image_right
    (x_lo, x_hi), (y_lo, y_hi) = ax.get_xlim(), ax.get_ylim()
    x0 = x_hi if near_left[0] > 0 else x_lo
    y0 = y_hi if near_left[1] > 0 else y_lo
    z0 = ax.get_zlim()[0]
    ax.plot([x0, x0], [y0, y0], [z0, z0 + length], color="k", lw=2.5, solid_capstyle="butt")
    ax.text(x0, y0, z0 + 0.5 * length, f" {length:g} m", fontsize=7, ha="left", va="center")


def plot_strip(skeleton: Skeleton, poses, titles=None, elev: float = 12, azim: float = 30, size: float = 2.6,
               scale_m: float = SCALE_BAR_M, frame: str = "scale"):
    """A row of poses, each on its own 3D axes (a tour of clips, the frames of a motion), each with a scale bar.

    Every panel has the same scale (:func:`pose_frame`'s largest cube), so sizes compare across the row.

    Parameters
    ----------
    skeleton : Skeleton
    poses : ndarray, shape (K, J, 3), metres
        World positions (:mod:`posekit.conventions`).
    titles : list of str, optional
    elev, azim : float
        The camera, degrees (:func:`plot_pose`; default: from the front-left of a character facing +Z).
    size : float
        Width of a panel, inches.
    scale_m : float
        Length of every panel's scale bar (a black vertical bar at the floor corner nearest the viewer on the
        image's left), metres.
    frame : {"scale", "shared"}
        ``"scale"``: one scale, each panel centred on its own pose (poses far apart, e.g. different clips);
        ``"shared"``: one frame for all, so that a pose that moves is seen moving (the frames of one motion).

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    poses = np.asarray(poses, dtype=float)
    if frame not in ("scale", "shared"):
        raise ValueError(f"frame: expected 'scale' or 'shared', got {frame!r}")
    keep = _body(skeleton)
    frames = [pose_frame(p[keep]) for p in poses]
    if frame == "shared":
        frames = [pose_frame(poses[:, keep])] * len(poses)
    else:
        half = max(h for _, h in frames)
        frames = [(c, half) for c, _ in frames]
    # room above the panels for titles of several lines, so that the key above the figure covers none of them
    lines = max((str(t).count("\n") + 1 for t in titles), default=0) if titles is not None else 0
    line_in = 0.18  # one line of a 9-point title, inches
    height = size + 0.4 + line_in * lines
    fig = plt.figure(figsize=(size * len(poses), height))
    for k, p in enumerate(poses):
        ax = fig.add_subplot(1, len(poses), k + 1, projection="3d")
        plot_pose(skeleton, p, ax=ax, elev=elev, azim=azim, frame=frames[k])
        if titles is not None:
            ax.set_title(titles[k], fontsize=9)
        ax.set_xticklabels([])  # a strip shows shapes: numbers and axis names on every small panel only crowd it
        ax.set_yticklabels([])
        ax.set_zticklabels([])
        ax.set_xlabel("")
        ax.set_ylabel("")
        ax.set_zlabel("")
        _scale_bar(ax, scale_m)
    # tight_layout cannot measure 3D axes; fixed margins keep every panel whole
    fig.subplots_adjust(left=0.0, right=1.0, bottom=0.08, top=1.0 - (line_in * lines + 0.05) / height, wspace=0.02)
    framing = "one frame for every panel" if frame == "shared" else "one scale in every panel, each centred on its pose"
    fig.text(0.5, 0.01, f"seen from the {view_side(azim)} of a character facing +z; {framing} (y up); "
             f"black bar: {scale_m:g} m", ha="center", fontsize=8, color="0.35")
    return fig

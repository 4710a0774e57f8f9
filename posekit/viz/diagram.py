"""Block diagrams of the learned networks, drawn from a model's own sizes (never a picture kept by hand).

Introduced in ``notebooks/05_protores.ipynb`` (section 3), where :func:`draw_protores` draws ProtoRes (Oreshkin
et al. 2022, Fig. 2) from the shipped network's :class:`~posekit.models.protores.blocks.ProtoResConfig`, so the
figure states the sizes the lesson actually runs. The lecture deck (:mod:`posekit.course.lecture`) shows it as
the lesson's architecture slide.
"""

from __future__ import annotations

__all__ = ["draw_protores"]

_FILL = {"input": "#e8eef7", "encoder": "#fde9d9", "code": "#f2f2f2", "decoder": "#e6f2e6", "fk": "#efe6f5"}


def _box(ax, x, y, w, h, title, lines, kind):
    from matplotlib.patches import FancyBboxPatch

    ax.add_patch(FancyBboxPatch((x, y), w, h, boxstyle="round,pad=0.01,rounding_size=0.04",
                                fc=_FILL[kind], ec="0.35", lw=1.0))
    ax.text(x + w / 2, y + h - 0.07, title, ha="center", va="top", fontsize=10.5, weight="bold")
    ax.text(x + w / 2, y + h - 0.25, "\n".join(lines), ha="center", va="top", fontsize=8.6, linespacing=1.35)


def _arrow(ax, a, b, label=None, rad=0.0):
    ax.annotate("", xy=b, xytext=a, arrowprops=dict(arrowstyle="-|>", lw=1.2, color="0.25", shrinkA=0, shrinkB=0,
                                                    connectionstyle=f"arc3,rad={rad}"))
    if label:
        ax.text((a[0] + b[0]) / 2, (a[1] + b[1]) / 2 + 0.05, label, ha="center", va="bottom", fontsize=8.2,
                color="0.2")


def draw_protores(config, n_effectors: int = 5, ax=None):
    """Draw ProtoRes as blocks: effector tokens -> proto-residual encoder -> pose code -> GPD -> IKD -> FK.

    Every size printed in the figure is read from ``config`` (Sec. 2 and Fig. 2 of Oreshkin et al. 2022;
    the encoder's update is Eq. 2, the decoders Eq. 3-5, FK Eq. 6).

    Parameters
    ----------
    config : ProtoResConfig
        The network's sizes (``net.config``); its ``arch`` must be ``"protores"``.
    n_effectors : int
        N, the effectors of the request drawn (the network takes any N >= 1).
    ax : matplotlib Axes, optional
        Drawn into; a new 12 x 3.4 inch figure when absent.

    Returns
    -------
    matplotlib Axes
    """
    import matplotlib.pyplot as plt

    if getattr(config, "arch", None) != "protores":
        raise ValueError(f"draw_protores draws the proto-residual network: expected a config with arch "
                         f"'protores', got {getattr(config, 'arch', None)!r}")
    if int(n_effectors) < 1:
        raise ValueError(f"n_effectors: expected at least 1 effector, got {n_effectors}")
    if ax is None:
        _, ax = plt.subplots(figsize=(12, 3.4))
    from matplotlib.patches import Circle, Rectangle

    N, B, W, R, L = int(n_effectors), config.n_joints, config.width, config.blocks, config.layers
    ax.set_xlim(0, 12.0)
    ax.set_ylim(0, 3.4)
    ax.axis("off")
    y, h = 0.45, 2.55
    mid = y + h / 2
    # the set: one row per effector token, cut into its parts (values, tolerance, two embeddings)
    _box(ax, 0.1, y, 2.1, h, f"{N} effector tokens", [f"{config.n_in} numbers each"], "input")
    parts = [(6, "#9bb7de", ""), (1, "#e0a458", ""), (config.embed, "#b9d7a8", "joint"),
             (config.embed, "#d7b9e0", "kind")]
    total = sum(n for n, _, _ in parts)
    rows = min(N, 6)
    top, step = y + h - 0.78, min(0.27, 1.3 / rows)
    for k in range(rows):
        x0 = 0.25
        for n, colour, _ in parts:
            w = 1.8 * n / total
            ax.add_patch(Rectangle((x0, top - k * step), w, step * 0.7, fc=colour, ec="0.4", lw=0.5))
            x0 += w
    x0 = 0.25
    for n, _, label in parts:
        w = 1.8 * n / total
        ax.text(x0 + w / 2, top - rows * step + 0.12, label, ha="center", va="top", fontsize=7.2)
        x0 += w
    ax.text(0.22, top - rows * step + 0.12, "$v$, $\\Lambda$", ha="left", va="top", fontsize=7.2)
    ax.text(1.15, y + 0.08, "any N, any order", ha="center", fontsize=8.2, style="italic")
    # the encoder: R blocks in a row, each followed by the mean over the set
    _box(ax, 2.55, y, 3.35, h, "proto-residual encoder (Eq. 2)", [], "encoder")
    bw, gap = 0.62, 0.42
    for r in range(R):
        bx = 2.72 + r * (bw + gap)
        ax.add_patch(Rectangle((bx, mid - 0.35), bw, 0.95, fc="white", ec="0.35", lw=0.9))
        ax.text(bx + bw / 2, mid + 0.12, f"block\n{r + 1}", ha="center", va="center", fontsize=8)
        ax.add_patch(Circle((bx + bw / 2, mid - 0.72), 0.16, fc="white", ec="0.35", lw=0.9))
        ax.text(bx + bw / 2, mid - 0.72, "$\\mu$", ha="center", va="center", fontsize=8.5)
        _arrow(ax, (bx + bw / 2, mid - 0.35), (bx + bw / 2, mid - 0.56))
        ax.text(bx + bw / 2 + 0.2, mid - 0.72, f"$p_{r + 1}$", ha="left", va="center", fontsize=8)
        if r < R - 1:
            _arrow(ax, (bx + bw, mid + 0.12), (bx + bw + gap, mid + 0.12))
            ax.text(bx + bw + gap / 2, mid + 0.2, "$-p/r$", ha="center", va="bottom", fontsize=7)
    ax.text(4.22, y + 0.08, f"a block: {L} layers of {W}, on every token\n$\\mu$: the mean over the set",
            ha="center", fontsize=7.6)
    _box(ax, 6.2, y + 0.65, 1.05, h - 1.3, "code", [f"$p_{{{R}}}$", f"{W}"], "code")
    _box(ax, 7.6, y + 1.4, 2.0, 1.15, "GPD (Eq. 3)", [f"{R} blocks", f"-> {B} x 3 positions"], "decoder")
    _box(ax, 7.6, y, 2.0, 1.15, "IKD (Eq. 4-5)", [f"{R} blocks", f"-> {B} x 6 rotations (6D)"], "decoder")
    _box(ax, 9.95, y, 1.95, h, "FK (Eq. 6)", ["local rotations,", "rooted at the", "GPD's pelvis:", "a world pose",
                                              "whose bones keep", "their lengths"], "fk")
    _arrow(ax, (2.2, mid), (2.55, mid))
    _arrow(ax, (5.9, mid), (6.2, mid))
    _arrow(ax, (7.25, mid + 0.25), (7.6, y + 1.95))
    _arrow(ax, (7.25, mid - 0.25), (7.6, y + 0.6))
    _arrow(ax, (8.6, y + 1.4), (8.6, y + 1.15))
    ax.text(8.68, y + 1.27, "pose", fontsize=7.6, va="center", color="0.2")
    _arrow(ax, (9.6, y + 0.6), (9.95, y + 0.6))
    _arrow(ax, (9.6, y + 1.95), (9.95, y + 1.95))
    ax.text(9.78, y + 2.0, "pelvis", fontsize=7.2, ha="center", va="bottom", color="0.2")
    ax.text(6.0, 0.08, f"width {W}, {B} body joints. The Masked-FCR and Transformer baselines keep the code, "
                       "both decoders and FK: only the encoder differs.", ha="center", fontsize=8.4, color="0.3")
    return ax

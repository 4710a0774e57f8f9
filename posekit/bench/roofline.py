"""A network's speed against what the machine's arithmetic allows: multiply-adds, GEMM rate, ideal poses/s.

Introduced in ``notebooks/05_protores.ipynb`` (speed); ``posekit bench protores`` prints one row per network.
A pose through a :class:`~posekit.models.protores.networks.PosingNet` is, for its arithmetic, a list of matrix
products fixed by the layer sizes and the number of effectors N:

* per-effector layers (the ProtoRes encoder's blocks, the Transformer's token projections) are ``N`` rows
  times ``(in, out)``; per-pose layers (the GPD and IKD decoders, the Masked-FCR encoder) one row;
* attention adds ``heads`` products of ``(queries, d_head) x (d_head, keys)`` and back.

:func:`gemm_shapes` lists them, :func:`macs_per_pose` sums them (one multiply-add per weight per row:
biases, activations, Gram-Schmidt and FK are not counted; they are cheap beside the products but not free).
:func:`gemm_rate` times the *same* products, for a batch of poses, on one thread: that is the machine's
float32 multiply-add rate on this network's own shapes, and ``rate / macs_per_pose`` the poses per second the
network would reach if it did nothing but its arithmetic — the roofline. A measured rate far below it says
time goes elsewhere (per-call overhead, memory traffic, small matrices); a goal above it cannot be met on this
machine by any implementation of the same network.
"""

from __future__ import annotations

import time

import numpy as np

__all__ = ["gemm_shapes", "macs_per_pose", "gemm_rate", "weight_bytes", "CLOCK"]


def _fc_block(n_in: int, width: int, layers: int, n_out: int, rows: int) -> list[tuple]:
    """The products of one :class:`~posekit.models.protores.blocks.FCBlock` on ``rows`` rows."""
    out = [(1, rows, n_in if i == 0 else width, width) for i in range(layers)]
    return out + [(1, rows, n_in, width), (1, rows, width, n_out)]  # skip (backcast) and forecast


def _fcr(n_in: int, n_out: int, width: int, blocks: int, layers: int, rows: int) -> list[tuple]:
    out = []
    for r in range(blocks):
        out += _fc_block(n_in if r == 0 else width, width, layers, n_out, rows)
    return out


def _attention(d: int, heads: int, n_q: int, n_k: int, poses: int) -> list[tuple]:
    """``nn.MultiheadAttention``: Q from the queries, K and V from the keys, per-head scores and values, out."""
    dh = d // heads
    out = [(1, poses * n_q, d, d), (1, poses * n_k, d, d), (1, poses * n_k, d, d)]
    out += [(poses * heads, n_q, dh, n_k), (poses * heads, n_q, n_k, dh)]
    return out + [(1, poses * n_q, d, d)]


def gemm_shapes(config, n_effectors: int, poses: int = 1) -> list[tuple[int, int, int, int]]:
    """The matrix products of one pass of a network of ``config`` on ``poses`` poses of ``n_effectors`` each.

    Parameters
    ----------
    config : ProtoResConfig
        The network's sizes (:class:`~posekit.models.protores.blocks.ProtoResConfig`).
    n_effectors : int
        Effectors per pose (N): the number of tokens of the ProtoRes and Transformer encoders.
    poses : int
        Poses in the batch.

    Returns
    -------
    list of (count, m, k, n)
        ``count`` independent products of an (m, k) by a (k, n) matrix: ``count * m * k * n`` multiply-adds.
    """
    if n_effectors < 1 or poses < 1:
        raise ValueError(f"n_effectors and poses must be at least 1, got {n_effectors} and {poses}")
    c, N, P, w = config, int(n_effectors), int(poses), config.width
    J = c.n_joints
    shapes: list[tuple] = []
    if c.arch == "protores":  # Eq. 2: every block on every effector's token
        for r in range(c.blocks):
            shapes += _fc_block(c.n_in if r == 0 else w, w, c.layers, w, P * N)
    elif c.arch == "masked-fcr":  # one row: the (kinds, joints, 7) table flattened
        shapes += _fcr(3 * J * 7, w, w, c.blocks, c.layers, P)
    elif c.arch == "transformer":
        d, h = c.d_model, c.heads
        shapes.append((1, P * N, c.n_in, d))          # tokens -> d_model (the queries are embeddings: no product)
        for _ in range(c.enc_layers):                 # self-attention over the N tokens, feed-forward
            shapes += _attention(d, h, N, N, P) + [(1, P * N, d, 4 * d), (1, P * N, 4 * d, d)]
        for _ in range(c.dec_layers):                 # the J joint queries: self-, cross-attention, feed-forward
            shapes += _attention(d, h, J, J, P) + _attention(d, h, J, N, P)
            shapes += [(1, P * J, d, 4 * d), (1, P * J, 4 * d, d)]
        shapes.append((1, P, J * d, w))               # flattened joints -> code
    else:
        raise ValueError(f"unknown arch {c.arch!r}")
    code = w
    if c.gpd:  # Eq. 3, then Eq. 4 reads the code and the GPD's positions
        shapes += _fcr(code, 3 * J, w, c.blocks, c.layers, P)
        shapes += _fcr(code + 3 * J, 6 * J, w, c.blocks, c.layers, P)
    else:
        shapes += _fcr(code, 6 * J + 3, w, 2 * c.blocks, c.layers, P)
    return shapes


def macs_per_pose(config, n_effectors: int) -> int:
    """Multiply-adds of one pose's pass (:func:`gemm_shapes`, summed): biases, activations and FK not counted."""
    return int(sum(n * m * k * q for n, m, k, q in gemm_shapes(config, n_effectors)))


def weight_bytes(config, n_effectors: int) -> int:
    """Bytes of float32 weights the products of one pass read (attention's products have no weights)."""
    return int(4 * sum(k * q for n, m, k, q in gemm_shapes(config, n_effectors) if n == 1))


def _products(shapes, seed: int = 0):
    import torch

    g = torch.Generator().manual_seed(seed)
    ops = []
    for n, m, k, q in shapes:
        if n == 1:
            ops.append((torch.mm, torch.rand(m, k, generator=g), torch.rand(k, q, generator=g), torch.empty(m, q)))
        else:
            ops.append((torch.bmm, torch.rand(n, m, k, generator=g), torch.rand(n, k, q, generator=g),
                        torch.empty(n, m, q)))
    return ops


CLOCK = time.thread_time
"""The clock of every timing here: the calling thread's CPU time. On a machine shared with other work the wall
clock also counts the time others held the core; the thread's own time is what this thread's arithmetic took."""


def _run_products(ops) -> float:
    t = CLOCK()
    for fn, a, b, o in ops:
        fn(a, b, out=o)
    return CLOCK() - t


def gemm_rate(shapes, rounds: int = 7, seed: int = 0, between=None) -> dict:
    """The machine's float32 multiply-add rate on ``shapes``, on the calling thread's torch setting.

    Every product of ``shapes`` is run once per round on random float32 matrices made beforehand (no
    allocation in the timed loop: ``torch.mm`` / ``torch.bmm`` into preallocated outputs); the time of a round
    is the sum, in the thread's CPU time (:data:`CLOCK`). Call it inside :func:`posekit.learn.threads.limit_threads` for a one-thread rate.

    Parameters
    ----------
    shapes : list of (count, m, k, n)
        :func:`gemm_shapes` (usually of a batch of poses).
    rounds : int
        Timed rounds after one untimed warm-up.
    between : callable, optional
        Called after each round and timed too (``between() -> seconds``): the network's own pass, so that
        both medians see the same load on a shared machine.

    Returns
    -------
    dict
        ``macs`` (per round), ``seconds_median`` (of a round), ``macs_per_s`` (``macs / seconds_median``);
        with ``between``, ``between_median`` (seconds).
    """
    import torch

    ops = _products(shapes, seed)
    macs = int(sum(n * m * k * q for n, m, k, q in shapes))
    times, other = [], []
    with torch.no_grad():
        _run_products(ops)
        if between is not None:
            between()
        for _ in range(rounds):
            times.append(_run_products(ops))
            if between is not None:
                other.append(float(between()))
    sec = float(np.median(times))
    out = {"macs": macs, "seconds_median": sec, "macs_per_s": macs / sec}
    if between is not None:
        out["between_median"] = float(np.median(other))
    return out

"""The AE-GAN's encoder and generator in numpy float32, read from its checkpoint without torch.

Introduced in ``notebooks/04_aegan_latent_space.ipynb``: latent optimisation calls the generator and its
gradient every iteration, and torch's per-call cost, not arithmetic, sets the time for one pose.
:class:`NumpySPL` is the structured prediction layer (:mod:`posekit.models.aegan.spl`, Aksan et al. 2019,
Eq. 4) with a hand-written backward pass; :class:`NumpyAEGAN` is ``E(x) = tanh(W spl(x) + b)`` and
``G(z) = spl(relu(W z + b))`` (Victor & Meyer 2020, Sec. 3.2) with ``vjp``. :meth:`NumpyAEGAN.load` reads the
weights with :func:`posekit.learn.checkpoint.load_checkpoint` (``arrays=True``), so a process that only poses
(the studio's kernel) never imports torch. Tested equal to the torch networks to float32 rounding.
"""

from __future__ import annotations

import numpy as np

from ...data.metrics import body_joints

__all__ = ["KIND", "WEIGHTS", "weights_path", "body_parents", "tree_levels", "NumpySPL", "NumpyAEGAN"]

KIND = "aegan"

WEIGHTS = "aegan.pt"
"""File name of the shipped weights in ``data_samples/weights/``."""


def weights_path(folder=None):
    """The weights' file, :data:`WEIGHTS` in ``folder`` or the shipped weights' folder
    (:func:`posekit.paths.weights_path`)."""
    from ... import paths

    return paths.weights_path(WEIGHTS, folder)


def body_parents(skeleton) -> np.ndarray:
    """The body-joint tree: for each body joint (:func:`~posekit.data.metrics.body_joints`, in order), the
    position of its parent among them, -1 for the pelvis (a helper root above it is not a body joint)."""
    b = [int(j) for j in body_joints(skeleton)]
    return np.array([b.index(int(skeleton.parents[j])) if int(skeleton.parents[j]) in b else -1 for j in b],
                    dtype=np.int64)


def tree_levels(parents, ancestors: str = "parent"):
    """Joints grouped by depth, with the ancestors each one reads.

    Parameters
    ----------
    parents : sequence of int, length J
        Parent of each joint, -1 for a root (several roots are fine); any order.
    ancestors : {"parent", "all"}

    Returns
    -------
    levels : list of (joints (n,), ancestors (n, a)) int arrays
        Depth 0 first; ``a`` is 0 at the roots, then 1 (parent) or the depth (all, nearest first).
    """
    if ancestors not in ("parent", "all"):
        raise ValueError(f"ancestors must be 'parent' or 'all', got {ancestors!r}")
    parents = [int(p) for p in parents]
    n = len(parents)
    chains = []
    for j in range(n):
        chain, k = [], parents[j]
        while k >= 0:
            if k >= n or k == j or k in chain:
                raise ValueError(f"parents: joint {j} has no root above it (a cycle or an index out of range)")
            chain.append(k)
            k = parents[k]
        chains.append(chain)
    depth = [len(c) for c in chains]
    levels = []
    for d in range(max(depth) + 1):
        js = [j for j in range(n) if depth[j] == d]
        anc = [chains[j][: (1 if ancestors == "parent" else d)] for j in js]
        levels.append((np.array(js, dtype=np.int64), np.array(anc, dtype=np.int64).reshape(len(js), -1)))
    return levels


class NumpySPL:
    """:class:`~posekit.models.aegan.spl.StructuredPrediction` in numpy float32, forward and backward, on (N, in)
    batches.

    The layout inside is joint-major, ``(J, N, .)``, so each depth is one batched ``matmul``. ``dtype``
    (:meth:`from_state`): float32, or float64 for the encoder (:meth:`NumpyAEGAN.encode`).
    """

    dtype = np.float32

    def __init__(self, layer):
        state = {k: v.detach().cpu().numpy() for k, v in layer.state_dict().items()}
        self._build(state, layer.parents, layer.out, layer.hidden, layer.ancestors)

    @classmethod
    def from_state(cls, state: dict, parents, out: int, hidden: int, ancestors: str = "parent",
                   dtype=np.float32) -> "NumpySPL":
        """The layer from a :class:`~posekit.models.aegan.spl.StructuredPrediction`'s state dict (name -> array:
        ``shared.weight``, ``shared.bias``, ``anc.i``, ``w_out.i``, ``b_out.i``) and its sizes, computing in
        ``dtype``."""
        self = cls.__new__(cls)
        self.dtype = np.dtype(dtype).type
        self._build(state, parents, out, hidden, ancestors)
        return self

    def _build(self, state, parents, out, hidden, ancestors):
        f32 = lambda name: np.asarray(state[name]).astype(self.dtype).copy()  # noqa: E731
        levels = tree_levels(parents, ancestors)
        if f"anc.{len(levels)}" in state:
            raise KeyError(f"anc.{len(levels)} (the tree has {len(levels)} depths)")
        self.J, self.out, self.hidden = len(parents), int(out), int(hidden)
        self.U = f32("shared.weight").T.copy()  # (in, J hidden): every joint's U_j side by side
        self.c = f32("shared.bias")
        self.levels = []
        for i, (js, anc) in enumerate(levels):
            A, V, b = f32(f"anc.{i}"), f32(f"w_out.{i}"), f32(f"b_out.{i}")
            flat = anc.reshape(-1)
            uniq = np.unique(flat)
            # sums the gradients of (joint, ancestor) pairs into each distinct ancestor: (n_uniq, n * a)
            S = (uniq[:, None] == flat[None, :]).astype(self.dtype)
            self.levels.append((js, anc, A, V, b[:, None, :], uniq, S))

    def forward(self, h):
        """``h`` (N, in) -> (N, J * out) and the cache :meth:`backward` needs."""
        h = np.asarray(h, dtype=self.dtype)
        n = h.shape[0]
        a = (h @ self.U + self.c).reshape(n, self.J, self.hidden).transpose(1, 0, 2)  # (J, N, hidden)
        outs = np.zeros((self.J, n, self.out), self.dtype)
        acts = []
        for js, anc, A, V, b, _, _ in self.levels:
            pre = a[js]
            p = None
            if anc.shape[1]:
                p = outs[anc].transpose(0, 2, 1, 3).reshape(len(js), n, -1)  # (n_l, N, a * out)
                pre = pre + np.matmul(p, A)
            r = np.maximum(pre, 0.0)
            outs[js] = np.matmul(r, V) + b
            acts.append((r, p))
        return outs.transpose(1, 0, 2).reshape(n, -1), (h, acts)

    def backward(self, cache, grad_out):
        """The gradient with respect to the input, (N, in), of a loss whose gradient with respect to
        the output is ``grad_out`` (N, J * out)."""
        h, acts = cache
        n = h.shape[0]
        g_out = np.asarray(grad_out, np.float32).reshape(n, self.J, self.out).transpose(1, 0, 2).copy()
        g_a = np.zeros((self.J, n, self.hidden), np.float32)
        for (js, anc, A, V, _, uniq, S), (r, p) in zip(reversed(self.levels), reversed(acts)):
            g_pre = np.matmul(g_out[js], V.transpose(0, 2, 1)) * (r > 0)  # (n_l, N, hidden)
            g_a[js] = g_pre
            if anc.shape[1]:  # into the ancestors' outputs (deeper levels are done: their sums are complete)
                g_p = np.matmul(g_pre, A.transpose(0, 2, 1)).reshape(len(js), n, anc.shape[1], self.out)
                g_p = g_p.transpose(0, 2, 1, 3).reshape(len(js) * anc.shape[1], n * self.out)
                g_out[uniq] += (S @ g_p).reshape(len(uniq), n, self.out)
        return g_a.transpose(1, 0, 2).reshape(n, -1) @ self.U.T


class NumpyAEGAN:
    """The AE-GAN's encoder and the generator in numpy float32, with the generator's gradient: :meth:`encode`,
    :meth:`forward` and :meth:`vjp` (the gradient of a loss on the output back to ``z``) on (N, .)
    batches — what latent optimisation calls every iteration, without torch's per-call cost."""

    def __init__(self, model):
        state = {f"{k}.{n}": v.detach().cpu().numpy() for k in ("encoder", "generator")
                 for n, v in getattr(model, k).state_dict().items()}
        self._build(state, model.config.to_dict(), model.skeleton)
        self.norm, self.x_range, self.info = model.norm, model.x_range, model.info

    @classmethod
    def load(cls, path, skeleton=None) -> "NumpyAEGAN":
        """The encoder and generator of an :meth:`AEGAN.save <posekit.models.aegan.networks.AEGAN.save>` file,
        read without torch, with its ``norm``, ``x_range``, ``config`` (a dict) and ``skeleton``; with
        ``skeleton`` it must be the one the weights were made for, else a ``ValueError`` names the difference."""
        from ...learn.checkpoint import load_checkpoint

        ck = load_checkpoint(path, kind=KIND, skeleton=skeleton, arrays=True)
        if "pose" not in ck["norms"]:
            raise ValueError(f"checkpoint {path} has no pose normalisation")
        self = cls.__new__(cls)
        try:
            self._build(ck["state"], ck["config"], ck["skeleton"])
        except KeyError as err:
            raise ValueError(f"checkpoint {path}: the encoder or generator does not match its config (missing or "
                             f"extra {err})") from None
        self.norm, self.x_range = ck["norms"]["pose"], ck["extra"].get("x_range")
        self.info = {k: ck[k] for k in ("command", "seed", "data", "licence", "path")} | {"extra": ck["extra"]}
        return self

    def _build(self, state, config: dict, skeleton):
        if not config.get("structured", True):
            raise ValueError("NumpyAEGAN needs the SPL networks (config.structured = True)")
        self.config, self.skeleton = dict(config), skeleton
        parents = body_parents(skeleton)
        hidden, ancestors, per_joint = int(config["spl_hidden"]), config["ancestors"], int(config["per_joint"])
        f32 = lambda name: np.asarray(state[name]).astype(np.float32).copy()  # noqa: E731
        part = lambda k: {n[len(k) + 1:]: v for n, v in state.items() if n.startswith(k + ".")}  # noqa: E731
        # the encoder in float64: its code, rounded to float32, is then the same on every CPU (a float32 product's
        # last bit depends on the BLAS kernel the CPU picks, and latent optimisation from it magnifies that bit)
        self.e_spl = NumpySPL.from_state(part("encoder.spl"), parents, per_joint, hidden, ancestors, dtype=np.float64)
        f64 = lambda name: np.asarray(state[name]).astype(np.float64).copy()  # noqa: E731
        self.e_W, self.e_b = f64("encoder.fc.weight").T.copy(), f64("encoder.fc.bias")
        self.g_W, self.g_b = f32("generator.fc.weight").T.copy(), f32("generator.fc.bias")
        self.g_spl = NumpySPL.from_state(part("generator.spl"), parents, 3, hidden, ancestors)
        self._sizes = {k: sum(int(np.asarray(v).size) for n, v in state.items() if n.startswith(k + "."))
                       for k in ("encoder", "generator")}

    def n_parameters(self, name: str) -> int:
        """Weights of ``"encoder"`` or ``"generator"`` (the torch networks' counts)."""
        return self._sizes[name]

    def encode(self, x):
        """z-scored poses (N, 3 B) -> codes (N, d), float32 (computed in float64, then rounded)."""
        h = np.maximum(self.e_spl.forward(np.asarray(x, np.float64))[0], 0.0)
        return np.tanh(h @ self.e_W + self.e_b).astype(np.float32)

    def forward(self, z):
        """Codes (N, d) -> z-scored poses (N, 3 B), and the cache for :meth:`vjp`."""
        h = np.maximum(np.asarray(z, np.float32) @ self.g_W + self.g_b, 0.0)
        x, cache = self.g_spl.forward(h)
        return x, (h, cache)

    def vjp(self, cache, grad_x):
        """d loss / d z (N, d) from d loss / d x (N, 3 B)."""
        h, spl_cache = cache
        g_h = self.g_spl.backward(spl_cache, grad_x) * (h > 0)
        return g_h @ self.g_W.T

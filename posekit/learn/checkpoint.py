"""Checkpoints: the weights of a learned model next to everything needed to rebuild and trust it.

Introduced in ``notebooks/02_inverse_rig_mapping.ipynb`` (the inverse-rig network); the learned
solvers of lessons 03-05 save and load through the same two functions.

A checkpoint is one ``torch.save`` file holding a plain dict (nanoGPT style)::

    format    "posekit-checkpoint"          version   FORMAT_VERSION (int)
    kind      "invrig_nn", ...              config    the model's arguments (plain Python values)
    state     {name: tensor}                half      True: floating weights stored as float16
    skeleton  {"name", "roles", "names", "parents", "offsets"} or None  (offsets (J, 3) float64, metres)
    norms     {name: {"mean": tensor, "std": tensor}}           (:class:`~posekit.records.NormStats`)
    command   the command that made it      seed      its seed
    data      data provenance               licence   the licence of what went in
    extra     anything else (plain values, tensors, numpy arrays)
    torch     torch version that wrote it

Only tensors and plain Python values (dict, list, str, int, float, bool, None) are stored, so the
file loads with ``torch.load(..., weights_only=True)``: reading a checkpoint runs no pickled code.
:func:`load_checkpoint` reads it without torch (:func:`posekit.io.torch_file.read_torch_file`, which
refuses anything else likewise) and gives the weights as tensors, or as numpy arrays with ``arrays=True``
for the numpy inference paths, which then never import torch.
numpy arrays in ``config`` / ``extra`` are stored as tensors and come back as numpy arrays; tuples
come back as lists.

Loading refuses a checkpoint made for something else with a sentence that names the field: the
kind, the format version, the skeleton's joint names, parents or offsets, a normalisation, or a
config field.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..io.torch_file import read_torch_file
from ..records import NormStats
from ..skeleton import Skeleton, joint_set_difference

__all__ = ["FORMAT", "FORMAT_VERSION", "save_checkpoint", "load_checkpoint"]

FORMAT = "posekit-checkpoint"
FORMAT_VERSION = 1
_ARRAY = "__ndarray__"  # marks a numpy array stored as a tensor, so it comes back as numpy
_OFFSET_ATOL = 1e-6  # metres: offsets read back from float32 files still match


def _plain(value, where: str):
    """``value`` as tensors and plain Python types only (what ``weights_only=True`` loads)."""
    import torch

    if value is None:
        return None
    for t in (bool, int, float, str):  # exact types: a subclass (TorchVersion, IntEnum) would not load
        if isinstance(value, t):
            return t(value)
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        if value.dtype == object or value.dtype.kind in "USV":
            return [_plain(v, where) for v in value.tolist()]
        return {_ARRAY: torch.from_numpy(np.array(value))}
    if isinstance(value, torch.Tensor):
        return value.detach().cpu().clone()
    if isinstance(value, dict):
        for k in value:
            if not isinstance(k, str):
                raise TypeError(f"{where}: keys must be strings, got {k!r}")
        return {str(k): _plain(v, f"{where}[{k!r}]") for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v, f"{where}[{i}]") for i, v in enumerate(value)]
    raise TypeError(f"{where}: cannot store a {type(value).__name__} in a checkpoint; use plain Python "
                    "values (dict, list, str, int, float, bool, None), numpy arrays or tensors")


def _unplain(value):
    if isinstance(value, dict):
        if set(value) == {_ARRAY}:
            return np.asarray(value[_ARRAY])
        return {k: _unplain(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_unplain(v) for v in value]
    return value


def save_checkpoint(path, model_state, *, kind: str, config: dict, skeleton: Skeleton | None = None,
                    norms: dict | None = None, command: str = "", seed: int | None = None, data: str = "",
                    licence: str = "", extra: dict | None = None, half: bool = False) -> Path:
    """Write a model's weights with its config, skeleton, normalisation and provenance.

    Parameters
    ----------
    path : str or Path
        Target file (``.pt``); its folder is created. Written to a temporary file first, then
        renamed, so an interrupted save never leaves half a checkpoint.
    model_state : dict of str -> Tensor, or torch.nn.Module
        The weights (a module's ``state_dict()`` is taken).
    kind : str
        What model this is (``"invrig_nn"``); :func:`load_checkpoint` can require it.
    config : dict
        The model's arguments (``hidden``, ``n_in``, ...), plain Python values, so that loading
        rebuilds the exact model.
    skeleton : Skeleton, optional
        The skeleton the model was trained for; its joint names, parents and offsets (metres) are
        stored and checked on load (its name and roles are stored too).
    norms : dict of str -> NormStats, optional
        Named normalisations (``{"x": ..., "y": ...}``), stored as float64.
    command : str
        The command that makes this file (``"posekit train invrig --methods pca ..."``). Saved under torchrun,
        a ``posekit ...`` command is stored with the launcher in front (``torchrun --nproc-per-node 2 -m
        posekit ...``): each process trains on its own share of every batch, so one process does not remake
        the file.
    seed : int, optional
    data : str
        Provenance of the training data.
    licence : str
        Licence of the data (and so of the weights).
    extra : dict, optional
        Anything else: plain values, numpy arrays, tensors.
    half : bool
        Store floating weights as float16 (half the size; :func:`load_checkpoint` returns float32).

    Returns
    -------
    Path
    """
    import torch

    if not kind or not isinstance(kind, str):
        raise ValueError("save_checkpoint: kind must be a non-empty string such as 'invrig_nn'")
    if not isinstance(config, dict):
        raise TypeError(f"save_checkpoint: config must be a dict, got {type(config).__name__}")
    if isinstance(model_state, torch.nn.Module):
        model_state = model_state.state_dict()
    state = {}
    for k, v in model_state.items():
        if not isinstance(v, torch.Tensor):
            raise TypeError(f"save_checkpoint: model_state[{k!r}] is a {type(v).__name__}, not a tensor")
        v = v.detach().cpu()
        state[k] = v.to(torch.float16) if half and v.is_floating_point() else v.clone()
    skel = None
    if skeleton is not None:
        skel = {"name": str(skeleton.name), "roles": {str(k): str(v) for k, v in skeleton.roles.items()},
                "names": [str(n) for n in skeleton.names],
                "parents": [int(p) for p in skeleton.parents],
                "offsets": torch.from_numpy(np.array(skeleton.offsets, dtype=np.float64))}
    stored_norms = {}
    for name, ns in (norms or {}).items():
        if not isinstance(ns, NormStats):
            raise TypeError(f"save_checkpoint: norms[{name!r}] is a {type(ns).__name__}, not a NormStats")
        stored_norms[str(name)] = {k: torch.from_numpy(np.array(v, dtype=np.float64))
                                   for k, v in ns.to_arrays(prefix="").items()}
    from .distributed import current, launcher

    run = current()
    command = str(command)
    if run.distributed and command.startswith("posekit "):
        command = launcher(run.world) + command
    ckpt = {"format": FORMAT, "version": FORMAT_VERSION, "kind": str(kind), "config": _plain(config, "config"),
            "state": state, "half": bool(half), "skeleton": skel, "norms": stored_norms, "command": command,
            "seed": None if seed is None else int(seed), "data": str(data), "licence": str(licence),
            "extra": _plain(extra or {}, "extra"), "torch": str(torch.__version__)}
    path = Path(path)
    if run.main:  # under torchrun every process holds the same weights: rank 0 writes them, the others wait
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(path.name + ".tmp")
        try:
            torch.save(ckpt, tmp)
            os.replace(tmp, path)
        except BaseException:  # no half-written .tmp left beside the weights
            tmp.unlink(missing_ok=True)
            raise
    run.barrier()
    return path


def _remake(ckpt: dict) -> str:
    return f"; remake it with `{ckpt['command']}`" if ckpt.get("command") else ""


def _name_difference(theirs: list, mine: list) -> str:
    """How two joint-name lists differ, in a line: the counts and the first few differences, never whole lists."""
    if len(theirs) != len(mine):
        return "; ".join([f"{len(theirs)} joints there, {len(mine)} here",
                          *joint_set_difference(mine, theirs, words=("only there", "only here"))])
    differ = [j for j, (a, b) in enumerate(zip(theirs, mine)) if a != b]
    shown = "; ".join(f"joint {j} is {theirs[j]!r} there, {mine[j]!r} here" for j in differ[:3])
    return f"{len(differ)} of {len(mine)} joint names differ ({shown}{'; ...' if len(differ) > 3 else ''})"


def _check_skeleton(path, ckpt: dict, skeleton: Skeleton):
    stored = ckpt.get("skeleton")
    if stored is None:
        raise ValueError(f"checkpoint {path} records no skeleton, so it cannot be checked against this one")
    names, mine = stored["names"], [str(n) for n in skeleton.names]
    if names != mine:
        raise ValueError(f"checkpoint {path} was trained for skeleton joints other than this skeleton's: "
                         f"{_name_difference(names, mine)}")
    parents, mine_p = stored["parents"], [int(p) for p in skeleton.parents]
    if parents != mine_p:
        moved = [i for i, (a, b) in enumerate(zip(parents, mine_p)) if a != b]
        shown = "; ".join(f"joint {names[j]!r}: parent {parents[j]} there, {mine_p[j]} here" for j in moved[:3])
        raise ValueError(f"checkpoint {path} was trained for skeleton parents other than this skeleton's: "
                         f"{len(moved)} joint(s) hang from another parent ({shown}{'; ...' if len(moved) > 3 else ''})")
    offsets = np.asarray(stored["offsets"])
    mine_o = np.asarray(skeleton.offsets, dtype=np.float64)
    if offsets.shape != mine_o.shape or not np.allclose(offsets, mine_o, rtol=0, atol=_OFFSET_ATOL):
        if offsets.shape != mine_o.shape:
            raise ValueError(f"checkpoint {path} was trained for skeleton offsets of shape {offsets.shape} — "
                             f"this skeleton's are {mine_o.shape}")
        err = np.linalg.norm(offsets - mine_o, axis=-1)
        j = int(np.argmax(err))
        raise ValueError(f"checkpoint {path} was trained for other skeleton offsets: joint {names[j]!r} is "
                         f"{np.round(offsets[j], 4).tolist()} m there, {np.round(mine_o[j], 4).tolist()} m in this "
                         f"skeleton ({int(np.sum(err > _OFFSET_ATOL))} joint(s) differ)")


def _check_norms(path, ckpt: dict, norms: dict):
    have = ckpt["norms"]
    for name, ns in norms.items():
        if name not in have:
            raise ValueError(f"checkpoint {path} has no normalisation {name!r} (it has: {sorted(have) or 'none'})")
        if not have[name].same_as(ns):
            a, b = have[name], ns
            if a.mean.shape != np.shape(b.mean) or a.std.shape != np.shape(b.std):
                detail = f"shape {a.mean.shape} there, {np.shape(b.mean)} here"
            else:
                detail = (f"mean differs by up to {np.max(np.abs(a.mean - b.mean)):.3g}, std by up to "
                          f"{np.max(np.abs(a.std - b.std)):.3g}")
            raise ValueError(f"checkpoint {path}: normalisation {name!r} differs from the one given ({detail})")


def load_checkpoint(path, *, kind: str | None = None, skeleton: Skeleton | None = None, norms: dict | None = None,
                    expect: dict | None = None, arrays: bool = False) -> dict:
    """Read a file written by :func:`save_checkpoint` and check it was made for what the caller has.

    Parameters
    ----------
    path : str or Path
    kind : str, optional
        Required model kind.
    skeleton : Skeleton, optional
        Must have the stored joint names, parents and offsets (to 1e-6 m).
    norms : dict of str -> NormStats, optional
        Each must equal the stored normalisation of that name (``NormStats.same_as``).
    expect : dict, optional
        Config fields that must have these values (``{"hidden": 2048}``).
    arrays : bool
        ``state`` as numpy arrays instead of tensors: nothing imports torch (the numpy inference paths).

    Returns
    -------
    dict
        ``state`` (tensors, or numpy arrays with ``arrays``; floating ones float32 when saved with ``half``),
        ``kind``, ``config``, ``skeleton`` (a :class:`~posekit.skeleton.Skeleton` or None), ``norms`` (str -> NormStats,
        float64), ``command``, ``seed``, ``data``, ``licence``, ``extra``, ``half``, ``version``,
        ``torch`` and ``path``.

    Raises
    ------
    FileNotFoundError
        No file at ``path``.
    ValueError
        The file is not a readable posekit checkpoint (corrupt, truncated, another format), has
        another format version or kind, or was made for another skeleton, normalisation or config;
        the message names the field.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no checkpoint at {path}")
    try:
        ckpt = read_torch_file(path)
    except ValueError as e:  # truncated, corrupt, another format, or an object that is not a plain value
        raise ValueError(f"{path} is not a readable posekit checkpoint ({type(e).__name__}: "
                         f"{str(e).splitlines()[0] if str(e) else 'no detail'}); the file may be truncated, "
                         "corrupt or written by an older posekit — remake it with its `posekit train` "
                         "command (posekit train --list)") from e
    if not isinstance(ckpt, dict) or ckpt.get("format") != FORMAT:
        raise ValueError(f"{path} is not a posekit checkpoint (no format field {FORMAT!r}); it may be written by an "
                         "older posekit — remake it with its `posekit train` command (posekit train --list)")
    if ckpt.get("version") != FORMAT_VERSION:
        raise ValueError(f"checkpoint {path} has format version {ckpt.get('version')}, this posekit reads version "
                         f"{FORMAT_VERSION}{_remake(ckpt)}")
    if kind is not None and ckpt["kind"] != kind:
        raise ValueError(f"checkpoint {path} holds a {ckpt['kind']!r} model, expected kind {kind!r}")
    if skeleton is not None:
        _check_skeleton(path, ckpt, skeleton)
    stored = ckpt["skeleton"]
    ckpt["skeleton"] = None if stored is None else Skeleton(stored["names"], np.asarray(stored["parents"]),
                                                            np.asarray(stored["offsets"]), roles=stored["roles"],
                                                            name=stored["name"])
    ckpt["norms"] = {k: NormStats.from_arrays({n: np.asarray(v) for n, v in d.items()}, prefix="")
                     for k, d in ckpt["norms"].items()}
    ckpt["config"], ckpt["extra"] = _unplain(ckpt["config"]), _unplain(ckpt["extra"])
    if norms:
        _check_norms(path, ckpt, norms)
    for field, want in (expect or {}).items():
        if field not in ckpt["config"]:
            raise ValueError(f"checkpoint {path} has no config field {field!r} (expected {want!r}){_remake(ckpt)}")
        got = ckpt["config"][field]
        if not _same(got, want):
            raise ValueError(f"checkpoint {path}: config field {field!r} is {got!r}, expected {want!r}")
    state = {k: np.asarray(v) for k, v in ckpt["state"].items()}
    if ckpt["half"]:
        state = {k: v.astype(np.float32) if v.dtype == np.float16 else v for k, v in state.items()}
    if not arrays:
        import torch

        state = {k: torch.from_numpy(v) for k, v in state.items()}
    ckpt["state"] = state
    ckpt["path"] = path
    return ckpt


def _same(a, b) -> bool:
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.shape(a) == np.shape(b) and bool(np.all(np.asarray(a) == np.asarray(b)))
    if isinstance(b, tuple):
        b = list(b)
    return a == b


_LOADED: dict = {}


def load_cached(load, path, skeleton=None):
    """``load(path)`` once per (loader, file) in a process — a learned solver's weights, shared by every
    solver built from them — then checked against ``skeleton``: a model made for another skeleton is
    loaded again with ``load(path, skeleton=skeleton)``, which raises with a sentence naming the joint,
    parent or offset that differs."""
    try:
        stamp = Path(path).stat().st_mtime_ns  # a file rewritten since (a retrained model) is loaded again
    except OSError:
        stamp = None
    key = (getattr(load, "__qualname__", repr(load)), str(path), stamp)
    if key not in _LOADED:
        _LOADED[key] = load(path)
    m = _LOADED[key]
    if skeleton is not None and not m.skeleton.same_as(skeleton):
        load(path, skeleton=skeleton)
    return m


def require_skeleton(what: str, trained, skeleton) -> None:
    """Refuse a model in memory made for another skeleton: ``ValueError`` "<what> was trained for skeleton
    ... , not ..." (a file is checked joint by joint by :func:`load_checkpoint`)."""
    if not trained.same_as(skeleton):
        raise ValueError(f"{what} was trained for skeleton {trained.name!r} ({trained.n_joints} joints), not "
                         f"{skeleton.name!r} ({skeleton.n_joints} joints); load weights made for this skeleton")

"""The two effector benchmarks of ProtoRes's Table 1 (Oreshkin et al. 2022, Sec. 4), on held-out Bandai poses.

Introduced in ``notebooks/05_protores.ipynb``. Generated once from a seed (``posekit data
build-benchmark protores``) and shipped as files in ``data_samples/benchmarks/`` so every solver, every
run and every machine is scored on the same cases:

* **5-point** — position effectors on the chest, both hands and both feet (:data:`FIVE_POINT`, the
  paper's set), their exact positions in the held-out pose;
* **random** — 6 to 12 effectors: one *position* effector on a random joint of each main zone
  (:data:`ZONES`: both legs, both arms, hips, head), the rest of random kinds on random body joints (no
  two of one kind on a joint, never a rotation and a look-at on one joint). A look-at effector faces a
  random direction of the joint's frame, its target 0.5-3 m away along it in the held-out pose.

Poses: frames of the mini set's *test* clips (held-out dataset-1 takes), world frame as captured.
Tolerances: the :class:`~posekit.ik.effectors.Effector` defaults (1 mm, 1 degree).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..data.metrics import body_joints
from ..ik.effectors import DEFAULT_TOLERANCE, KIND_CODES, Effector
from ..kinematics import fk
from ..paths import samples_dir
from ..rotations import matrix_to_sixd, quat_to_matrix

__all__ = ["BENCHMARKS", "FIVE_POINT", "ZONES", "EffectorBenchmark", "build_benchmark", "load_benchmark",
           "benchmark_path", "MAX_EFFECTORS", "draw_random", "as_effector", "random_case_effectors"]

BENCHMARKS = ("5point", "random")

FIVE_POINT = ("chest", "left_hand", "right_hand", "left_foot", "right_foot")
"""The 5-point benchmark's joints (roles)."""

ZONES = {"left leg": ("left_hip", "left_knee", "left_foot", "left_toe"),
         "right leg": ("right_hip", "right_knee", "right_foot", "right_toe"),
         "left arm": ("left_shoulder", "left_elbow", "left_hand"),
         "right arm": ("right_shoulder", "right_elbow", "right_hand"),
         "hips": ("pelvis",), "head": ("neck", "head")}
"""The random benchmark's main zones (roles): one position effector on one joint of each."""

MAX_EFFECTORS = 12
KIND_NAMES = {v: k for k, v in KIND_CODES.items()}
FORMAT_VERSION = 1


def benchmark_path(name: str) -> Path:
    if name not in BENCHMARKS:
        raise ValueError(f"unknown benchmark {name!r}; valid: {', '.join(BENCHMARKS)}")
    return samples_dir() / "benchmarks" / f"protores_{name}.npz"


@dataclass
class EffectorBenchmark:
    """Cases of one benchmark; C cases of at most K effectors (padded with joint -1).

    Attributes
    ----------
    name : str
    skeleton : Skeleton
    frames : ndarray of int, shape (C,)
        Mini-set frames of the true poses.
    n : ndarray of int, shape (C,)
    joint : ndarray of int, shape (C, K)
        Skeleton joint index; -1 past ``n``.
    kind : ndarray of int, shape (C, K)
        :data:`~posekit.ik.effectors.KIND_CODES`.
    value : ndarray, shape (C, K, 6)
        Position + zeros; 6D world rotation; look-at target + local direction (metres, world frame).
    tolerance : ndarray, shape (C, K)
        Metres (position) or radians.
    local_rot, global_rot : ndarray, shape (C, J, 3, 3)
    root_pos : ndarray, shape (C, 3)
    global_pos : ndarray, shape (C, J, 3), metres
        The true poses.
    """

    name: str
    skeleton: object
    frames: np.ndarray
    n: np.ndarray
    joint: np.ndarray
    kind: np.ndarray
    value: np.ndarray
    tolerance: np.ndarray
    local_rot: np.ndarray
    global_rot: np.ndarray
    root_pos: np.ndarray
    global_pos: np.ndarray

    def __len__(self):
        return len(self.frames)

    def first(self, n: int) -> "EffectorBenchmark":
        """The benchmark's first ``n`` cases (a quicker run of the same cases)."""
        from dataclasses import fields, replace

        return replace(self, **{f.name: getattr(self, f.name)[:n] for f in fields(self)
                                if f.name not in ("name", "skeleton")})

    def effectors(self, i: int) -> list[Effector]:
        """Case ``i`` as :class:`~posekit.ik.effectors.Effector` objects (what a Solver takes)."""
        return [as_effector(self.skeleton, self.joint[i, k], self.kind[i, k], self.value[i, k], self.tolerance[i, k])
                for k in range(int(self.n[i]))]

    def groups(self) -> list[np.ndarray]:
        """Cases that share their joints and kinds (the same network input layout), for batching."""
        keys = {}
        for i in range(len(self)):
            key = (tuple(self.joint[i, :self.n[i]]), tuple(self.kind[i, :self.n[i]]))
            keys.setdefault(key, []).append(i)
        return [np.array(v) for v in keys.values()]

    def kinds_present(self) -> list[str]:
        return [KIND_NAMES[k] for k in sorted(set(self.kind[self.joint >= 0].tolist()))]


def draw_random(rng: np.random.Generator, skeleton, global_pos, global_rot, body=None) -> list[tuple]:
    """One case of the random benchmark (the rule of the module docstring) at a true pose.

    Parameters
    ----------
    rng : numpy Generator
        Consumed in a fixed order, so a seed gives the same effectors on every machine.
    skeleton : Skeleton
    global_pos : ndarray, shape (J, 3), metres
    global_rot : ndarray, shape (J, 3, 3)
        The true pose, world (or root) frame.
    body : sequence of int, optional
        The joints extra effectors may go on (default :func:`posekit.data.metrics.body_joints`).

    Returns
    -------
    list of (joint, kind code, value)
        6 to :data:`MAX_EFFECTORS` effectors; ``value`` (6,) as in :attr:`EffectorBenchmark.value`.
    """
    s, P, G = skeleton, np.asarray(global_pos, float), np.asarray(global_rot, float)
    body = [int(j) for j in (body_joints(s) if body is None else body)]
    picks = [(s.index(str(rng.choice(zone))), 0) for zone in ZONES.values()]
    n = int(rng.integers(6, MAX_EFFECTORS + 1))
    while len(picks) < n:
        j, k = int(rng.choice(body)), int(rng.integers(0, 3))
        taken = {kk for jj, kk in picks if jj == j}
        if k in taken or (k > 0 and taken & {1, 2}):
            continue
        picks.append((j, k))
    out = []
    for j, k in picks:
        value = np.zeros(6)
        if k == 0:
            value[:3] = P[j]
        elif k == 1:
            value[:] = matrix_to_sixd(G[j])
        else:
            v = rng.normal(size=3)
            v /= np.linalg.norm(v)
            value[:3] = P[j] + rng.uniform(0.5, 3.0) * (G[j] @ v)
            value[3:] = v
        out.append((j, k, value))
    return out


def as_effector(skeleton, joint: int, kind_code: int, value, tolerance: float | None = None) -> Effector:
    """One ``(joint, kind code, value)`` of a benchmark as an :class:`~posekit.ik.effectors.Effector`
    (tolerance: the kind's default when None)."""
    kind, name, v = KIND_NAMES[int(kind_code)], skeleton.names[int(joint)], np.asarray(value, float)
    tol = DEFAULT_TOLERANCE[kind] if tolerance is None else float(tolerance)
    if kind == "position":
        return Effector(name, v[:3], "position", tolerance=tol)
    if kind == "rotation":
        return Effector(name, v, "rotation", tolerance=tol)
    return Effector(name, v[:3], "look_at", tolerance=tol, axis=v[3:])


def random_case_effectors(cases, seed: int = 0, tolerance: float | None = None) -> list[list[Effector]]:
    """The random benchmark's rule drawn on posing cases (:class:`posekit.data.cases.Cases`): each case's
    effectors at its true pose (the root frame of the cases), from one generator seeded by ``seed``.

    ``posekit bench ik`` / ``bench all`` call it for ``--effectors random``, so the solvers of every lesson
    meet lesson 05's mixed-kind effectors on their own cases. ``tolerance`` (metres) replaces the position
    effectors' default; angular effectors keep 1 degree.
    """
    s = cases.skeleton
    if cases.target_rot is None:
        raise ValueError("random effectors need the cases' true rotations (Cases.target_rot)")
    _, G = fk(s, quat_to_matrix(np.asarray(cases.target_rot, float)), cases.target_root, cases.target_local_pos)
    rng = np.random.default_rng([seed, BENCHMARKS.index("random"), 1])
    body = [int(j) for j in body_joints(s)]
    out = []
    for i in range(len(cases)):
        picks = draw_random(rng, s, cases.target_pos[i], G[i], body)
        out.append([as_effector(s, j, k, v, tolerance if k == 0 else None) for j, k, v in picks])
    return out


def _truth(motions, frames):
    R = quat_to_matrix(motions.local_rot[frames])
    P, G = fk(motions.skeleton, R, motions.root_pos[frames])
    return R, G, motions.root_pos[frames].copy(), P


def build_benchmark(name: str, motions=None, n_cases: int = 1000, seed: int = 0) -> EffectorBenchmark:
    """Draw a benchmark (see the module docstring) on the test frames of ``motions`` (default the mini set)."""
    from ..data.bandai_mini import load_bandai_mini

    if name not in BENCHMARKS:
        raise ValueError(f"unknown benchmark {name!r}; valid: {', '.join(BENCHMARKS)}")
    motions = load_bandai_mini() if motions is None else motions
    s = motions.skeleton
    rng = np.random.default_rng([seed, BENCHMARKS.index(name)])
    test = motions.split.test
    frames = np.sort(rng.choice(test, size=min(n_cases, len(test)), replace=False))
    R, G, root, P = _truth(motions, frames)
    C, K = len(frames), MAX_EFFECTORS
    joint = -np.ones((C, K), dtype=np.int64)
    kind = np.zeros((C, K), dtype=np.int64)
    value = np.zeros((C, K, 6))
    tol = np.zeros((C, K))
    body = [int(j) for j in body_joints(s)]
    for c in range(C):
        if name == "5point":
            picks = [(s.index(r), 0, np.concatenate([P[c, s.index(r)], np.zeros(3)])) for r in FIVE_POINT]
        else:
            picks = draw_random(rng, s, P[c], G[c], body)
        for e, (j, k, v) in enumerate(picks):
            joint[c, e], kind[c, e], value[c, e] = j, k, v
            tol[c, e] = DEFAULT_TOLERANCE[KIND_NAMES[k]]
    n = (joint >= 0).sum(1)
    return EffectorBenchmark(name, s, frames, n, joint, kind, value, tol, R, G, root, P)


def save_benchmark(b: EffectorBenchmark, path=None, seed: int = 0) -> Path:
    path = Path(path) if path is not None else benchmark_path(b.name)
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(path, version=FORMAT_VERSION, name=b.name, seed=seed, frames=b.frames, joint=b.joint,
                        kind=b.kind, value=b.value.astype(np.float32), tolerance=b.tolerance,
                        joint_names=np.array(b.skeleton.names), source="bandai-mini test clips")
    return path


def load_benchmark(name: str, motions=None, path=None) -> EffectorBenchmark:
    """A shipped benchmark with its true poses (from the mini set, default loaded here).

    Raises
    ------
    FileNotFoundError
        The file is missing (``posekit data build-benchmark protores`` rebuilds it).
    ValueError
        The file was made for other joints or frames outside the set's test clips.
    """
    from ..data.bandai_mini import load_bandai_mini

    path = Path(path) if path is not None else benchmark_path(name)
    if not path.is_file():
        raise FileNotFoundError(f"{path} is missing; rebuild it with `posekit data build-benchmark protores`")
    motions = load_bandai_mini() if motions is None else motions
    s = motions.skeleton
    with np.load(path, allow_pickle=False) as z:
        if tuple(str(n) for n in z["joint_names"]) != tuple(s.names):
            raise ValueError(f"{path}: made for joints {list(z['joint_names'])}, not skeleton {s.name!r}")
        frames = z["frames"].astype(np.int64)
        if not np.isin(frames, motions.split.test).all():
            raise ValueError(f"{path}: frames outside the test clips of {motions.source}; rebuild the benchmark")
        joint, kind = z["joint"].astype(np.int64), z["kind"].astype(np.int64)
        value, tol = z["value"].astype(np.float64), z["tolerance"].astype(np.float64)
    rot6 = kind == KIND_CODES["rotation"]
    if rot6.any():  # stored as float32: back to an exact rotation's columns
        from ..rotations import sixd_to_matrix

        value[rot6] = matrix_to_sixd(sixd_to_matrix(value[rot6]))
    look = kind == KIND_CODES["look_at"]
    value[look, 3:] /= np.linalg.norm(value[look, 3:], axis=-1, keepdims=True)
    R, G, root, P = _truth(motions, frames)
    return EffectorBenchmark(name, s, frames, (joint >= 0).sum(1), joint, kind, value, tol, R, G, root, P)

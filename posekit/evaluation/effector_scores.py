"""Scoring solvers on ProtoRes's effector benchmarks (Oreshkin et al. 2022, Sec. 4), learned and classical alike.

Introduced in ``notebooks/05_protores.ipynb``; ``posekit bench protores`` prints these numbers. Every
method is scored by :func:`scores` on the same cases (:mod:`posekit.evaluation.effector_cases`):

* ``ikd_l2`` — the paper's L_ikd-L2: mean squared error of the final pose's positions over every body
  joint's coordinates, m^2 (world frame, nothing aligned);
* ``gpd_l2`` — L_gpd-L2: the same for the global position decoder's positions (learned models with a GPD);
* ``loc_geo`` — L_loc-geo: mean geodesic angle between predicted and true local rotations over the
  body joints, radians;
* ``mpjpe_mm`` — the *world joint error* of :mod:`posekit.evaluation.measures`: mean per-joint distance in the
  world frame, averaged over the cases, millimetres (the same error as ``ikd_l2``, easier to picture). It is not
  the pelvis-relative, median MPJPE of :mod:`posekit.data.metrics` (the key keeps its name for the stored results);
* effector errors per kind (medians: position mm, rotation and look-at degrees), by the one definition
  every solver shares (:func:`posekit.ik.effector_errors.errors_into`).

Classical methods (the paper's FinalIK stand-ins) start from the rest pose of :func:`posekit.data.cases.rest_start`
placed by the rigid motion (vertical turn + translation) that best fits its joints onto the position
targets (:func:`rest_starts`): the same information the learned models get. FABRIK moves positions only:
it is given the position effectors, and its rotations for L_loc-geo
come from :func:`posekit.ik.bone_rotations.rotations_from_positions`.
"""

from __future__ import annotations

import numpy as np

from ..data.metrics import body_joints
from ..ik.effector_errors import errors_of
from ..ik.effectors import KIND_CODES, resolve_effectors
from ..rotations import geodesic_distance, quat_to_matrix

__all__ = ["scores", "run_classical", "rest_starts", "effector_error_table"]


def effector_error_table(bench, global_pos, global_rot) -> np.ndarray:
    """Every effector's error, shape (C, K) (NaN past each case's ``n``): metres or radians by kind, by the
    solvers' own definition (:func:`posekit.ik.effector_errors.errors_of`)."""
    C, K = bench.joint.shape
    out = np.full((C, K), np.nan)
    for i in range(C):
        res = resolve_effectors(bench.skeleton, bench.effectors(i))
        out[i, :len(res)] = errors_of(global_pos[i], global_rot[i], res)[0]
    return out


def scores(bench, global_pos, local_rot, global_rot, gpd_pos=None) -> dict:
    """The module's metrics of C predicted poses for ``bench``'s C cases.

    Parameters
    ----------
    global_pos : ndarray, shape (C, J, 3), metres
    local_rot : ndarray, shape (C, J, 3, 3) or (C, J, 4)
    global_rot : ndarray, shape (C, J, 3, 3)
    gpd_pos : ndarray, shape (C, J, 3), optional
    """
    b = body_joints(bench.skeleton)
    L = np.asarray(local_rot, dtype=float)
    if L.shape[-1] == 4:
        L = quat_to_matrix(L)
    d = global_pos[:, b] - bench.global_pos[:, b]
    out = {"ikd_l2": float((d ** 2).mean()),
           "gpd_l2": None if gpd_pos is None else float(((gpd_pos[:, b] - bench.global_pos[:, b]) ** 2).mean()),
           "loc_geo": float(geodesic_distance(L[:, b], bench.local_rot[:, b]).mean()),
           "mpjpe_mm": float(np.linalg.norm(d, axis=-1).mean() * 1000)}
    err = effector_error_table(bench, global_pos, global_rot)
    for name, code, scale in (("pos_mm", 0, 1000.0), ("rot_deg", 1, 180 / np.pi), ("look_deg", 2, 180 / np.pi)):
        sel = (bench.kind == code) & (bench.joint >= 0)
        out[name] = float(np.median(err[sel]) * scale) if sel.any() else None
    return out


def rest_starts(bench, motions):
    """The classical methods' start per case: the rest pose (:func:`posekit.data.cases.rest_start`) placed by
    the rigid motion — a turn about the vertical and a translation — that best fits its position-effector
    joints onto their targets (least squares, closed form), so it uses only what the learned models are given.
    Returns local quaternions (C, J, 4) and root positions (C, 3)."""
    from ..data.cases import rest_start
    from ..kinematics import fk
    from ..transforms import rotate_y_rotations

    s = bench.skeleton
    q0, r0, _ = rest_start(motions, motions.split.train)
    p0 = fk(s, q0, r0)[0]
    C = len(bench)
    angle, shift = np.zeros(C), np.zeros((C, 3))
    for i in range(C):
        sel = (bench.kind[i] == KIND_CODES["position"]) & (bench.joint[i] >= 0)
        a, t = p0[bench.joint[i, sel]], bench.value[i, sel, :3]
        ca, ct = a.mean(0), t.mean(0)
        da, dt = a - ca, t - ct
        # yaw theta maximising sum t . R_y(theta) a over the floor plane: R_y(theta) (x, z) = (x c + z s, -x s + z c)
        num = (dt[:, 0] * da[:, 2] - dt[:, 2] * da[:, 0]).sum()
        den = (dt[:, 0] * da[:, 0] + dt[:, 2] * da[:, 2]).sum()
        angle[i] = np.arctan2(num, den)
        c, sn = np.cos(angle[i]), np.sin(angle[i])
        shift[i] = ct - np.array([ca[0] * c + ca[2] * sn, ca[1], -ca[0] * sn + ca[2] * c])
    q, root = rotate_y_rotations(np.broadcast_to(q0, (C,) + q0.shape), np.broadcast_to(r0, (C, 3)), angle)
    return q, root + shift


def run_classical(name: str, bench, motions, progress: bool = False, **options) -> dict:
    """Solve every case with the registered solver ``name`` (``"fabrik"`` or ``"dls"``) from :func:`rest_starts`;
    FABRIK gets the position effectors only. Returns the arrays of :func:`run_learned` plus ``seconds``."""
    import time

    from ..ik.api import Pose
    from ..ik.bone_rotations import rotations_from_positions
    from ..ik.registry import make_solver
    from ..kinematics import fk

    s = bench.skeleton
    solver = make_solver(name, s, **options)
    q, root = rest_starts(bench, motions)
    C, J = len(bench), s.n_joints
    P = np.empty((C, J, 3))
    Lq = np.empty((C, J, 4))
    R0 = root.copy()
    it = range(C)
    if progress:
        from tqdm.auto import tqdm

        it = tqdm(it, desc=name, unit="case")
    t = time.perf_counter()
    for i in it:
        effs = bench.effectors(i)
        effs = [e for e in effs if e.kind in solver.kinds]
        start = Pose.from_rotations(s, q[i], root[i])
        r = solver.solve(start, effs)
        P[i] = r.pose.global_pos
        if r.pose.local_rot is not None:
            Lq[i], R0[i] = r.pose.local_rot, r.pose.root_pos
    sec = time.perf_counter() - t
    if "rotation" not in solver.kinds:  # positions only: rotations that turn the start's bones onto them
        L, R0 = rotations_from_positions(s, quat_to_matrix(q), root, P)
    else:
        L = quat_to_matrix(Lq)
    G = fk(s, L, R0)[1]
    return {"global_pos": P, "local_rot": L, "global_rot": G, "gpd_pos": None, "seconds": sec}

"""``posekit bench invrig``: the shape of Tables 1 and 2 of Holden, Saito & Komura 2017 on our rig.

Introduced in ``notebooks/02_inverse_rig_mapping.ipynb``. Training animation and held-out test clips
come from :func:`posekit.invrig.standard_sets` (seeded; the setup shared with the lesson is :mod:`posekit.invrig.lesson`). Per method, on the 1,000 test frames:

* ``joint_error`` — mean distance between the rig's joints at the predicted controls and the true
  joints, cm (the paper's "Joint Error");
* ``ground_truth_error`` — mean absolute control error, in standard deviations of the training
  animation (the paper's rig-space "Ground-Truth Error");
* ``total_s`` and ``frames_per_s`` — the whole test set on one thread, rig evaluations included.

Table 1: heuristic script, GPR, GPR + learned Jacobian, GPR + computed Jacobian, NN, NN + computed
Jacobian. Table 2: the network trained on each supersampling method (weights shipped in
``data_samples/weights``, made by ``posekit train invrig``). Table 3 (the paper's Fig. 11): three long
1,000-frame test clips solved frame by frame, by pure optimisation from the previous frame and with
a learned first guess every frame; errors of the first and the last 200 frames.
"""

from __future__ import annotations

import time

from ..invrig.lesson import Setup, drift
from .plugin import arg, register_benchmark

# torch is imported only when the networks are loaded, so that building the command line (which
# lists this benchmark) stays fast

__all__ = ["run", "PAPER_FPS"]

PAPER_FPS = (195, 656)
"""Frames per second the paper reports for its methods with Maya in the loop (range over methods)."""


def _timed(fn):
    t = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t


def run(seed: int = 0, budget: int = 500, weights=None, sampling: bool = True, drift_table: bool = True,
        setup_: Setup | None = None) -> list[dict]:
    """Measure Table 1 (and Table 2 with ``sampling``, Table 3 with ``drift_table``); one row per method."""
    from ..learn.threads import single_thread
    from ..invrig import METHODS, heuristic_inverse, refine

    s = setup_ or Setup(seed, budget)
    Xt = s.Xt3.reshape(len(s.test), -1)
    rows = []
    with single_thread():
        nn_pca = s.net("pca", weights)
        methods = [
            ("heuristic script", lambda: heuristic_inverse(s.rig, s.Xt3)),
            ("GPR", lambda: s.gpr.predict(Xt)),
            ("GPR + learned Jacobian", lambda: refine(s.rig, s.Xt3, s.gpr.predict(Xt), s.learned_jacobian)),
            ("GPR + computed Jacobian", lambda: refine(s.rig, s.Xt3, s.gpr.predict(Xt), "computed")),
            ("NN", lambda: nn_pca.predict(Xt)),
            ("NN + computed Jacobian", lambda: refine(s.rig, s.Xt3, nn_pca.predict(Xt), "computed")),
        ]
        for name, fn in methods:
            y, dt = _timed(fn)
            rows.append({"table": 1, "method": name, "joint_error": s.joint_error(y),
                         "ground_truth_error": s.ground_truth_error(y), "total_s": dt,
                         "frames_per_s": len(Xt) / dt, "clamped_values": s.clamped_values(y)})
        for guess, name in (("previous", "optimisation only (previous frame as guess)"),
                            ("gpr", "GPR + computed Jacobian, every frame")) if drift_table else ():
            (je, ge), dt = _timed(lambda: drift(s, guess))
            rows.append({"table": 3, "method": name, "frames": je.size,
                         "joint_error_first_200": float(je[:, :200].mean()),
                         "joint_error_last_200": float(je[:, -200:].mean()),
                         "ground_truth_error_first_200": float(ge[:, :200].mean()),
                         "ground_truth_error_last_200": float(ge[:, -200:].mean()), "frames_per_s": je.size / dt})
        if sampling:
            for m in METHODS:
                y = s.net(m, weights).predict(Xt)
                yr = refine(s.rig, s.Xt3, y, "computed")
                rows.append({"table": 2, "method": f"NN, {m} sampling", "joint_error": s.joint_error(y),
                             "ground_truth_error": s.ground_truth_error(y),
                             "joint_error_with_jacobian": s.joint_error(yr)})
    for r in rows:
        r.setdefault("frames", len(Xt))
    rows.append({"table": 0, "method": "setup", "theta0": s.theta0, "gpr_budget": budget, "fit_s": s.fit_s,
                 "paper_frames_per_s": list(PAPER_FPS)})
    return rows


def _header(rows, args) -> str:
    setup = next(r for r in rows if r.get("table") == 0)
    frames = next(r["frames"] for r in rows if r.get("table") == 1)
    return (f"Inverse rig mapping on the held-out test clips ({frames} frames), one thread; GPR: multiquadric, "
            f"theta0 = {setup['theta0']:.3g}, {setup['gpr_budget']} subsampled poses, "
            f"fitted in {setup['fit_s']:.1f} s\n"
            "joint error: cm; ground-truth error: control error in training standard deviations")


TABLES = [
    ("Table 1 (paper: {}-{} frames/s with Maya in the loop)".format(*PAPER_FPS),
     ["method", "joint_error", "ground_truth_error", "total_s", "frames_per_s", "clamped_values"], {"table": 1}),
    ("Table 2: the network by supersampling method",
     ["method", "joint_error", "ground_truth_error", "joint_error_with_jacobian"], {"table": 2}),
    ("Drift (Fig. 11): three 1,000-frame test clips solved frame by frame; joint error (cm) and control\n"
     "error (sd) of the first and the last 200 frames",
     ["method", "joint_error_first_200", "joint_error_last_200", "ground_truth_error_first_200",
      "ground_truth_error_last_200", "frames_per_s"], {"table": 3}),
]
"""The tables ``posekit bench invrig`` prints: (title, JSON keys, which rows)."""

TABLE_LABELS = {
    "joint_error": "joint cm", "ground_truth_error": "control sd", "total_s": "total s", "frames_per_s": "frames/s",
    "clamped_values": "clamped", "joint_error_with_jacobian": "joint cm + Jacobian",
    "joint_error_first_200": "cm first", "joint_error_last_200": "cm last",
    "ground_truth_error_first_200": "sd first", "ground_truth_error_last_200": "sd last",
}
"""Short table headers for the JSON keys (units in the header)."""

register_benchmark(
    "invrig", lambda args: run(seed=args.seed, budget=args.budget, weights=args.weights),
    help="inverse rig mapping: Tables 1 and 2 of Holden et al. 2017 on our rig",
    args=[arg("--seed", type=int, default=0, help="seed of the animation and the GPR fit"),
          arg("--budget", type=int, default=500, help="GPR training poses after greedy subsampling"),
          arg("--weights", default=None, help="folder of invrig_nn_*.pt (default data_samples/weights)")],
    tables=TABLES, labels=TABLE_LABELS, header=_header, lesson="notebooks/02_inverse_rig_mapping.ipynb")

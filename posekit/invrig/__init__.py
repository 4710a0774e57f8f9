"""Lesson 02, inverse rig mapping (Holden, Saito & Komura, TVCG 2017), in one folder.

Introduced in ``notebooks/02_inverse_rig_mapping.ipynb``:

* the rig an animator moves — :mod:`~posekit.invrig.humanoid` (``HumanoidRig``: controls -> joint
  positions), :mod:`~posekit.invrig.animator` (key poses and in-betweens: the training and test
  animation), :mod:`~posekit.invrig.heuristic` (the hand-written retargeting script);
* learning its inverse — :mod:`~posekit.invrig.gpr` (Gaussian-process regression, multiquadric
  kernel), :mod:`~posekit.invrig.jacobian` (learned and computed Jacobians, refinement),
  :mod:`~posekit.invrig.sampling` (supersampling the controls), :mod:`~posekit.invrig.nn` (the
  2048-unit network) and :mod:`~posekit.invrig.train` (``posekit train invrig``);
* :mod:`~posekit.invrig.lesson` — the lesson's setup and drift experiment, also used by
  ``posekit bench invrig``.
"""

from .animator import animate, standard_sets
from .gpr import GPR, KERNELS, cross_validate, greedy_subsample, line_search_theta0
from .heuristic import heuristic_inverse
from .humanoid import CONTROLS, HumanoidRig
from .jacobian import LearnedJacobian, refine
from .sampling import METHODS, sample_controls

__all__ = ["HumanoidRig", "CONTROLS", "animate", "standard_sets", "heuristic_inverse", "GPR", "KERNELS",
           "cross_validate", "line_search_theta0", "greedy_subsample", "refine", "LearnedJacobian", "METHODS",
           "sample_controls"]

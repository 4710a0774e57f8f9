"""Classical inverse kinematics behind one Solver API (lesson 01).

* :mod:`posekit.ik.api` — the contract: :class:`Pose`, :class:`IKResult`, :class:`Solver`,
  :class:`SolverBase`;
* :mod:`posekit.ik.effectors` — :class:`Effector` (position, rotation, look-at) and the one error
  function, :func:`effector_errors`;
* :mod:`posekit.ik.registry` — solvers by name (:func:`make_solver`, :func:`solver_names`);
* the solvers: :mod:`~posekit.ik.fabrik` (``"fabrik"``, ``"fabrik-constrained"``),
  :mod:`~posekit.ik.ccd` (``"ccd"``), :mod:`~posekit.ik.dls` (``"dls"``).
"""

from .api import (DEFAULT_TOLERANCE, EFFECTOR_SETS, KINDS, Effector, IKResult, Pose, ResolvedEffectors, Solver,
                  SolverBase, effector_errors, effector_errors_batch, effector_set, resolve_effectors)
from .fabrik import Constraints, FabrikSolver, default_constraints  # noqa: I001
from .single_chain import fabrik_chain, straighten_chain
from .fix_bones import fix_bone_lengths
from .ccd import CCDSolver
from .dls import DLSSolver
from .registry import SolverInfo, make_solver, register, solver_info, solver_names

__all__ = ["Effector", "Pose", "IKResult", "Solver", "SolverBase", "EFFECTOR_SETS", "effector_set",
           "resolve_effectors", "effector_errors", "effector_errors_batch", "KINDS", "DEFAULT_TOLERANCE",
           "ResolvedEffectors", "FabrikSolver", "CCDSolver", "DLSSolver", "fabrik_chain", "straighten_chain", "fix_bone_lengths",
           "Constraints", "default_constraints", "SolverInfo", "register", "make_solver", "solver_names",
           "solver_info"]

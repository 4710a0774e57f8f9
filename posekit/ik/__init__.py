"""Classical inverse kinematics behind one Solver API (lesson 01)."""

from .api import EFFECTOR_SETS, Effector, IKResult, Pose, Solver, effector_set, resolve_effectors
from .ccd import CCDSolver
from .dls import DLSSolver
from .fabrik import Constraints, FabrikSolver, default_constraints, fabrik_chain, fix_bone_lengths

__all__ = ["Effector", "Pose", "IKResult", "Solver", "EFFECTOR_SETS", "effector_set", "resolve_effectors",
           "FabrikSolver", "CCDSolver", "DLSSolver", "fabrik_chain", "fix_bone_lengths", "Constraints", "default_constraints"]

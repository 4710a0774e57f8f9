"""Learning inverse rig mappings (lesson 02): GPR, Jacobian refinement, supersampling, the network."""

from .gpr import GPR, KERNELS, cross_validate, greedy_subsample, line_search_theta0
from .jacobian import LearnedJacobian, refine
from .sampling import METHODS, sample_controls

__all__ = ["GPR", "KERNELS", "cross_validate", "line_search_theta0", "greedy_subsample", "refine",
           "LearnedJacobian", "METHODS", "sample_controls"]

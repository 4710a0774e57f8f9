"""Checker functions for the notebooks' exercises: a self-learner knows when they are right.

Each checker calls the student's function on seeded cases, compares with posekit, prints one line
(✓ or ✗ with what differed) and returns True or False. A function that still raises
``NotImplementedError`` is reported as "not attempted yet"; one that changes its inputs in place, or calls the
posekit function it is compared against, fails (:mod:`posekit.exercises._check`).

The exercises' reference solutions are not in this package (students import it): they live in the repository's
``instructor/solutions/`` folder (:mod:`posekit.course.solutions`).
"""

from .nb00 import check_bone_drift, check_local_from_global, check_matrix_to_quat
from .nb01 import check_fabrik_planted, check_two_bone_swivel
from .nb02 import check_dls_prior, check_gpr_loo
from .nb03 import check_authors_loss, check_pose_from_vector, check_pose_vector
from .nb04 import check_adversarial, check_latent_loss, check_spl_all
from .nb05 import check_effector_inputs, check_look_at_angle, check_rotation_noise
from .nb06 import check_drag_on_sphere, check_slerp

__all__ = ["check_local_from_global", "check_matrix_to_quat", "check_bone_drift", "check_fabrik_planted", "check_two_bone_swivel",
           "check_gpr_loo", "check_dls_prior", "check_pose_vector", "check_pose_from_vector", "check_authors_loss",
           "check_spl_all", "check_latent_loss", "check_adversarial", "check_look_at_angle",
           "check_rotation_noise", "check_effector_inputs", "check_drag_on_sphere", "check_slerp"]

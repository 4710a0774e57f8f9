"""posekit — the library behind a numbered series of notebooks on data-driven character posing.

Layers point down — a module imports only from its own layer or the ones above it in this list
(``docs/library.md`` draws the same table):

1. core: :mod:`posekit.conventions`, :mod:`posekit.rotations`, :mod:`posekit.skeleton`,
   :mod:`posekit.kinematics`, :mod:`posekit.transforms`, :mod:`posekit.records` (``Pose``, ``NormStats``),
   :mod:`posekit.paths`, :mod:`posekit.catalogue` (the built-in plug-in modules, by name) and
   :mod:`posekit.plugins` (the registry they fill)
2. data: :mod:`posekit.io` (BVH, rig and unit recognition, DeepMimic conversion), :mod:`posekit.data`
3. solvers: :mod:`posekit.ik` (lesson 01), the inverse rig mapping (lesson 02), :mod:`posekit.learn`
   (the torch layer the learned models share, the trainer registry) and :mod:`posekit.models`, one
   folder per paper (lessons 03-05)
4. top: :mod:`posekit.viz` (3D widget, matplotlib), :mod:`posekit.bench`, :mod:`posekit.cli`,
   :mod:`posekit.exercises`

Conventions (metres, Y up, facing +Z, quaternions ``(x, y, z, w)``): :mod:`posekit.conventions`.
"""

from .kinematics import bone_lengths_of, fk, rest_pose
from .skeleton import Skeleton

__version__ = "0.1.0"
__all__ = ["Skeleton", "fk", "rest_pose", "bone_lengths_of", "__version__"]

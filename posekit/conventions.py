"""Conventions used everywhere in posekit — read this once, every docstring links here.

Glossary of array codes
-----------------------
=================  =====================  ==============================================
name               shape                  meaning
=================  =====================  ==============================================
``parents``        (J,) int               parent index of each joint; ``-1`` for the root;
                                          parents always come before children
``offsets``        (J, 3) metres          rest translation of each joint in its parent's frame
``local_rot``      (..., J, 4) or         rotation of each joint relative to its parent,
                   (..., J, 3, 3)         as quaternions or rotation matrices
``local_pos``      (..., J, 3) metres     per-frame translation in the parent's frame (BVH
                                          position channels); defaults to ``offsets``
``root_pos``       (..., 3) metres        world position of joint 0
``global_pos``     (..., J, 3) metres     world position of each joint
``global_rot``     (..., J, 3, 3)         world rotation of each joint
``sixd``           (..., 6)               6D rotation: the first two *columns* of the matrix,
                                          ``[R[:, 0], R[:, 1]]`` (Zhou et al. 2019)
=================  =====================  ==============================================

Every function takes any number of leading batch dimensions ``...``.

Axes and units
--------------
* Lengths in **metres**, angles in **radians** (BVH files store degrees; the reader converts).
* Right-handed world, **Y up**, the character **faces +Z** in its root frame, so its left
  is +X and its right is -X. The floor is the plane y = 0.
* Mirroring reflects across the YZ plane (x -> -x) and swaps left and right joints.
* Figures keep this handedness: matplotlib's 3D axes are Z up, so :mod:`posekit.viz.plot` draws world
  ``(x, y, z)`` at matplotlib's ``(z, x, y)``, a rotation (never an axis swap, which would mirror every figure).
  A camera's azimuth there is its angle from the character's front (+Z) towards its left (+X): 0 front, 90 left,
  180 behind. Seen from the front, a character's left hand is on the image's right.

Rotations
---------
* Quaternions are stored **scalar-last**, ``(x, y, z, w)``, the order of
  :class:`scipy.spatial.transform.Rotation` and of the ``roma`` torch library.
* Rotation matrices act on **column vectors**: ``v_world = R @ v_local``.
* Forward kinematics composes parent-first:
  ``global_rot[j] = global_rot[parent] @ local_rot[j]`` and
  ``global_pos[j] = global_pos[parent] + global_rot[parent] @ local_pos[j]``.
* Euler angles follow BVH: the channel order as written is an *intrinsic* sequence, so
  ``Zrotation Xrotation Yrotation`` means ``R = Rz @ Rx @ Ry`` (scipy's upper-case ``"ZXY"``).

Time
----
* ``frame_time`` is seconds per frame.
"""

import numpy as np

UP = np.array([0.0, 1.0, 0.0])
"""World up axis (Y)."""

FORWARD = np.array([0.0, 0.0, 1.0])
"""Facing direction of a character in its root frame (+Z)."""

LEFT = np.array([1.0, 0.0, 0.0])
"""A character's left in its root frame (+X)."""

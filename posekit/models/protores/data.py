"""ProtoRes's training data (Oreshkin et al. 2022, Sec. 2.3 and Appendix B): poses, and effectors drawn on them.

Introduced in ``notebooks/05_protores.ipynb``. Units and axes: :mod:`posekit.conventions` (metres,
radians, Y up, facing +Z).

:class:`PoseBank` holds the training poses as torch tensors (local and world rotations, world
positions), mirrored copies appended (:func:`posekit.transforms.mirror_rotation_matrices`: the Bandai
skeleton's frames are not mirror images, so a plain quaternion flip would not do). :func:`draw_batch`
makes one training batch the way the paper's Algorithm 1 does:

* B poses, each turned about the vertical axis by a uniform random angle (Y-rotation augmentation);
* ``N ~ U{n_min..n_max}`` effectors per pose, drawn once per batch; kinds uniform over position,
  rotation and look-at, the first ``min_position`` forced to position (so a pose can be placed);
  joints drawn without replacement per kind (look-at with replacement), so a hand may carry a position
  and a rotation effector at once;
* a tolerance ``Lambda ~ U[0, 1]`` per effector, noise of scale ``sigma = sigma_M Lambda^eta`` added to
  its target by the kind's **noise model** (:func:`add_noise`) and a loss weight ``min(W_M, 1 / sigma)``
  on its joint (:mod:`posekit.models.protores.train`);
* a look-at effector: a random unit direction ``v`` in the joint's frame, its target
  ``p + d R v`` at distance ``d = 1 mm + 5 |N(0, 1)|`` m (the authors' code).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from ...data.metrics import body_joints
from ...rotations import matrix_to_sixd, quat_to_matrix
from ...transforms import mirror_frame_signs, mirror_rotation_matrices
from .networks import KIND_IDS, SIGMA_M, ETA

__all__ = ["PoseBank", "Batch", "draw_batch", "add_noise", "axis_angle_matrix", "LOOK_AT_SCALE"]

LOOK_AT_SCALE = 5.0
"""Scale (metres) of the half-normal distance of a training look-at target from its joint."""


def axis_angle_matrix(v):
    """Rotation matrices of rotation vectors ``v`` (..., 3) (axis times angle, radians): Rodrigues."""
    theta = v.norm(dim=-1, keepdim=True).clamp_min(1e-12)
    k = v / theta
    K = torch.zeros(*v.shape[:-1], 3, 3, dtype=v.dtype)
    K[..., 0, 1], K[..., 0, 2], K[..., 1, 2] = -k[..., 2], k[..., 1], -k[..., 0]
    K = K - K.transpose(-1, -2)
    s, c = torch.sin(theta)[..., None], torch.cos(theta)[..., None]
    return torch.eye(3, dtype=v.dtype) + s * K + (1 - c) * (K @ K)


def _yaw(angle):
    c, s = torch.cos(angle), torch.sin(angle)
    z, o = torch.zeros_like(angle), torch.ones_like(angle)
    return torch.stack([torch.stack([c, z, s], -1), torch.stack([z, o, z], -1), torch.stack([-s, z, c], -1)], -2)


class PoseBank:
    """Poses for training or validation, as float32 tensors over the body joints and the full skeleton.

    Parameters
    ----------
    motions : MotionSet
        With ``local_rot`` (the Bandai mini set); a helper root above the pelvis must never rotate.
    frames : array of int
    mirror : bool
        Append mirrored copies (training).

    Attributes
    ----------
    local_rot : tensor, shape (F, J, 3, 3)
    global_rot : tensor, shape (F, J, 3, 3)
    global_pos : tensor, shape (F, J, 3), metres
    body : ndarray of int, shape (B,)
        The body joints (:func:`~posekit.data.metrics.body_joints`): effectors and outputs live on them.
    """

    def __init__(self, motions, frames, mirror: bool = False):
        from ...kinematics import fk

        s = motions.skeleton
        frames = np.asarray(frames, dtype=np.int64)
        R = quat_to_matrix(motions.local_rot[frames])
        root = motions.root_pos[frames]
        self.body = np.asarray(body_joints(s), dtype=np.int64)
        self.pelvis = s.pelvis()
        helper = s.parents[self.pelvis]
        if helper >= 0 and not np.allclose(R[:, helper], np.eye(3), atol=1e-6):
            raise ValueError(f"{motions.source}: the helper root {s.names[helper]} rotates; ProtoRes's outputs "
                             "leave it fixed (expected the identity rotation)")
        if mirror:
            signs = mirror_frame_signs(s, R[:: max(1, len(R) // 5000)])
            Rm, rootm = mirror_rotation_matrices(s, R, root, signs)
            R, root = np.concatenate([R, Rm]), np.concatenate([root, rootm])
        P, G = fk(s, R, root)
        self.skeleton = s
        self.local_rot = torch.as_tensor(R, dtype=torch.float32)
        self.global_rot = torch.as_tensor(G, dtype=torch.float32)
        self.global_pos = torch.as_tensor(P, dtype=torch.float32)

    def __len__(self):
        return len(self.local_rot)


@dataclass
class Batch:
    """One batch of poses and effectors (tensors; B poses, N effectors, J skeleton joints).

    ``joint`` (B, N) body-joint index; ``kind`` (B, N) :data:`~posekit.models.protores.networks.KIND_IDS`;
    ``value`` (B, N, 6) the network's input values (noisy targets); ``tol`` (B, N) Lambda; ``sigma``
    (B, N) noise scale; ``axis`` (B, N, 3) look-at direction (local); ``target`` (B, N, 3) look-at
    target; ``local_rot`` (B, J, 3, 3), ``global_rot`` (B, J, 3, 3), ``global_pos`` (B, J, 3) the true pose.
    """

    joint: torch.Tensor
    kind: torch.Tensor
    value: torch.Tensor
    tol: torch.Tensor
    sigma: torch.Tensor
    axis: torch.Tensor
    target: torch.Tensor
    local_rot: torch.Tensor
    global_rot: torch.Tensor
    global_pos: torch.Tensor

    def to(self, device) -> "Batch":
        """The batch on ``device`` (itself when it is there already)."""
        if self.joint.device == torch.device(device):
            return self
        return Batch(**{k: v.to(device) for k, v in vars(self).items()})


def add_noise(pos, rot, lookdir, sigma, gen):
    """The three noise models (Appendix B), one per kind, each of scale ``sigma`` (B, N).

    * position: ``p + sigma n``, ``n ~ N(0, I_3)`` (metres);
    * rotation: ``exp(sigma n) R`` — a random rotation vector of scale ``sigma`` radians, applied in the
      world frame (the authors' code draws Euler angles; the same scale);
    * look-at: the world direction ``R v`` turned by ``exp(sigma n)``. (The authors' code leaves look-at
      targets exact, a "to do" in its source; with this model the tolerance means the same angle
      for both angular kinds.)

    Returns noisy ``pos`` (B, N, 3), ``rot`` (B, N, 3, 3) and ``lookdir`` (B, N, 3).
    """
    n = torch.randn(*sigma.shape, 3, 3, generator=gen) * sigma[..., None, None]
    pos = pos + n[..., 0, :]
    rot = axis_angle_matrix(n[..., 1, :]) @ rot
    lookdir = (axis_angle_matrix(n[..., 2, :]) @ lookdir[..., None])[..., 0]
    return pos, rot, lookdir


def draw_batch(bank: PoseBank, batch: int, gen: torch.Generator, n_min: int = 3, n_max: int = 16,
               min_position: int = 3, yaw: bool = True, noise: bool = True) -> Batch:
    """One training batch (Algorithm 1 of the paper; the module docstring lists what is drawn).

    Parameters
    ----------
    bank : PoseBank
    batch : int
        B poses.
    gen : torch.Generator
        The only source of randomness (seeded by the caller).
    n_min, n_max : int
        ``N ~ U{n_min..n_max}`` effectors, the same N for the whole batch.
    min_position : int
        At least this many of them position effectors.
    yaw : bool
        Turn every pose about the vertical by a uniform angle.
    noise : bool
        Add tolerance-driven noise (off: exact targets whatever Lambda says).
    """
    idx = torch.randint(0, len(bank), (batch,), generator=gen)
    L, G, P = bank.local_rot[idx], bank.global_rot[idx], bank.global_pos[idx]
    if yaw:
        Ry = _yaw(torch.rand(batch, generator=gen) * (2 * np.pi))
        P = (Ry[:, None] @ P[..., None])[..., 0]
        G = Ry[:, None] @ G
        L = L.clone()
        L[:, bank.pelvis] = Ry @ L[:, bank.pelvis]  # the helper root never turns (checked by PoseBank)
    nb = len(bank.body)
    N = int(torch.randint(n_min, n_max + 1, (1,), generator=gen))
    kind = torch.randint(0, 3, (batch, N), generator=gen)
    kind[:, :min(min_position, N)] = KIND_IDS["position"]
    # joints without replacement per kind: slot i of kind k takes the rank-th entry of a permutation
    perm = torch.argsort(torch.rand(batch, 3, nb, generator=gen), dim=-1)
    onehot = torch.nn.functional.one_hot(kind, 3)
    rank = (onehot.cumsum(1) - 1).gather(2, kind[..., None])[..., 0].clamp_max(nb - 1)
    joint = perm[torch.arange(batch)[:, None], kind, rank]
    look = kind == KIND_IDS["look_at"]
    joint = torch.where(look, torch.randint(0, nb, (batch, N), generator=gen), joint)
    sk = torch.as_tensor(bank.body)[joint]  # skeleton index
    bi = torch.arange(batch)[:, None]
    pos, rot = P[bi, sk], G[bi, sk]
    axis = torch.randn(batch, N, 3, generator=gen)
    axis = axis / axis.norm(dim=-1, keepdim=True).clamp_min(1e-9)
    lookdir = (rot @ axis[..., None])[..., 0]
    dist = 1e-3 + LOOK_AT_SCALE * torch.randn(batch, N, 1, generator=gen).abs()
    tol = torch.rand(batch, N, generator=gen)
    sigma = SIGMA_M * tol ** ETA
    if noise:
        pos_n, rot_n, dir_n = add_noise(pos, rot, lookdir, sigma, gen)
    else:
        pos_n, rot_n, dir_n = pos, rot, lookdir
    target = pos + dist * dir_n
    value = torch.zeros(batch, N, 6)
    value = torch.where((kind == KIND_IDS["position"])[..., None], torch.cat([pos_n, torch.zeros_like(pos_n)], -1),
                        value)
    value = torch.where((kind == KIND_IDS["rotation"])[..., None], matrix_to_sixd(rot_n), value)
    value = torch.where(look[..., None], torch.cat([target, axis], -1), value)
    return Batch(joint, kind, value, tol, sigma, axis, target, L, G, P)

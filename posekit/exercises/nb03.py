"""Checkers for ``notebooks/03_autoencoder_solvers.ipynb``."""

from __future__ import annotations

import numpy as np

from ._check import report
from ._judge import judged


@judged
def check_pose_vector(my_pose_vector) -> bool:
    """Check ``my_pose_vector(skeleton, global_pos (J, 3)) -> (3B,)``: the body joints (no helper root)
    in the pose's root frame — pelvis projected on the floor at the origin, facing +Z — flattened
    (:func:`posekit.data.pose_vectors.pose_vectors`)."""
    from ..data import load_sample
    from ..data.bandai_mini import load_bandai_mini
    from ..data.pose_vectors import pose_vectors

    m = load_bandai_mini()
    other = load_sample()  # another skeleton (DeepMimic's humanoid, no helper root): no index may be hard-coded
    cases = []

    def describe(got, expected):
        d = np.abs(got - expected).reshape(-1, 3).max(-1)
        return (f"largest difference {d.max() * 1e3:.1f} mm at body joint {int(np.argmax(d))}; left out joint_Root? "
                "turned by minus the facing angle? pelvis on the floor (y kept)?")
    for motion, f in ((m, 0), (other, 100), (m, 4321), (m, 20_000), (other, 1500), (m, 40_000)):
        pos = motion.global_pos[f]
        cases.append(((motion.skeleton, pos.copy()), pose_vectors(motion.skeleton, pos[None])[0][0], describe))
    return report("check_pose_vector", my_pose_vector, cases, atol=1e-6, forbid=(pose_vectors,),
                  arg_names=("skeleton", "global_pos"))


@judged
def check_tied_decoder(my_decode) -> bool:
    """Check ``my_decode(z (N, d), W1 (H, F), W2 (H, H), W3 (d, H)) -> x (N, F)``: the tied decoder of the
    authors' code, ``W1^T relu(W2^T relu(W3^T z))`` with no biases (weights in torch's (out, in) layout)."""
    import torch

    from ..models.pose_autoencoder.networks import PoseAutoencoder

    cases = []

    def describe(got, expected):
        return f"max error {np.abs(got - expected).max():.3g}; transposed weights, ReLU after the first two, no biases?"
    for seed, (F, H, d, N) in enumerate(((12, 8, 4, 6), (63, 200, 64, 6), (9, 5, 3, 6), (7, 6, 4, 1))):
        torch.manual_seed(seed)
        ae = PoseAutoencoder(F, H, d, tied=True)
        z = torch.randn(N, d)  # the last: one code, (1, d)
        with torch.no_grad():
            expected = ae.decode(z).numpy().astype(float)
        weights = (m.weight.detach().numpy().astype(float) for m in (ae.enc1, ae.enc2, ae.enc3))
        args = (z.numpy().astype(float), *weights)
        cases.append((args, expected, describe))
    z, W1, W2, W3 = (np.asarray(a, np.float32) for a in cases[0][0])  # float32 codes and weights
    cases.append(((z, W1, W2, W3), cases[0][1], describe))
    return report("check_tied_decoder", my_decode, cases, atol=1e-5, forbid=(PoseAutoencoder.decode,),
                  arg_names=("z", "W1", "W2", "W3"))


@judged
def check_solver_loss(my_loss) -> bool:
    """Check ``my_loss(decoded (N, F), target (N, F), columns, k) -> float``: Eq. (1), the mean squared
    error on the target joints' feature ``columns`` plus ``k`` times the mean squared error on the
    other features (:func:`posekit.models.pose_autoencoder.train.solver_loss`)."""
    import torch

    from ..models.pose_autoencoder.train import solver_loss

    rng = np.random.default_rng(3)
    cases = []

    def describe(got, expected):
        return (f"got {float(np.ravel(got)[0]):.6g}, expected {float(expected):.6g}; a mean per group, k on the "
                "others only?")
    for N, F, cols, k in ((4, 9, [0, 1, 2], 0.01), (10, 63, list(range(27, 33)), 0.1), (3, 6, [3, 4, 5], 1.0),
                          (5, 12, np.array([9, 10, 11, 0, 1, 2]), 0.0),  # an index array, not in order; k = 0
                          (2, 6, [0, 1, 2], 10.0)):                       # the others weighted above the targets
        d, t = rng.normal(size=(N, F)), rng.normal(size=(N, F))
        expected = float(solver_loss(F, list(cols), k)(torch.as_tensor(d), torch.as_tensor(t)))
        cases.append(((d, t, cols, k), np.float64(expected), describe))
    return report("check_solver_loss", lambda *a: np.float64(my_loss(*a)), cases, atol=1e-9, forbid=(solver_loss,),
                  arg_names=("decoded", "target", "columns", "k"))

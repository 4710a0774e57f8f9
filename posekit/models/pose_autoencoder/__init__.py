"""Lesson 03, learning-based IK with a pose autoencoder (Victor et al. 2021), in one folder.

Introduced in ``notebooks/03_autoencoder_solvers.ipynb``. The paper, section by section:

* Sec. 3.2, poses as root-frame vectors ``x`` — shared with lesson 04, so one layer down:
  :mod:`posekit.data.pose_vectors`;
* Sec. 3.3.1, the autoencoder ``E``, ``D`` — :class:`~posekit.models.pose_autoencoder.networks.PoseAutoencoder`;
  Sec. 3.3.2, the latent-space solvers ``S_t(z, p_t)`` and their loss Eq. (1) —
  :class:`~posekit.models.pose_autoencoder.networks.LatentSolver`; Sec. 3.5, chaining —
  :meth:`~posekit.models.pose_autoencoder.networks.AESolvers.latent`: all in
  :mod:`~posekit.models.pose_autoencoder.networks`, top to bottom, with their numpy twin
  (:class:`~posekit.models.pose_autoencoder.networks.NumpyAESolvers`);
* the (start, target) training pairs of Sec. 3.3.2 — :mod:`~posekit.models.pose_autoencoder.data`;
* training, Eq. (1) (:func:`~posekit.models.pose_autoencoder.train.solver_loss`) and the chaining-aware
  copies of Sec. 3.5 — :mod:`~posekit.models.pose_autoencoder.train` (``posekit train ae-solvers``);
* the Solver that poses a skeleton with them (registered as ``"neural"`` and variants) —
  :mod:`~posekit.models.pose_autoencoder.solver`; its compiled single-pose path —
  :mod:`~posekit.models.pose_autoencoder.fast` (numba, tested equal to the numpy networks);
* the lesson's measured choices (latent size, tied decoder, ``k``, chaining) —
  :mod:`~posekit.models.pose_autoencoder.studies` (``posekit train ae-studies``).
"""

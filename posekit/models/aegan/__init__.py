"""Lesson 04, an AE-GAN latent space of poses and IK by latent optimisation (Victor & Meyer, JFIG 2020),
in one folder.

Introduced in ``notebooks/04_aegan_latent_space.ipynb``. Poses are lesson 03's root-frame vectors
(:mod:`posekit.data.pose_vectors`). The paper, section by section:

* Sec. 3.2, the four networks (encoder, generator, pose and latent discriminators) —
  :mod:`~posekit.models.aegan.networks`, top to bottom, with the generator's numpy twin
  (:class:`~posekit.models.aegan.numpy_nets.NumpyAEGAN`); the structured prediction layer they are built
  from (Aksan et al. 2019, Eq. 4) — :mod:`~posekit.models.aegan.spl`;
* Eq. (1)-(5), the adversarial training — :mod:`~posekit.models.aegan.train` (``posekit train aegan``);
* Sec. 3.3, Eq. (6), IK by optimising the code — :mod:`~posekit.models.aegan.latent_opt` (Adam and
  L-BFGS, batched numpy); its compiled single-problem path — :mod:`~posekit.models.aegan.fast` (numba);
* the Solver that poses a skeleton with it (registered as ``"latent-opt"`` and variants) —
  :mod:`~posekit.models.aegan.solver`;
* measuring a latent space (invertible? is every point a pose?), set against lesson 03's autoencoder —
  :mod:`~posekit.models.aegan.latent_space`.
"""

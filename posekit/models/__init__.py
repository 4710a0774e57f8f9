"""Learned posing models, one file per paper (solver layer): lesson 03's pose autoencoder and
latent-space solvers (:mod:`~posekit.models.ae_solvers`, Victor & Meyer 2020), their data
(:mod:`~posekit.models.ae_data`), training (:mod:`~posekit.models.ae_train`) and the Solver that
poses a skeleton with them (:mod:`~posekit.models.neural_ik`, registered as ``"neural"``).
"""

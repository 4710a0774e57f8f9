"""Learned posing models, one folder per paper (solver layer), in lesson order:

* :mod:`posekit.models.pose_autoencoder` — lesson 03, learning-based IK with a pose autoencoder and
  latent-space solvers (Victor et al. 2021), the ``"neural"`` solvers;
* :mod:`posekit.models.aegan` — lesson 04, an AE-GAN latent space and IK by latent optimisation
  (Victor & Meyer, JFIG 2020), the ``"latent-opt"`` solvers;
* :mod:`posekit.models.protores` — lesson 05, ProtoRes (Oreshkin et al. 2022), the ``"protores"``
  solvers and its two baselines.

Every folder has the same inner shape: ``networks.py`` (the paper's networks, top to bottom),
``train.py``, ``solver.py`` (the Solver wrapper, the only place that knows both effectors and the
networks' vectors), ``fast.py`` (the numpy/numba inference path beside the torch model it mirrors) and
the lesson's studies; its ``__init__`` maps the paper's sections and equations to files. What two
papers share lives one layer down (pose vectors: :mod:`posekit.data.pose_vectors`; benchmarks and
their scores: :mod:`posekit.bench`).
"""

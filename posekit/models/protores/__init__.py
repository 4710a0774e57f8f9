"""Lesson 05, ProtoRes: a full pose from a variable set of effectors (Oreshkin et al. 2022), in one folder.

Introduced in ``notebooks/05_protores.ipynb``. The paper, section by section:

* Sec. 2.1, the effector inputs (Eq. 1), and the fully connected blocks the decoders are made of —
  :mod:`~posekit.models.protores.blocks`;
* Sec. 2, Eq. (2)-(6), the proto-residual encoder, the global position and inverse kinematics decoders
  and FK — :mod:`~posekit.models.protores.networks`, top to bottom; the two encoders of Table 1's
  baselines (Masked-FCR, Transformer) — :mod:`~posekit.models.protores.baselines`; the same forward
  pass in numpy for one request at a time — :mod:`~posekit.models.protores.fast`;
* Sec. 2.3 and Appendix B, Algorithm 1's batches (effectors drawn on poses, the noise models) —
  :mod:`~posekit.models.protores.data`;
* Sec. 2.2, the losses Eq. (7)-(9) and the randomized weighting — :mod:`~posekit.models.protores.train`
  (``posekit train protores``);
* the Solver that poses a skeleton with it (registered as ``"protores"`` and the baselines) —
  :mod:`~posekit.models.protores.solver`;
* Table 2's ablations and the width trade-off — :mod:`~posekit.models.protores.studies`
  (``posekit train protores-studies``).

Sec. 4's benchmarks (5-point and random effectors on held-out poses) and their scores are shared by every
solver, one layer down: :mod:`posekit.evaluation.effector_cases`, :mod:`posekit.evaluation.effector_scores`
(:func:`~posekit.models.protores.solver.run_learned` feeds them a ProtoRes's predictions).
"""

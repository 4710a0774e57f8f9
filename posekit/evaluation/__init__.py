"""Scoring posing solvers: the cases they are measured on and the scores, one stack for every benchmark.

It sits between the solvers (:mod:`posekit.ik`, whose one definition of an effector's error every score
uses) and what measures them: the learned models' studies (:mod:`posekit.models`) and the benchmark
commands (:mod:`posekit.bench`) import it, it imports neither.

* :mod:`~posekit.evaluation.pose_scores` — a method's poses on held-out posing cases
  (:mod:`posekit.data.cases`): effector, full-pose, bone-length, rotation and naturalness errors
  (``posekit bench ik``, ``posekit bench all``, lesson 03's studies);
* :mod:`~posekit.evaluation.effector_cases` — ProtoRes's two effector benchmarks (5-point and random,
  Oreshkin et al. 2022, Sec. 4), shipped as files;
* :mod:`~posekit.evaluation.effector_scores` — the paper's metrics on them (L_ikd-L2, L_gpd-L2,
  L_loc-geo, the world joint error, effector errors per kind), the classical methods run from the same
  information (``posekit bench protores``, lesson 05's studies);
* :mod:`~posekit.evaluation.measures` — the glossary: every measure's frame, reduction and unit, the column
  headers that show it, and the verdict table that ends a lesson's Discussion (``docs/measures.md``).
"""

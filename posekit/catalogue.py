"""The built-in plug-ins, in lesson order: the one list to extend when a lesson adds a solver, a trainer or
a benchmark.

Each registry (solvers: :mod:`posekit.ik.registry`; trainers: :mod:`posekit.learn.trainers`; benchmarks:
:mod:`posekit.bench.plugin` and the extra methods of ``posekit bench ik``: :mod:`posekit.bench.ik`) imports
the modules named here, by name, the first time it is asked; each module registers itself when imported.
The registries import nothing above them: this file names modules and imports none.

A new learned model is one package under :mod:`posekit.models` and a line in :data:`SOLVERS` (and one in
:data:`TRAINERS` when it is trained by ``posekit train``).
"""

SOLVERS = (
    "posekit.ik.fabrik",  # lesson 01
    "posekit.ik.ccd",
    "posekit.ik.dls",
    "posekit.models.pose_autoencoder.solver",  # lesson 03
    "posekit.models.aegan.solver",  # lesson 04
    "posekit.models.protores.solver",  # lesson 05
    "posekit.ik.finish",  # lesson 06: each learned solver with an exact finish (after the learned ones)
)
"""Modules that register solvers (``make_solver(NAME, ...)``), in lesson order."""

TRAINERS = (
    "posekit.invrig.train",  # lesson 02
    "posekit.models.pose_autoencoder.train",  # lesson 03
    "posekit.models.pose_autoencoder.studies",
    "posekit.models.aegan.train",  # lesson 04
    "posekit.models.protores.train",  # lesson 05
    "posekit.models.protores.studies",
)
"""Modules that register trainers (``posekit train NAME``), in lesson order."""

BENCHMARKS = (
    "posekit.bench.fk",
    "posekit.bench.ik",
    "posekit.bench.invrig",
    "posekit.bench.ae_scale",
    "posekit.bench.protores",
    "posekit.bench.all",
    "posekit.bench.studio",
)
"""Modules that register benchmarks (``posekit bench NAME``), in the order ``posekit bench --help`` lists them."""

BENCH_IK_METHODS = (
    "posekit.bench.ik_methods",  # lesson 01: the naive baseline, the batched FABRIK, ikpy
    "posekit.bench.ik_neural",  # lesson 03
    "posekit.bench.ik_latent",  # lesson 04
)
"""Modules that register the extra methods of ``posekit bench ik``."""

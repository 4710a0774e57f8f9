"""Benchmarks behind ``posekit bench ...``: tables and JSON, measured side by side in one run.

Each benchmark is a plug-in (:mod:`posekit.bench.plugin`): ``fk`` (:mod:`~posekit.bench.fk`), ``ik``
(:mod:`~posekit.bench.ik`, whose extra methods live in :mod:`~posekit.bench.ik_methods`) and ``invrig``
(:mod:`~posekit.bench.invrig`) register themselves; the cases and the scores of the posing benchmarks
come from the layers below (:mod:`posekit.data.cases`, :mod:`posekit.evaluation`).
"""

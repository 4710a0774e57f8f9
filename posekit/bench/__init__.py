"""Benchmarks behind ``posekit bench ...``: tables and JSON, measured side by side in one run."""

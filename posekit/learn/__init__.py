"""Shared torch layer of the learned models (solver layer): checkpoints that carry skeleton,
normalisation, config and provenance; one seeded training loop; a one-thread context.

Introduced in ``notebooks/02_inverse_rig_mapping.ipynb`` (the inverse-rig network); the learned
solvers of lessons 03-05 reuse it. ``posekit train --list`` names every model trained with it.
"""

from .checkpoint import FORMAT, FORMAT_VERSION, load_cached, load_checkpoint, require_skeleton, save_checkpoint
from .threads import limit_threads, single_thread
from .train import Curves, fit, merge_settings

__all__ = ["save_checkpoint", "load_checkpoint", "load_cached", "require_skeleton", "FORMAT", "FORMAT_VERSION", "fit", "Curves",
           "merge_settings", "single_thread", "limit_threads"]

"""Shared torch layer of the learned models (solver layer): checkpoints that carry skeleton,
normalisation, config and provenance; one seeded training loop; a one-thread context.

Introduced in ``notebooks/02_inverse_rig_mapping.ipynb`` (the inverse-rig network); the learned
solvers of lessons 03-05 reuse it. ``posekit train --list`` names every model trained with it.

Importing the package imports no torch: each name is imported from its module when first used, so the
numpy inference paths of the learned solvers (which read checkpoints and check skeletons here) stay free of
torch; ``fit`` and ``Curves`` bring it in.
"""

import importlib

_WHERE = {"FORMAT": "checkpoint", "FORMAT_VERSION": "checkpoint", "load_cached": "checkpoint",
          "load_checkpoint": "checkpoint", "require_skeleton": "checkpoint", "save_checkpoint": "checkpoint",
          "limit_threads": "threads", "single_thread": "threads", "Curves": "train", "fit": "train",
          "merge_settings": "train"}

__all__ = ["save_checkpoint", "load_checkpoint", "load_cached", "require_skeleton", "FORMAT", "FORMAT_VERSION", "fit", "Curves",
           "merge_settings", "single_thread", "limit_threads"]


def __getattr__(name):
    if name in _WHERE:
        value = getattr(importlib.import_module(f".{_WHERE[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(list(globals()) + list(_WHERE))

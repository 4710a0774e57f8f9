"""Pose data: the shipped sample, BVH folders, the Bandai Namco sets, and training utilities."""

from .dataset import NormStats, augment_positions, sample_pairs, split_by_clip
from .motion import MotionSet
from .sources import (load_bandai, load_bvh_files, load_sample, open_dataset, skeleton_preset)

__all__ = ["MotionSet", "load_sample", "load_bvh_files", "load_bandai", "open_dataset", "skeleton_preset",
           "split_by_clip", "NormStats", "augment_positions", "sample_pairs"]

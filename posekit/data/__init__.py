"""Pose data: the shipped sample, BVH folders, the Bandai Namco sets, and training utilities."""

from .dataset import NormStats, augment_positions, sample_pairs, split_by_clip, split_by_time
from .motion import MotionSet
from .sources import (load_bandai, load_bvh_files, load_sample, open_dataset, skeleton_preset)
from ..io.rigs import guess_roles, guess_units, missing_roles, rig_report
from .bandai_mini import BandaiMiniSplit, bandai_mini_split, load_bandai_mini
from .bandai_mini_build import build_bandai_mini
from .cases import START_CONDITIONS, Cases, build_cases, case_split
from .metrics import NaturalnessIndex, body_joints

__all__ = ["MotionSet", "load_sample", "load_bvh_files", "load_bandai", "open_dataset", "skeleton_preset",
           "guess_roles", "missing_roles", "rig_report", "guess_units", "split_by_clip", "split_by_time", "NormStats", "augment_positions", "sample_pairs",
           "load_bandai_mini", "bandai_mini_split", "build_bandai_mini", "BandaiMiniSplit",
           "Cases", "build_cases", "case_split", "START_CONDITIONS", "body_joints", "NaturalnessIndex"]

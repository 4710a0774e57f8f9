"""Animation rigs: controls an animator moves -> joint positions (lesson 02)."""

from .animator import animate, standard_sets
from .heuristic import heuristic_inverse
from .humanoid import CONTROLS, HumanoidRig

__all__ = ["HumanoidRig", "CONTROLS", "animate", "standard_sets", "heuristic_inverse"]

"""Animation rigs: controls an animator moves -> joint positions (lesson 02)."""

from .humanoid import CONTROLS, HumanoidRig

__all__ = ["HumanoidRig", "CONTROLS"]

"""Seeing poses: the interactive 3D viewer (pythreejs) and static matplotlib figures.

Top layer: imports the core and data layers, never a particular solver."""

from .plot import plot_pose, plot_strip
from .compare import SolverPanel
from .effector_editor import EffectorEditor
from .studio import PosingStudio
from .viewer import SkeletonViewer

__all__ = ["SkeletonViewer", "SolverPanel", "EffectorEditor", "PosingStudio", "plot_pose", "plot_strip"]

"""The posing studio's state and decisions, without widgets (``notebooks/06_posing_studio.ipynb``).

* :mod:`~posekit.studio.session` — :class:`PosingSession`: the effectors (one list, the one copy of every target),
  the solvers, their results, selection, undo/redo, setups and timeline keys;
* :mod:`~posekit.studio.solve` — :func:`solve_honoured`: a solver given the effectors of the kinds it honours (the
  one place that filters by ``solver.kinds``);
* :mod:`~posekit.studio.status` — the texts under each view and in the summary.

Layer: above the solvers (:mod:`posekit.ik`), below the views (:mod:`posekit.viz`), which show a session and report
what the mouse and the keys did to it.
"""

from .session import COALESCE_S, KIND_CHOICES, PosingSession, StudioEffector, conflict
from .solve import Solved, accepts, honoured, solve_honoured
from .status import NO_EFFECTORS, NO_EFFECTORS_SUMMARY, reached_mark, status_line, summary_rows, view_status

__all__ = ["PosingSession", "StudioEffector", "KIND_CHOICES", "COALESCE_S", "conflict", "Solved", "accepts",
           "honoured", "solve_honoured", "NO_EFFECTORS", "NO_EFFECTORS_SUMMARY", "reached_mark", "status_line",
           "summary_rows", "view_status"]

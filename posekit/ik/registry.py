"""The solver registry: solver name -> factory, with what each solver accepts.

Introduced in ``notebooks/01_fabrik.ipynb``. A solver module registers itself once, when it is
imported (``register("fabrik", FabrikSolver, ...)`` at the end of :mod:`posekit.ik.fabrik`); the
built-in modules are named, in lesson order, by :data:`posekit.catalogue.SOLVERS` and imported the
first time the registry is asked (the registry imports nothing above it); the
benchmark, the CLI, the viewer and the studio only ever ask this registry, so a solver added by a
later lesson (or by a student's notebook) is available everywhere without editing them::

    from posekit.ik import make_solver, solver_info, solver_names

    solver_names()                      # ['ccd', 'dls', 'fabrik', 'fabrik-constrained', ...]
    solver_info("dls").kinds            # ('position', 'rotation', 'look_at')
    solver = make_solver("fabrik", skeleton, max_iter=50)
    solver.solve(start_pose, effectors)

What a solver declares (``kinds``, ``needs_start``) is checked against the solver it builds, so the
registry never promises what the solver does not do.
"""

from __future__ import annotations

import inspect
from dataclasses import dataclass, field
from typing import Callable

from .. import catalogue
from ..plugins import Registry
from .effectors import normalise_kind

__all__ = ["SolverInfo", "register", "unregister", "make_solver", "solver_names", "solver_info"]


@dataclass(frozen=True)
class SolverInfo:
    """What the registry knows of a solver.

    Attributes
    ----------
    name : str
    factory : callable
        ``factory(skeleton, **config) -> Solver``.
    kinds : tuple of str
        Effector kinds it honours (``"position"``, ``"rotation"``, ``"look_at"``).
    needs_start : bool
        Whether ``solve`` needs a start pose (False for solvers that predict a whole pose).
    description : str
        One line for ``--help`` and tables.
    lesson : str
        The notebook that introduces it.
    defaults : dict
        Config passed to the factory unless overridden.
    data : str
        For a learned solver, the data set (a :func:`posekit.data.open_dataset` name) its weights were
        trained on and work with; benchmarks default to it. Empty for the classical solvers.
    """

    name: str
    factory: Callable
    kinds: tuple = ("position",)
    needs_start: bool = True
    description: str = ""
    lesson: str = ""
    defaults: dict = field(default_factory=dict)
    data: str = ""


_REGISTRY = Registry("solver", catalogue.SOLVERS, load_on_add=False)


def _kinds(kinds, what: str) -> tuple:
    if isinstance(kinds, str):
        kinds = (kinds,)
    try:
        out = tuple(dict.fromkeys(normalise_kind(k) for k in kinds))
    except ValueError as err:
        raise ValueError(f"{what}: {err}") from None
    if not out:
        raise ValueError(f"{what}: declares no effector kinds")
    return out


def register(name: str, factory: Callable, *, kinds=None, needs_start: bool | None = None,
             description: str = "", lesson: str = "", replace: bool = False, data: str = "", **defaults) -> SolverInfo:
    """Make a solver available by name everywhere (benchmark, CLI, viewer, studio).

    Parameters
    ----------
    name : str
    factory : callable
        ``factory(skeleton, **config)``, usually the solver class.
    kinds : tuple of str, optional
        Effector kinds the solver honours; default the factory's ``kinds`` attribute (a class that
        declares them), else ``("position",)``. When both are given they must agree.
    needs_start : bool, optional
        Default the factory's ``needs_start`` attribute, else True; must agree likewise.
    description, lesson : str
    replace : bool
        Redefine a registered name (e.g. while editing a notebook); without it a taken name is an error.
    data : str
        A learned solver's data set (:attr:`SolverInfo.data`).
    **defaults
        Config passed to the factory unless overridden (``constraints=True``).

    Raises
    ------
    ValueError
        When ``name`` is taken, the factory is not callable, a kind is unknown, the declared kinds or
        ``needs_start`` contradict the solver class, or a default is not a parameter of the factory.
    """
    if not name or not isinstance(name, str):
        raise ValueError(f"solver name must be a non-empty string, got {name!r}")
    if not callable(factory):
        raise ValueError(f"solver {name!r}: factory must be callable (a solver class or a function), got {factory!r}")
    what = f"solver {name!r}"
    own_kinds = getattr(factory, "kinds", None) if isinstance(factory, type) else None
    own_start = getattr(factory, "needs_start", None) if isinstance(factory, type) else None
    if kinds is None:
        kinds = own_kinds if own_kinds is not None else ("position",)
    kinds = _kinds(kinds, what)
    if own_kinds is not None and set(_kinds(own_kinds, what)) != set(kinds):
        raise ValueError(f"{what} is registered with kinds {kinds} but {factory.__name__}.kinds is "
                         f"{tuple(own_kinds)}; they must agree")
    if needs_start is None:
        needs_start = True if own_start is None else own_start
    if own_start is not None and bool(own_start) != bool(needs_start):
        raise ValueError(f"{what} is registered with needs_start={needs_start} but "
                         f"{factory.__name__}.needs_start is {own_start}")
    _check_config(name, factory, defaults)
    info = SolverInfo(name, factory, kinds, bool(needs_start), description, lesson, dict(defaults), str(data))
    return _REGISTRY.add(name, info, owner=getattr(factory, "__module__", ""), replace=replace)


def unregister(name: str) -> None:
    """Forget a registered solver (e.g. one a notebook registered to try out)."""
    if name not in _REGISTRY:
        raise ValueError(f"no solver named {name!r} is registered")
    _REGISTRY.remove(name)


def _parameters(factory):
    """The factory's config parameters after the skeleton, or None when any keyword goes."""
    try:
        params = list(inspect.signature(factory).parameters.values())
    except (TypeError, ValueError):
        return None
    if any(p.kind is p.VAR_KEYWORD for p in params):
        return None
    return [p.name for p in params[1:] if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)]


def _check_config(name, factory, config):
    allowed = _parameters(factory)
    if allowed is None:
        return
    bad = [k for k in config if k not in allowed]
    if bad:
        raise ValueError(f"solver {name!r} has no option {bad[0]!r}; its options: {', '.join(allowed) or 'none'}")


def solver_info(name: str) -> SolverInfo:
    """The registry entry of a solver; a clear error lists the valid names."""
    return _REGISTRY.get(name)


def make_solver(name: str, skeleton, **config):
    """Build a registered solver for ``skeleton`` (registry defaults, overridden by ``config``).

    The solver's ``name`` becomes the registry name (``"fabrik-constrained"``), and what it declares
    (``kinds``, ``needs_start``) must match its registry entry.

    Raises
    ------
    ValueError
        An unknown solver (listing the valid ones), an option the factory does not take (listing its
        options), or a solver that contradicts its registry entry.
    """
    info = solver_info(name)
    config = {**info.defaults, **config}
    _check_config(name, info.factory, config)
    solver = info.factory(skeleton, **config)
    kinds = getattr(solver, "kinds", None)
    if kinds is None or set(_kinds(kinds, f"solver {name!r}")) != set(info.kinds):
        raise ValueError(f"solver {name!r} built a solver declaring kinds {kinds!r}, but it is registered with "
                         f"{info.kinds}")
    if bool(getattr(solver, "needs_start", True)) != info.needs_start:
        raise ValueError(f"solver {name!r} built a solver with needs_start={getattr(solver, 'needs_start', None)!r}, "
                         f"but it is registered with needs_start={info.needs_start}")
    try:
        solver.name = name
    except AttributeError:  # a read-only name: leave it
        pass
    return solver


def solver_names() -> list[str]:
    """Every registered solver name: the built-in ones in lesson order (:data:`posekit.catalogue.SOLVERS`),
    then the others in registration order."""
    return _REGISTRY.names()

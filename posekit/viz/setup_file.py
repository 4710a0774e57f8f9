"""Effector setups as JSON files: what the posing studio saves and loads.

Introduced in ``notebooks/06_posing_studio.ipynb``. A setup is the studio's effector list (the rows of
:class:`~posekit.viz.EffectorEditor`, :meth:`~posekit.viz.EffectorEditor.setup`) with the skeleton's joint
names and the solvers being compared, so that a student can hand a pose problem to someone else::

    {"format": "posekit-effector-setup", "version": 1,
     "skeleton": ["joint_Root", "Hips", ...],
     "solvers": ["fabrik", "protores"],
     "effectors": [
        {"joint": "Hand_L", "kind": "position", "lam": 0.0, "target": [0.31, 1.12, 0.25]},
        {"joint": "Chest", "kind": "rotation", "lam": 0.2, "base": [[1, 0, 0], [0, 1, 0], [0, 0, 1]],
         "euler": [30, 0, 0]},
        {"joint": "Head", "kind": "look_at", "lam": 0.0, "target": [0, 1.6, 1.5], "axis": [0, 0, 1]}]}

Units: metres for targets, degrees for ``euler`` (yaw about Y, pitch about X, roll about Z, world frame, on
top of ``base``, the joint's world rotation matrix); ``lam`` is the tolerance slider's value in [0, 1].
A malformed file raises :class:`SetupError` naming the file, and the line and column for broken JSON;
the effectors themselves are checked by :meth:`~posekit.viz.EffectorEditor.set_setup`.
"""

from __future__ import annotations

import json
from pathlib import Path

__all__ = ["FORMAT", "SetupError", "setup_to_json", "parse_setup", "save_setup", "load_setup"]

FORMAT = "posekit-effector-setup"
VERSION = 1


class SetupError(ValueError):
    """A setup file that cannot be read; the message names the file (and line and column)."""


def setup_to_json(skeleton, effectors, solvers=()) -> str:
    """A setup as JSON text: ``effectors`` are :meth:`EffectorEditor.setup` rows, ``solvers`` names."""
    doc = {"format": FORMAT, "version": VERSION, "skeleton": list(skeleton.names), "solvers": list(solvers),
           "effectors": list(effectors)}
    return json.dumps(doc, indent=1) + "\n"


def parse_setup(text: str, skeleton, source: str = "setup") -> dict:
    """Read setup JSON text: ``{"effectors": [...], "solvers": [...]}``.

    Raises
    ------
    SetupError
        Broken JSON (with line and column), another format, a newer version, another skeleton, or fields
        of the wrong type.
    """
    try:
        doc = json.loads(text)
    except json.JSONDecodeError as err:
        raise SetupError(f"{source}, line {err.lineno}, column {err.colno}: not valid JSON ({err.msg})") from None
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        raise SetupError(f"{source}: not a posekit effector setup (expected a JSON object with "
                         f'"format": "{FORMAT}")')
    if not isinstance(doc.get("version"), int) or doc["version"] > VERSION:
        raise SetupError(f"{source}: setup version {doc.get('version')!r}; this posekit reads version {VERSION}")
    names = doc.get("skeleton")
    if names is not None and list(names) != list(skeleton.names):
        missing = [n for n in names if n not in skeleton.names][:3]
        raise SetupError(f"{source}: made for another skeleton ({len(names)} joints"
                         f"{', e.g. ' + ', '.join(map(repr, missing)) if missing else ''}); this one has "
                         f"{skeleton.n_joints}: {', '.join(skeleton.names[:4])}, ...")
    effectors = doc.get("effectors")
    if not isinstance(effectors, list) or not all(isinstance(e, dict) for e in effectors):
        raise SetupError(f'{source}: "effectors" must be a list of objects')
    solvers = doc.get("solvers", [])
    if not isinstance(solvers, list) or not all(isinstance(n, str) for n in solvers):
        raise SetupError(f'{source}: "solvers" must be a list of solver names')
    return {"effectors": effectors, "solvers": solvers}


def save_setup(path, skeleton, effectors, solvers=()) -> Path:
    """Write a setup file (see the module docstring); returns its path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(setup_to_json(skeleton, effectors, solvers), encoding="utf-8")
    return path


def load_setup(path, skeleton) -> dict:
    """Read a setup file: ``{"effectors": [...], "solvers": [...]}`` (see :func:`parse_setup`)."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as err:
        raise SetupError(f"{path}: cannot read the setup file ({err})") from None
    return parse_setup(text, skeleton, source=str(path))

"""What passes between a checker's judge and the process that runs the student's function: JSON lines only.

The judge (:mod:`posekit.exercises._judge`) holds the expected answers; the student's function runs in another
process. What crosses is data, never code: numbers, strings, ``None``, lists, tuples, dicts with string keys, NumPy
arrays (``.npy`` bytes read with ``allow_pickle=False``), torch tensors (as their arrays, dtype kept) and posekit's
:class:`~posekit.skeleton.Skeleton` (its fields). Nothing is
unpickled, so an answer cannot make the judge run code by what it returns; anything else arrives as
:class:`Unsupported`, which no comparison accepts.
"""

from __future__ import annotations

import base64
import io
import json

import numpy as np

__all__ = ["encode", "decode", "dumps", "loads", "Unsupported"]


class Unsupported:
    """A value of a type the wire does not carry (its type's name is kept for the message)."""

    def __init__(self, type_name: str):
        self.type_name = type_name

    def __repr__(self) -> str:
        return f"<a {self.type_name}>"


def _npy(a: np.ndarray) -> str:
    buf = io.BytesIO()
    np.save(buf, np.ascontiguousarray(a), allow_pickle=False)
    return base64.b64encode(buf.getvalue()).decode()


def encode(value):
    """``value`` as JSON-ready data (see the module docstring)."""
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    if isinstance(value, np.generic):
        return encode(value.item())
    if isinstance(value, np.ndarray):
        if value.dtype == object:
            return {"unsupported": "ndarray of objects"}
        return {"ndarray": _npy(value)}
    if type(value).__module__ == "torch" and type(value).__name__ in ("Tensor", "Parameter"):
        return {"tensor": _npy(value.detach().cpu().numpy())}
    if type(value).__name__ == "Skeleton" and type(value).__module__ == "posekit.skeleton":
        return {"skeleton": {"names": list(value.names), "parents": encode(value.parents),
                             "offsets": encode(value.offsets), "roles": encode(dict(value.roles)), "name": value.name,
                             "end_sites": [[int(k), encode(v)] for k, v in value.end_sites.items()]}}
    if isinstance(value, tuple):
        return {"tuple": [encode(v) for v in value]}
    if isinstance(value, list):
        return [encode(v) for v in value]
    if isinstance(value, dict) and all(isinstance(k, str) for k in value):
        return {"dict": {k: encode(v) for k, v in value.items()}}
    return {"unsupported": type(value).__name__}


def _array(text: str) -> np.ndarray:
    return np.load(io.BytesIO(base64.b64decode(text)), allow_pickle=False)


def decode(data):
    """The value :func:`encode` made ``data`` from."""
    if isinstance(data, list):
        return [decode(v) for v in data]
    if not isinstance(data, dict):
        return data
    if "ndarray" in data:
        return _array(data["ndarray"])
    if "tensor" in data:
        import torch

        return torch.from_numpy(_array(data["tensor"]).copy())
    if "tuple" in data:
        return tuple(decode(v) for v in data["tuple"])
    if "skeleton" in data:
        from ..skeleton import Skeleton

        d = data["skeleton"]
        return Skeleton(names=tuple(d["names"]), parents=decode(d["parents"]), offsets=decode(d["offsets"]),
                        roles=decode(d["roles"]), name=d["name"],
                        end_sites={int(k): decode(v) for k, v in d["end_sites"]})
    if "dict" in data:
        return {k: decode(v) for k, v in data["dict"].items()}
    return Unsupported(str(data.get("unsupported", "value")))


def dumps(message: dict) -> str:
    """One protocol line."""
    return json.dumps(message, separators=(",", ":"), allow_nan=True) + "\n"


def loads(line: str) -> dict:
    message = json.loads(line)
    if not isinstance(message, dict):
        raise ValueError("a protocol line is a JSON object")
    return message

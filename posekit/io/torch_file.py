"""Read a file written by ``torch.save`` without torch: tensors come back as numpy arrays.

Introduced in ``notebooks/06_posing_studio.ipynb`` (the studio's small kernels): a learned solver posing one
pose at a time runs numpy code (each model's ``fast`` module), so a process that only poses need not import
torch (about 220 MB and a second and a half) just to read its weights.

The format (torch >= 1.6, "zip"): a zip archive ``NAME/data.pkl`` — a pickle whose tensors refer to
storages by key — and ``NAME/data/KEY``, each storage's raw bytes (``NAME/byteorder`` says which byte
order). This reader accepts exactly what posekit checkpoints hold (:mod:`posekit.learn.checkpoint`): plain
Python values, ``OrderedDict`` and dense tensors of the numeric storage types below; any other object in the
pickle is refused, as ``torch.load(..., weights_only=True)`` refuses it, so reading a file runs no code from it.
"""

from __future__ import annotations

import pickle
import zipfile
from collections import OrderedDict
from pathlib import Path

import numpy as np

__all__ = ["read_torch_file", "STORAGE_DTYPES"]

STORAGE_DTYPES = {
    "FloatStorage": np.float32, "DoubleStorage": np.float64, "HalfStorage": np.float16,
    "LongStorage": np.int64, "IntStorage": np.int32, "ShortStorage": np.int16, "CharStorage": np.int8,
    "ByteStorage": np.uint8, "BoolStorage": np.bool_,
}
"""torch's storage type names -> numpy dtypes (bfloat16 and complex storages are not read)."""


class _Storage:
    """A storage's type, read lazily by key from the archive."""

    def __init__(self, dtype):
        self.dtype = dtype


def _rebuild_tensor(storage, offset, size, stride, requires_grad=False, hooks=None, metadata=None):
    """``torch._utils._rebuild_tensor_v2``: a view of a storage (elements, not bytes) as an array."""
    flat, itemsize = storage
    size, stride = tuple(int(s) for s in size), tuple(int(s) for s in stride)
    if not size:
        return np.array(flat[int(offset)])
    view = np.lib.stride_tricks.as_strided(flat[int(offset):], shape=size,
                                           strides=tuple(s * itemsize for s in stride))
    return np.array(view)  # own, contiguous, writable


class _Unpickler(pickle.Unpickler):
    def __init__(self, file, archive: zipfile.ZipFile, prefix: str, byteorder: str):
        super().__init__(file)
        self._archive, self._prefix, self._order = archive, prefix, byteorder
        self._storages: dict = {}

    def find_class(self, module, name):
        if module == "collections" and name == "OrderedDict":
            return OrderedDict
        if module == "torch._utils" and name in ("_rebuild_tensor_v2", "_rebuild_tensor"):
            return _rebuild_tensor
        if module == "torch" and name in STORAGE_DTYPES:
            return _Storage(STORAGE_DTYPES[name])
        raise pickle.UnpicklingError(f"{module}.{name} is not a plain value or a dense numeric tensor; this reader "
                                     "accepts what posekit checkpoints hold (read other files with torch.load)")

    def persistent_load(self, pid):
        if not (isinstance(pid, tuple) and len(pid) >= 3 and pid[0] == "storage" and isinstance(pid[1], _Storage)):
            raise pickle.UnpicklingError(f"unexpected persistent id {pid!r:.80}")
        storage, key = pid[1], str(pid[2])
        if key not in self._storages:
            raw = self._archive.read(f"{self._prefix}data/{key}")
            dtype = np.dtype(storage.dtype).newbyteorder("<" if self._order == "little" else ">")
            self._storages[key] = (np.frombuffer(raw, dtype=dtype).astype(np.dtype(storage.dtype).newbyteorder("=")),
                                   np.dtype(storage.dtype).itemsize)
        return self._storages[key]


def read_torch_file(path):
    """The object ``torch.save`` wrote to ``path``, every tensor a numpy array of its dtype (float16 stays
    float16).

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    object
        Plain Python values, ``OrderedDict`` and numpy arrays.

    Raises
    ------
    FileNotFoundError
        No file at ``path``.
    ValueError
        Not a zip-format torch file (truncated, corrupt, the legacy format), or it holds an object other than
        plain values and dense numeric tensors; the message says which.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"no file at {path}")
    try:
        with zipfile.ZipFile(path) as archive:
            pkl = [n for n in archive.namelist() if n.endswith("data.pkl") and n.count("/") == 1]
            if not pkl:
                raise ValueError("the archive holds no NAME/data.pkl")
            prefix = pkl[0][: -len("data.pkl")]
            names = set(archive.namelist())
            order = archive.read(prefix + "byteorder").decode().strip() if prefix + "byteorder" in names else "little"
            with archive.open(pkl[0]) as f:
                return _Unpickler(f, archive, prefix, order).load()
    except zipfile.BadZipFile as e:
        raise ValueError(f"{path} is not a zip-format torch file ({e})") from e
    except (pickle.UnpicklingError, EOFError, KeyError, ValueError, TypeError, IndexError) as e:
        raise ValueError(f"{path}: {type(e).__name__}: {e}") from e

r"""Reading ``.npy`` and ``.npz`` dataset files without running their code.

A ``.npy`` file of an object array (the per-grasp dicts of grasp-synthesis pipelines, saved by
``np.save(path, dict)``) holds a pickle after its header. ``np.load(allow_pickle=True)`` would
run whatever that pickle names; [`load_npy()`][mjtvm.grasp.document.safe_npy.load_npy] reads the
header itself and unpickles the rest with [`DataUnpickler`][mjtvm.grasp.document.safe_npy.DataUnpickler],
which builds only numpy arrays, dtypes and scalars (besides the dicts, lists, strings and numbers
that pickle builds without naming a class): any other global, a callable such as ``os.system``
or ``builtins.eval`` included, is refused before anything is called.
"""

from __future__ import annotations

import io
import pickle
import zipfile
from pathlib import Path
from typing import Any

import numpy as np
from numpy.lib import format as npformat

__all__ = ["DataUnpickler", "UnsafePickle", "load_npy", "load_npz"]

_ALLOWED = {
    # What numpy's own pickles of arrays, dtypes and scalars name (numpy 1.x and 2.x modules).
    ("numpy.core.multiarray", "_reconstruct"),
    ("numpy._core.multiarray", "_reconstruct"),
    ("numpy.core.multiarray", "scalar"),
    ("numpy._core.multiarray", "scalar"),
    ("numpy", "ndarray"),
    ("numpy", "dtype"),
    # Protocol 2 pickles spell bytes through codecs.encode of a latin-1 string: data, no code.
    ("_codecs", "encode"),
}


class UnsafePickle(pickle.UnpicklingError):
    """A pickle that names a global other than numpy's array, dtype and scalar builders."""


class DataUnpickler(pickle.Unpickler):
    """A ``pickle.Unpickler`` that finds only numpy's array, dtype and scalar builders."""

    def find_class(self, module: str, name: str) -> Any:
        if (module, name) not in _ALLOWED:
            raise UnsafePickle(
                f"the pickle names {module}.{name}: only numpy arrays, numbers, strings and dicts are read"
            )
        return super().find_class(module, name)


def _unpickle(data: bytes) -> Any:
    return DataUnpickler(io.BytesIO(data)).load()


def load_npy(path: Path) -> Any:
    r"""The content of a ``.npy`` file: a number array, or the object a pickled object array holds.

    A 0-d object array gives its item (a per-grasp dict); an ``(N,)`` object array its list of
    items (a per-object list of dicts).

    Raises
    ------
    ValueError
        Not a ``.npy`` file (e.g. a zip: a ``.npz`` renamed), a damaged header or data.
    UnsafePickle
        A pickle that names anything but numpy's array builders.
    """
    with path.open("rb") as f:
        head = f.read(6)
        if head[:2] == b"PK":
            raise ValueError("a zip archive (an .npz?), not an .npy file")
        if head != b"\x93NUMPY":
            raise ValueError("not an .npy file (no NUMPY magic)")
        f.seek(0)
        version = npformat.read_magic(f)
        if version == (1, 0):
            shape, _fortran, dtype = npformat.read_array_header_1_0(f)
        elif version == (2, 0):
            shape, _fortran, dtype = npformat.read_array_header_2_0(f)
        else:
            raise ValueError(f"unknown .npy version {version}")
        if not dtype.hasobject:
            f.seek(0)
            return np.load(f, allow_pickle=False)
        value = _unpickle(f.read())
    if not isinstance(value, np.ndarray) or value.shape != tuple(shape):
        raise ValueError(f"the pickle does not hold the header's object array of shape {tuple(shape)}")
    return value.item() if value.shape == () else list(value.reshape(-1))


def load_npz(path: Path) -> dict[str, np.ndarray]:
    """The arrays of a ``.npz`` file, read without pickle.

    Raises
    ------
    ValueError
        Not a zip, a damaged or truncated member, or an object array.
    """
    with path.open("rb") as f:
        if f.read(2) != b"PK":
            raise ValueError("not an .npz (zip) archive")
        f.seek(0)
        try:  # numpy leaves its own file open when the archive is damaged: give it ours
            with np.load(f, allow_pickle=False) as z:
                return {k: z[k] for k in z.files}
        except (zipfile.BadZipFile, EOFError, OSError, KeyError) as e:
            raise ValueError(f"not a readable .npz (zip) archive: {e}") from e

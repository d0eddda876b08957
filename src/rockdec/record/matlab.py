"""MATLAB ``.mat`` records (the format shaking-table laboratories often write), read with
:func:`scipy.io.loadmat` (MATLAB v4 to v7; a v7.3 file is HDF5 and is refused with the fix)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rockdec.timeaxis import RecordError, sampling_step

#: Names of a time vector looked for in a ``.mat`` file, in order.
TIME_NAMES = ("time", "t")


def _vector(value, path: Path, name: str) -> np.ndarray:
    array = np.asarray(value)
    if array.dtype.kind not in "fiu" or array.ndim > 2 or (array.ndim == 2 and 1 not in array.shape):
        raise RecordError(f"{path}: '{name}' holds a {array.dtype} array of shape {array.shape}; store a vector of numbers.")
    return array.astype(np.float64).ravel()


def read_mat(path: Path, variable: str, step: float | None) -> tuple[np.ndarray, float | None]:
    """The angle ``variable`` of a ``.mat`` file and its step: ``step`` when given, else
    from a time vector (:data:`TIME_NAMES`) or a scalar ``dt``/``fs`` stored beside it
    (``None`` when the file has none: the caller asks for ``dt``)."""
    from scipy.io import loadmat
    from scipy.io.matlab import MatReadError

    with open(path, "rb") as f:
        head = f.read(128)
    if b"MATLAB 7.3" in head or head[:8] == b"\x89HDF\r\n\x1a\n":
        raise RecordError(f"{path}: a MATLAB v7.3 (HDF5) file, which rockdec does not read; save it with save(..., '-v7').")
    try:
        data = loadmat(path, squeeze_me=False)
    except (MatReadError, ValueError, OSError) as exc:
        raise RecordError(f"{path}: not a readable .mat file ({exc}).") from None
    names = [k for k in data if not k.startswith("__")]
    if variable not in data:
        raise RecordError(f"{path}: no variable '{variable}' (variables: {', '.join(names) or 'none'}); name it with `variable`.")
    values = _vector(data[variable], path, variable)
    if step is None:
        for name in TIME_NAMES:
            if name in data:
                time = _vector(data[name], path, name)
                if time.size != values.size:
                    raise RecordError(f"{path}: '{name}' has {time.size} values and '{variable}' {values.size}; store one time per sample.")
                return values, sampling_step(time, str(path))
        for name, to_step in (("dt", lambda x: x), ("fs", lambda x: 1.0 / x)):
            if name in data and np.asarray(data[name]).size == 1:
                return values, float(to_step(float(np.asarray(data[name]).ravel()[0])))
    return values, step

"""MATLAB ``.mat`` records (the format shaking-table laboratories often write), read with
:func:`scipy.io.loadmat` (MATLAB v4 to v7; a v7.3 file is HDF5 and is refused with the fix)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rockdec.timeaxis import RecordError, sampling_step

__all__ = ["read_mat"]

#: Names of a time vector looked for in a ``.mat`` file, in order.
TIME_NAMES = ("time", "t")


def _kind(array: np.ndarray) -> str | None:
    """What a MATLAB value that is not a real number array is (``None`` for one that is)."""
    if array.dtype.kind == "O":
        return "a cell array"
    if array.dtype.names is not None:
        return "a struct"
    if array.dtype.kind in "US":
        return "text"
    if array.dtype.kind not in "fiu":
        return f"{'complex' if array.dtype.kind == 'c' else array.dtype.name} values"
    return None


def _vector(value, path: Path, name: str) -> np.ndarray:
    array = np.asarray(value)
    kind = _kind(array)
    if kind is not None:
        fix = f"store the vector itself ({name} = {name}{{1}})" if array.dtype.kind == "O" else "store a vector of real numbers"
        raise RecordError(f"{path}: '{name}' holds {kind} of size {'x'.join(map(str, array.shape))}, not a vector of real numbers; {fix}.")
    if array.size == 0:
        raise RecordError(f"{path}: '{name}' is empty; store its values.")
    if array.ndim > 2 or (array.ndim == 2 and 1 not in array.shape):
        raise RecordError(f"{path}: '{name}' is a {'x'.join(map(str, array.shape))} matrix; store a vector of numbers.")
    return array.astype(np.float64).ravel()


def _step(data: dict, path: Path, name: str) -> float:
    """The sampling step (s) a scalar ``dt`` (s) or ``fs`` (Hz) of the file gives, refused in
    one sentence unless it is one real number > 0 with a finite step."""
    array = np.asarray(data[name])
    kind = _kind(array) or (None if array.size == 1 else f"{array.size} values")
    unit = "s" if name == "dt" else "Hz"
    if kind is not None:
        raise RecordError(f"{path}: '{name}' holds {kind}, not one number; store {name} as a number of {unit}, or give `{name}`.")
    value = float(array.ravel()[0])
    step = value if name == "dt" else 1.0 / value if value else float("inf")
    if not (np.isfinite(value) and value > 0 and np.isfinite(step) and step > 0):
        raise RecordError(f"{path}: '{name}' is {value:g}, not a positive, finite number of {unit}"
                          f"{'' if name == 'dt' else ' with a finite step 1/fs'}; store the file's {name} in {unit}, > 0, or give `{name}`.")
    return step


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
        for name in ("dt", "fs"):
            if name in data:
                return values, _step(data, path, name)
    return values, step

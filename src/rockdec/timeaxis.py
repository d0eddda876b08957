"""The time axis of a record or a simulated series: uniform and increasing, or refused.

Shared by the reader of measured records (:mod:`rockdec.records`) and the signature wrapper
(:mod:`rockdec.signatures`), so the kernels' side never imports a file reader.
"""

from __future__ import annotations

import numpy as np

from rockdec.validate import InputError

#: Relative tolerance on the spacing of a time axis (printed times are rounded).
TIME_RTOL = 1e-3


class RecordError(InputError):
    """A record the user can fix; the message names the file, the problem and the fix."""


def sampling_step(time, source: str, min_samples: int = 2) -> float:
    """The step of a time axis (s), refusing one that is not uniform and increasing, or that
    has fewer than 2 values (``min_samples``: the fewest samples the caller's record needs,
    named in that sentence)."""
    t = np.asarray(time)
    if np.issubdtype(t.dtype, np.datetime64) or np.issubdtype(t.dtype, np.timedelta64):
        t = (t - t[0]) / np.timedelta64(1, "s")
    t = t.astype(np.float64)
    if t.size < 2:
        raise RecordError(f"{source}: the time axis has {t.size} value(s); a record needs at least {min_samples} samples.")
    if not np.all(np.isfinite(t)):
        row = int(np.flatnonzero(~np.isfinite(t))[0])
        raise RecordError(f"{source}: time value {row} is {t[row]}; every time stamp must be a finite number of seconds.")
    step = np.diff(t)
    if np.any(step <= 0):
        row = int(np.flatnonzero(step <= 0)[0]) + 1
        what = "repeats" if step[row - 1] == 0 else "goes back"
        raise RecordError(f"{source}: time {what} at sample {row} (t = {t[row]:g} s); sort the record and drop duplicate stamps.")
    median = float(np.median(step))
    bad = np.abs(step - median) > TIME_RTOL * median
    if np.any(bad):
        row = int(np.flatnonzero(bad)[0]) + 1
        raise RecordError(
            f"{source}: time is not uniformly sampled (step {step[row - 1]:g} s at sample {row}, typical {median:g} s); "
            "resample it to a uniform step, or mark missing samples as NaN on a uniform time axis."
        )
    return float((t[-1] - t[0]) / (t.size - 1))

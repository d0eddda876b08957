"""The time axis of a record or a simulated series: uniform and increasing, or refused; and
the ``units`` of stored angles and times, converted to rad and s or refused.

Shared by the reader of measured records (:mod:`rockdec.record.records`) and the signature wrapper
(:mod:`rockdec.rdd.signatures`), so the kernels' side never imports a file reader.
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


#: ``units`` of an angle variable and their factor to rad (CF/UDUNITS spellings).
ANGLE_UNITS = {"rad": 1.0, "radian": 1.0, "radians": 1.0, "1": 1.0,
               "mrad": 1e-3, "milliradian": 1e-3, "milliradians": 1e-3,
               "degree": np.pi / 180, "degrees": np.pi / 180, "deg": np.pi / 180}

#: ``units`` of a time coordinate and their factor to s (CF/UDUNITS spellings; a reference
#: date, ``"nanoseconds since 2020-01-01"`` as xarray writes datetimes, only shifts the origin).
TIME_UNITS = {"s": 1.0, "sec": 1.0, "second": 1.0, "seconds": 1.0,
              "ms": 1e-3, "millisecond": 1e-3, "milliseconds": 1e-3,
              "us": 1e-6, "microsecond": 1e-6, "microseconds": 1e-6,
              "ns": 1e-9, "nanosecond": 1e-9, "nanoseconds": 1e-9,
              "min": 60.0, "minute": 60.0, "minutes": 60.0,
              "h": 3600.0, "hr": 3600.0, "hour": 3600.0, "hours": 3600.0,
              "d": 86400.0, "day": 86400.0, "days": 86400.0}


def _factor(units, table: dict, source: str, what: str, fix: str) -> float:
    """The factor that converts ``what`` in ``units`` (``None``: not stated) to SI by ``table``."""
    if units is None:
        return 1.0
    unit = str(units).split(" since ")[0].strip()
    if unit.lower() not in table:
        known = ", ".join(sorted({k for k in table if len(k) > 1}))
        raise RecordError(f"{source}: {what} has units '{units}', which rockdec does not convert; {fix} (known: {known}).")
    return table[unit.lower()]


def angle_factor(units, source: str, variable: str) -> float:
    """The factor from an angle in ``units`` (a NetCDF ``units`` attribute, ``None``: rad) to rad."""
    return _factor(units, ANGLE_UNITS, source, f"'{variable}'", "store the angle in rad, mrad or degrees")


def time_factor(units, source: str, name: str) -> float:
    """The factor from a time coordinate in ``units`` (``None``: s) to s."""
    return _factor(units, TIME_UNITS, source, f"the time coordinate '{name}'", "store it in s or ms")

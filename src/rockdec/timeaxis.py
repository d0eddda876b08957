"""The time axis of a record or a simulated series: uniform and increasing, or refused; and
the ``units`` of stored angles and times, converted to rad and s or refused.

Shared by the reader of measured records (:mod:`rockdec.record.records`) and the signature wrapper
(:mod:`rockdec.rdd.signatures`), so the kernels' side never imports a file reader.
"""

from __future__ import annotations

import numpy as np

from rockdec.validate import InputError

__all__ = ["ANGLE_UNITS", "RecordError", "angle_factor", "sampling_step", "time_factor"]

#: Relative tolerance on the spacing of a time axis read as uniform without looking at its
#: digits (each step within it of the median step).
TIME_RTOL = 1e-3

#: A time axis read as uniform by its printed precision must have a step ``h`` this many times
#: the widest rounding ``r`` of a step (of its two times), so that a missing sample shows: its
#: step, ``2 h`` rounded by up to ``r``, then differs from ``h`` by more than ``r``.
MIN_STEP_OVER_ROUNDING = 2.0


class RecordError(InputError):
    """A record the user can fix; the message names the file, the problem and the fix."""


#: The way past a time axis whose samples are uniform but whose times do not say so.
DROP_TIME = "if the samples are uniform, drop the time axis and give the step as `dt` (s) or `fs` (Hz)"

#: What to do with a time axis that is not uniform (the end of its refusal).
NOT_UNIFORM_FIX = f"resample the record to a uniform step, mark missing samples as NaN on a uniform time axis, or, {DROP_TIME}"


def sampling_step(time, source: str, min_samples: int = 2) -> float:
    """The step of a time axis (s), refusing one that is not uniform and increasing, or that
    has fewer than 2 values (``min_samples``: the fewest samples the caller's record needs,
    named in that sentence).

    A time axis whose every step is within :data:`TIME_RTOL` of the median step has the step
    ``(t[-1] - t[0]) / (n - 1)``. One that is not, but lies on a uniform axis within the
    rounding of its values (:func:`rounding`: times printed with few digits, such as ``%.3f``
    of a 1/300 s step, or stored as float32), has the least-squares step of the whole axis:
    each step within the rounding of its two times (and :data:`TIME_RTOL`) of that step, and
    that step at least :data:`MIN_STEP_OVER_ROUNDING` times the rounding, so that a missing
    sample would show. Any other axis is refused, saying what to do.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.round(np.arange(3000) / 300, 3)  # printed with %.3f: steps of 0.003 and 0.004 s
    >>> round(1 / sampling_step(t, "rec.csv"), 3)  # the least-squares step
    300.0
    >>> t[1500:] += 1 / 300  # a sample missing
    >>> sampling_step(t, "rec.csv")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    rockdec.timeaxis.RecordError: rec.csv: time is not uniformly sampled: ...
    """
    t = np.asarray(time)
    if np.issubdtype(t.dtype, np.datetime64) or np.issubdtype(t.dtype, np.timedelta64):
        t = (t - t[0]) / np.timedelta64(1, "s")
    single = t.dtype == np.float32
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
    if np.all(np.abs(step - median) <= TIME_RTOL * median):
        return float((t[-1] - t[0]) / (t.size - 1))
    return _rounded_step(t, step, rounding(t, single), source)


def _rounded_step(t: np.ndarray, step: np.ndarray, bound: np.ndarray, source: str) -> float:
    """The least-squares step of the time axis ``t`` (steps ``step``) if it lies on a uniform
    axis within the rounding ``bound`` of each time (:func:`sampling_step`), else refused."""
    k = np.arange(t.size) - (t.size - 1) / 2
    fitted = float(np.dot(k, t - t.mean()) / np.dot(k, k))
    pair = bound[:-1] + bound[1:]
    if pair.max() * MIN_STEP_OVER_ROUNDING >= fitted:
        raise RecordError(
            f"{source}: time is not uniformly sampled at the precision of its values (steps from {step.min():g} to {step.max():g} s, "
            f"its times rounded by up to {bound.max():.2g} s, too coarse to tell a missing sample at a step of {fitted:.6g} s); "
            f"write the times with more digits, or, {DROP_TIME}."
        )
    off = np.abs(step - fitted) - pair - TIME_RTOL * fitted
    if off.max() > 0:
        row = int(np.argmax(off)) + 1
        raise RecordError(
            f"{source}: time is not uniformly sampled: the step {step[row - 1]:g} s at sample {row} (t = {t[row]:g} s) is not the step "
            f"{fitted:.6g} s fitted to the whole axis, even within the rounding of its times (+-{pair[row - 1]:.2g} s); {NOT_UNIFORM_FIX}."
        )
    return fitted


def rounding(t: np.ndarray, single: bool = False) -> np.ndarray:
    """How far each time of ``t`` (float64) may lie from the value it was rounded from: half
    the last digit it was written with, and the float32 spacing when it went through float32.

    The digits are those of each value's shortest decimal form (``repr``). Times written with
    a fixed number of decimals (``%.3f``) are all multiples of the finest last digit among
    them, and most end on it; times written with a fixed number of significant digits
    (``%.10g``) have at most the most significant digits among them, and most have that many.
    The reading that more of the times fit sets their rounding (the decimals on a tie).
    ``single`` (the axis was stored as float32), or every value a float32 or, written with 8
    significant digits or more, a float32's shortest decimal form, adds the float32 spacing at
    that time (half for the rounding to float32, half for the shortest form).

    Examples
    --------
    >>> import numpy as np
    >>> rounding(np.array([0.003, 0.007, 0.01, 10.003])).round(6)  # %.3f: half of 0.001
    array([0.0005, 0.0005, 0.0005, 0.0005])
    >>> rounding(np.array([0.1, 0.1034567891, 12.34567891])).round(12)  # %.10g: half the 10th digit
    array([5.e-11, 5.e-11, 5.e-09])
    """
    texts = [repr(x) for x in t.tolist()]
    last = np.array([_last_digit(text) for text in texts], dtype=np.float64)  # inf for 0
    nonzero = t != 0
    lead = np.full(t.size, np.nan)
    lead[nonzero] = np.floor(np.log10(np.abs(t[nonzero])))
    finest = np.min(last)
    digits = np.max(lead[nonzero] - last[nonzero]) + 1 if nonzero.any() else 0.0
    as_fixed = np.mean(last[nonzero] == finest) if nonzero.any() else 1.0
    as_significant = np.mean(lead[nonzero] - last[nonzero] + 1 == digits) if nonzero.any() else 0.0
    if as_fixed >= as_significant:
        bound = np.full(t.size, 0.5 * 10.0**finest)
    else:
        bound = np.where(nonzero, 0.5 * 10.0 ** (np.nan_to_num(lead) - digits + 1), 0.5 * 10.0**finest)
    bound += 2.0 * np.spacing(np.abs(t))
    as_single = t.astype(np.float32)
    if single or np.array_equal(as_single, t) or (digits >= 8 and all(str(v) == text for v, text in zip(as_single, texts))):
        bound += np.spacing(np.abs(as_single)).astype(np.float64)  # rounded to float32, then perhaps printed
    return bound


def _last_digit(text: str) -> float:
    """The power of ten of the last significant digit of the decimal ``text`` (``repr`` of a
    float: ``'0.0035'`` -> -4, ``'1200.0'`` -> 2, ``'1.5e-07'`` -> -8); inf for zero."""
    mantissa, _, exponent = text.lstrip("-").partition("e")
    whole, _, fraction = mantissa.partition(".")
    fraction = fraction.rstrip("0")
    if fraction:
        return int(exponent or 0) - len(fraction)
    stripped = whole.rstrip("0")
    return float("inf") if not stripped else int(exponent or 0) + len(whole) - len(stripped)


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

"""Repair of a measured record before its estimate: spikes are replaced, drift is filtered out.

Two defects of a rig's record are repaired rather than reported (the checks ``spikes`` and
``drift`` of :mod:`rockdec.record.diagnostics` find them), by :func:`apply`:

* Spikes (:func:`find_spikes`): a spike of height ``a`` at sample ``k`` leaves the second
  differences ``d[k] = y[k+1] - 2 y[k] + y[k-1]`` the pattern ``(a, -2a, a)``, where an
  impact (eq. 6) moves one or two of one sign; a sample is a spike when its second
  difference is the largest of its three, beyond ``2 SPIKE_Z s``, and a neighbour's of the
  other sign beyond ``SPIKE_Z s`` (``s`` the robust scale, :func:`second_difference_scale`).
  It is replaced by the line through its neighbours (:func:`fill`), not made a gap: a gap
  costs every trigger whose segment holds it.
* A drifting zero is removed by a zero-phase Butterworth high-pass (:func:`highpass`, order
  :data:`HIGHPASS_ORDER`) at :data:`HIGHPASS_CORNER` rocking frequencies (eq. 5).

The calibration applies the same :func:`apply` to its simulated sets, so the belt carries the
bias the repair leaves, and the repair enters its settings (:func:`settings`). Evidence for
the constants: ``benchmarks/repair_study.py``.

Explanation: docs/how-to/own-record.md (spikes and drift are repaired first);
docs/explanation/constants.md (the repair's constants).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

__all__ = [
    "HIGHPASS_CORNER", "Repair", "SPIKE_Z", "apply", "cycle_samples", "find_spikes", "highpass",
    "settings",
]

#: Robust z of a spike's second difference: the sample's own beyond ``2 SPIKE_Z`` scales,
#: a neighbour's of the other sign beyond ``SPIKE_Z`` (module docstring); Gaussian second
#: differences pass both practically never. Evidence of no false spike on clean records:
#: ``benchmarks/repair_study.py`` (docs/explanation/constants.md).
SPIKE_Z = 8.0

#: Passes of :func:`find_spikes`: spikes on neighbouring samples hide each other's pattern
#: until one of them is a gap.
SPIKE_PASSES = 8

#: A sample beside a gap is read against the line through the nearest finite samples on
#: each side, at most this many samples away (a run of touching spikes is a few samples).
GAP_REACH = 4

#: Corner of the drift's high-pass in rocking frequencies (eq. 5), and the filter's order:
#: evidence that it removes drift of up to 5 sigma_Y and what it does to a clean record's
#: ``e``: ``benchmarks/repair_study.py`` (docs/explanation/constants.md).
HIGHPASS_CORNER, HIGHPASS_ORDER = 0.1, 2

#: The factor from the median absolute deviation to the standard deviation of a Gaussian.
MAD_TO_SD = 1.4826


class Repair(NamedTuple):
    """What :func:`apply` did to a set of records: ``spikes``, the indices of the samples
    replaced (an integer array per record); ``corner``: the high-pass corner in rocking
    frequencies (``None``: no high-pass) and ``per_sample``, the same in cycles per sample."""

    spikes: tuple
    corner: float | None
    per_sample: float | None

    @property
    def removed(self) -> int:
        """Spikes replaced over all records."""
        return int(sum(where.size for where in self.spikes))

    @property
    def repaired(self) -> bool:
        """Whether any record was changed: a spike replaced or a high-pass applied."""
        return bool(self.removed or self.corner is not None)


def settings(spikes: bool, drift: bool) -> dict:
    """The repair as the calibration's settings hold it: ``{"spikes": SPIKE_Z or None,
    "highpass": HIGHPASS_CORNER or None, "order": HIGHPASS_ORDER}``.

    Examples
    --------
    >>> settings(True, False)["spikes"] == SPIKE_Z
    True
    """
    return {"spikes": SPIKE_Z if spikes else None, "highpass": HIGHPASS_CORNER if drift else None, "order": HIGHPASS_ORDER}


@njit(nogil=True, cache=True)
def _spike_marks(y, limit, out):
    """Mark in ``out`` each ``k`` whose second difference ``d[k]`` is the largest in size of
    ``d[k-1..k+1]``, beyond ``2 limit``, with a neighbour's of the other sign beyond
    ``limit`` (NaN compares False); a sample beside a gap (a spike found on an earlier
    pass), when it stands beyond ``2 limit`` off the line through the nearest finite
    samples on each side (within :data:`GAP_REACH`), or else through the two on its other
    side. Returns how many were marked."""
    n = y.size
    marked = 0
    for k in range(2, n - 2):
        if y[k] != y[k]:
            continue
        if y[k - 1] != y[k - 1] or y[k + 1] != y[k + 1]:  # beside a gap: the line through the nearest samples
            low, high = k - 1, k + 1
            while low > max(k - GAP_REACH, 0) and y[low] != y[low]:
                low -= 1
            while high < min(k + GAP_REACH, n - 1) and y[high] != y[high]:
                high += 1
            if y[low] == y[low] and y[high] == y[high]:
                off = y[k] - (y[low] + (y[high] - y[low]) * (k - low) / (high - low))
            elif y[k - 1] != y[k - 1] and y[k + 1] == y[k + 1] and y[k + 2] == y[k + 2]:
                off = y[k] - 2.0 * y[k + 1] + y[k + 2]
            elif y[k + 1] != y[k + 1] and y[k - 1] == y[k - 1] and y[k - 2] == y[k - 2]:
                off = y[k] - 2.0 * y[k - 1] + y[k - 2]
            else:
                continue
            if abs(off) > 2.0 * limit:
                out[k] = True
                marked += 1
            continue
        d0 = y[k + 1] - 2.0 * y[k] + y[k - 1]
        if not abs(d0) > 2.0 * limit:
            continue
        dm = y[k] - 2.0 * y[k - 1] + y[k - 2]
        dp = y[k + 2] - 2.0 * y[k + 1] + y[k]
        if not (abs(d0) >= abs(dm) or dm != dm) or not (abs(d0) >= abs(dp) or dp != dp):
            continue
        s = 1.0 if d0 > 0.0 else -1.0
        if -s * dm > limit or -s * dp > limit:
            out[k] = True
            marked += 1
    return marked


def second_difference_scale(y: np.ndarray) -> float:
    """The robust scale of ``y``'s finite second differences: :data:`MAD_TO_SD` times their
    median absolute deviation from their median (NaN when there are none).

    Examples
    --------
    >>> y = np.random.default_rng(0).normal(size=100_000)
    >>> round(float(second_difference_scale(y) / np.sqrt(6.0)), 1)  # d = y[k+1] - 2 y[k] + y[k-1] of white noise
    1.0
    """
    d = np.diff(np.asarray(y, dtype=float), 2)
    d = d[np.isfinite(d)]
    if not d.size:
        return float("nan")
    return MAD_TO_SD * float(np.median(np.abs(d - np.median(d))))


def find_spikes(y, z: float = SPIKE_Z) -> np.ndarray:
    """Indices of the spikes of the record ``y`` (1-D, NaN allowed): the samples whose
    second differences show the pattern of an isolated wrong sample beyond ``z`` robust
    scales (module docstring), over :data:`SPIKE_PASSES` passes, each after the spikes found
    so far are gaps.

    Parameters
    ----------
    y : array_like
        One record.
    z : float
        Robust z of a spike (:data:`SPIKE_Z`).

    Returns
    -------
    numpy.ndarray
        Sorted indices (int).

    Examples
    --------
    >>> y = np.sin(np.arange(2000) * 0.05) + np.random.default_rng(1).normal(0.0, 0.01, 2000)
    >>> y[[300, 1200]] += [3.0, -2.0]
    >>> find_spikes(y).tolist()
    [300, 1200]
    """
    y = np.array(y, dtype=np.float64)
    limit = z * second_difference_scale(y)
    found = np.zeros(y.size, dtype=bool)
    if not limit > 0.0:
        return np.flatnonzero(found)
    for _ in range(SPIKE_PASSES):
        marks = np.zeros(y.size, dtype=bool)
        if not _spike_marks(y, limit, marks):
            break
        found |= marks
        y[marks] = np.nan
    return np.flatnonzero(found)


def highpass(y, per_sample: float, order: int = HIGHPASS_ORDER) -> np.ndarray:
    """``y`` through a zero-phase Butterworth high-pass of ``order`` with its corner at
    ``per_sample`` cycles per sample (:func:`scipy.signal.sosfiltfilt`); NaN samples are
    bridged by straight lines for the filter and stay NaN.

    Parameters
    ----------
    y : array_like
        One record (1-D, NaN allowed, at least one finite sample).
    per_sample : float
        Corner in cycles per sample, between 0 and 0.5.
    order : int
        Order of the filter (run twice: forwards and backwards).

    Returns
    -------
    numpy.ndarray
        The filtered record.

    Examples
    --------
    >>> t = np.arange(20_000)
    >>> y = np.sin(2 * np.pi * t / 40) + t / 5_000      # 4 units of drift under a cycle of 40 samples
    >>> out = highpass(y, 0.05 / 40)
    >>> bool(abs(np.polyfit(t, out, 1)[0]) * t.size < 0.02)
    True
    """
    from scipy import signal

    y = np.asarray(y, dtype=np.float64)
    gaps = ~np.isfinite(y)
    filled = fill(y, np.flatnonzero(gaps)) if gaps.any() else y
    sos = signal.butter(order, 2.0 * per_sample, btype="highpass", output="sos")
    out = signal.sosfiltfilt(sos, filled)
    out[gaps] = np.nan
    return out


def cycle_samples(records) -> float:
    """Samples per rocking cycle read without the analysis, for a record the analysis cannot
    read until its drift is gone: twice the mean interval between the sign changes of the
    slope ``diff(y)`` (an extremum on each side of a cycle), which a slow drift barely moves.
    Sensor noise adds sign changes and so reads fewer samples (a higher corner); the
    corner is placed again from the analysis of the filtered records.

    Examples
    --------
    >>> y = np.sin(np.arange(10_000) * 2 * np.pi / 50) + np.arange(10_000) / 2_000
    >>> round(cycle_samples([y]))
    50
    """
    changes = samples = 0
    for y in records:
        d = np.diff(np.asarray(y, dtype=float))
        d = d[np.isfinite(d) & (d != 0.0)]
        changes += int(np.count_nonzero(np.diff(np.signbit(d))))
        samples += d.size
    return 2.0 * samples / max(changes, 1)


def fill(y, where) -> np.ndarray:
    """``y`` with the samples ``where`` replaced by the straight line through the nearest
    finite samples on each side that are not in ``where`` (:func:`numpy.interp`; NaN
    elsewhere stays NaN).

    Examples
    --------
    >>> fill(np.array([0.0, 1.0, 9.0, 3.0, 4.0]), [2]).tolist()
    [0.0, 1.0, 2.0, 3.0, 4.0]
    """
    y = np.array(y, dtype=np.float64)
    bad = np.zeros(y.size, dtype=bool)
    bad[np.asarray(where, dtype=int)] = True
    good = ~bad & np.isfinite(y)
    if bad.any() and good.any():
        k = np.arange(y.size)
        y[bad] = np.interp(k[bad], k[good], y[good])
    return y


def apply(records, repair: dict | None, points_per_cycle: float) -> tuple[list[np.ndarray], Repair]:
    """``records`` repaired as ``repair`` (:func:`settings`) says: spikes replaced by their
    neighbours' line (:func:`find_spikes`, :func:`fill`) and then the high-pass (:func:`highpass`) at ``repair["highpass"]``
    rocking frequencies, placed per sample by ``points_per_cycle`` (eq. 5). The very
    function the calibration runs on its simulated sets. ``None`` or an empty repair
    returns the records as they are.

    Parameters
    ----------
    records : sequence of array_like
        The records (1-D, NaN allowed).
    repair : dict or None
        :func:`settings`.
    points_per_cycle : float
        Samples per rocking cycle at ``sigma_Y`` (eq. 5) of the records.

    Returns
    -------
    (list of numpy.ndarray, Repair)

    Examples
    --------
    >>> y = np.sin(np.arange(4000) * 2 * np.pi / 40)
    >>> y[1000] = 9.0
    >>> out, done = apply([y], settings(True, True), 40.0)
    >>> done.removed, done.corner, bool(abs(out[0][1000]) < 1.0)
    (1, 0.1, True)
    """
    records = [np.asarray(y, dtype=np.float64) for y in records]
    if not repair or (repair.get("spikes") is None and repair.get("highpass") is None):
        return records, Repair(tuple(np.empty(0, dtype=np.int64) for _ in records), None, None)
    replaced = [np.empty(0, dtype=np.int64) for _ in records]
    if repair.get("spikes") is not None:
        replaced = [find_spikes(y, repair["spikes"]) for y in records]
        records = [fill(y, where) if where.size else y for y, where in zip(records, replaced)]
    corner = repair.get("highpass")
    per_sample = None
    if corner is not None:
        per_sample = float(corner) / float(points_per_cycle)
        records = [highpass(y, per_sample, int(repair.get("order", HIGHPASS_ORDER))) for y in records]
    return records, Repair(tuple(replaced), corner, per_sample)

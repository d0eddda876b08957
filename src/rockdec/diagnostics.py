"""What may be wrong with a measured record: the checks of ``rockdec estimate``, declared once.

Every check is a :class:`Check`: its name, the defect it names, a cheap dimensionless
statistic of the records and their analysis (:func:`rockdec.measured.analyse`), the side
on which a large (``"high"``) or small (``"low"``) value is suspicious, its one-sentence
message, and how its threshold is set. :data:`REGISTRY` lists them; the calibration
(:mod:`rockdec.calibration`) and ``rockdec estimate`` (:func:`rockdec.inference.diagnose`)
read it, and so do the study (:mod:`rockdec.diagnostics_study`) and the docs.

Thresholds. A warning is a claim, so it is set like an interval: from the simulations that
calibrate ``e``. The calibration computes every statistic (:func:`statistics`) on each of
its simulated record sets, which have the measured records' lengths and sampling and are
clean (the record model the calibration simulates, nothing else), and stores them as
``diagnostic(e_true, set, check)``. :func:`thresholds` pools the sets of the grid points
inside the record's 95 % interval of ``e`` and the nearest grid point on each side of its
corrected ``e`` (every grid point when there is no ``e``), and takes the
:data:`QUANTILE` quantile of a ``"high"`` check (``1 - QUANTILE`` of a ``"low"`` one): on
the calibration's own records near the record's ``e`` a check fires on at most
``1 - QUANTILE`` of them, with room for the sampling error of a quantile of some hundred
sets below the 5 % the checks promise. Pooling over the interval takes the widest null of
the ``e`` the record allows. The statistics are scale-free (the calibration has ``g =
sigma_p = 1``): each is a ratio, a z score, a skewness or a count.

``coarse_sampling`` is the exception: the calibration copies the record's sampling, so its
records say nothing about whether the sampling is too coarse; its threshold is the
structural floor of the local fits of eq. 27 (:func:`rockdec.fits.min_points_per_cycle`).

The false-alarm and detection rates of each check, on records simulated apart from any
calibration, are measured by :mod:`rockdec.diagnostics_study` (docs/method.md §10).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from rockdec import fits, record_measure

#: Share of the calibration's own records (near the record's ``e``) below a ``"high"``
#: threshold; a check fires on ``1 - QUANTILE`` of them in expectation.
QUANTILE = 0.975

#: Consecutive blocks per record of the non-stationarity statistic.
STATIONARITY_BLOCKS = 8

#: ``e`` at which the structural floor of ``coarse_sampling`` is taken when the record gives
#: no corrected ``e`` (the floor is highest for small ``e``; 0.95 is the paper's middle).
FLOOR_E = 0.95


def _finite(records) -> np.ndarray:
    """The records' finite samples, each record less its own mean, end to end."""
    return np.concatenate([(y - np.nanmean(y))[np.isfinite(y)] for y in records])


def nonstationarity(records, analysis) -> float:
    """Standard deviation of ``ln`` of the rms of :data:`STATIONARITY_BLOCKS` consecutive
    blocks of each record (each block about its own mean, so an offset does not count),
    pooled over records: 0 for a stationary record of infinite length."""
    logs = []
    for y in records:
        for block in np.array_split(np.asarray(y, dtype=float), STATIONARITY_BLOCKS):
            block = block[np.isfinite(block)]
            if block.size > 1:
                logs.append(np.log(np.std(block)))
    return float(np.std(logs)) if len(logs) > 1 else np.nan


def drift(records, analysis) -> float:
    """``drift_z`` of :mod:`rockdec.record_measure`: von Neumann's ratio of 20 block means per
    record as a z score (about N(0, 1) for independent block means; large for a slow
    offset)."""
    return float(record_measure._drift([np.asarray(y, dtype=float) - np.nanmean(y) for y in records], analysis.sigma_y)[1])


def spikes(records, analysis) -> float:
    """Largest ``|y[k] - (y[k-1] + y[k+1]) / 2|`` over ``sigma_Y``: how far one sample stands
    off the line through its neighbours. Between impacts the block moves on parabolas, so
    a clean record gives a few tenths at most (velocity jumps at impacts); an isolated
    spike of ``k sigma_Y`` gives ``k``."""
    worst = 0.0
    for y in records:
        y = np.asarray(y, dtype=float)
        off = np.abs(y[1:-1] - 0.5 * (y[:-2] + y[2:]))
        if np.isfinite(off).any():
            worst = max(worst, float(np.nanmax(off)))
    return worst / analysis.sigma_y


def asymmetry(records, analysis) -> float:
    """``|skewness|`` of the pooled records (each less its mean): a block leaning on one
    side (``g`` differing between its sides, or a load with a non-zero mean) goes further
    on its weak side."""
    y = _finite(records)
    return float(abs(np.mean(y**3) / np.mean(y**2) ** 1.5))


def triggers(records, analysis) -> float:
    """Triggers of both signatures (``D_a`` and ``D_v``) in the largest window."""
    return float(analysis.count["a"][-1] + analysis.count["v"][-1])


def sampling(records, analysis) -> float:
    """Samples per cycle at amplitude ``sigma_Y`` (eq. 5)."""
    return float(analysis.points_per_cycle)


@dataclass(frozen=True)
class Check:
    """One diagnostic of the records.

    ``name``: the ``check`` coordinate of the calibration's ``diagnostic`` variable and the
    key of ``rockdec estimate``'s JSON ``diagnostics``; ``defect``: what it finds, in a few
    words; ``statistic``: ``f(records, analysis) -> float`` (dimensionless); ``side``:
    ``"high"`` fires above the threshold, ``"low"`` below; ``threshold``: ``"calibrated"``
    (:func:`thresholds`) or ``"structural"`` (``coarse_sampling``, module docstring);
    ``message``: the warning, formatted with ``value`` and ``threshold``.
    """

    name: str
    defect: str
    statistic: Callable
    side: str
    threshold: str
    message: str


REGISTRY = (
    Check("nonstationary", "the load's strength changes along the record", nonstationarity, "high", "calibrated",
          "the response is not stationary: the rms of its blocks varies more than in stationary records like it (spread "
          "of log rms {value:.2f}, calibrated limit {threshold:.2f}); the load changes along the record, so estimate "
          "stretches of steady load apart"),
    Check("drift", "a slow offset of the zero", drift, "high", "calibrated",
          "the record's block means wander more than rocking makes them (drift z {value:.1f}, calibrated limit "
          "{threshold:.1f}): the sensor's zero drifts; remove the trend (high-pass well below the rocking frequency)"),
    Check("spikes", "isolated wrong samples", spikes, "high", "calibrated",
          "a sample stands {value:.2f} sigma_Y off the line through its neighbours, where rocking records like it reach "
          "{threshold:.2f}: the record holds spikes; remove them or mark them as gaps (NaN)"),
    Check("asymmetry", "a block leaning on one side", asymmetry, "high", "calibrated",
          "the response is asymmetric (|skewness| {value:.2f}, calibrated limit {threshold:.2f}): the block may lean on "
          "one side or the load push one way; the model assumes a symmetric block"),
    Check("few_triggers", "gaps or quiet stretches", triggers, "low", "calibrated",
          "{value:.0f} triggers in the largest windows, fewer than records of this length and sampling give "
          "({threshold:.0f}): gaps or quiet stretches leave fewer segments than the calibration assumed, so the interval "
          "is too narrow; cut the record into pieces without them"),
    Check("coarse_sampling", "too few samples per cycle for e1..e4", sampling, "low", "structural",
          "{value:.1f} samples per cycle at sigma_Y is below {threshold:.1f}, too coarse for the local fits of e1..e4 "
          "(eq. 27); sample faster"),
)
"""Every check, in the order of the ``check`` coordinate."""

CHECKS = tuple(check.name for check in REGISTRY)
"""Names of the checks, in registry order."""


def statistics(records, analysis) -> np.ndarray:
    """Every check's statistic on ``records`` (zero-mean-able 1-D arrays, NaN allowed) and
    their :class:`rockdec.measured.Analysis`, in registry order."""
    return np.array([check.statistic(records, analysis) for check in REGISTRY], dtype=float)


def _near(e_grid: np.ndarray, e: float | None, interval) -> np.ndarray:
    """Grid points pooled for a record of corrected ``e`` and 95 % ``interval``: those inside
    the interval and the nearest on each side of ``e``; all when ``e`` is not finite."""
    if e is None or not np.isfinite(e):
        return np.ones(e_grid.size, dtype=bool)
    keep = np.zeros(e_grid.size, dtype=bool)
    low, high = (np.nan, np.nan) if interval is None else (np.nan if v is None else v for v in interval)
    if np.isfinite(low) and np.isfinite(high):
        keep |= (e_grid >= low) & (e_grid <= high)
    below, above = np.flatnonzero(e_grid <= e), np.flatnonzero(e_grid >= e)
    keep[below[-1] if below.size else 0] = True
    keep[above[0] if above.size else -1] = True
    return keep


def thresholds(cal, e: float | None, interval, level: float) -> dict:
    """Each check's threshold for a record of corrected ``e`` (``None`` when not estimated)
    and 95 % ``interval``, from the calibration ``cal``'s ``diagnostic(e_true, set, check)``
    (module docstring); ``level``: the trigger level in ``sigma_Y`` (for the structural
    floor). NaN for a check the calibration's records never gave a value."""
    grid = np.asarray(cal["e_true"].values, dtype=float)
    keep = _near(grid, e, interval)
    values = cal["diagnostic"].values[keep]  # (e_true, set, check)
    out = {}
    for j, check in enumerate(REGISTRY):
        if check.threshold == "structural":
            out[check.name] = fits.min_points_per_cycle(e if e is not None and np.isfinite(e) else FLOOR_E, level)
            continue
        column = values[..., j].ravel()
        column = column[np.isfinite(column)]
        q = QUANTILE if check.side == "high" else 1.0 - QUANTILE
        out[check.name] = float(np.quantile(column, q)) if column.size else np.nan
    return out


@dataclass(frozen=True)
class Outcome:
    """One check on a record: its ``statistic``, ``threshold`` and whether it ``fired``;
    ``message`` is the warning (empty when it did not fire)."""

    statistic: float
    threshold: float
    fired: bool
    message: str


def judge(values, limits: dict) -> dict:
    """``{name: Outcome}`` (registry order) of the statistics ``values``
    (:func:`statistics`) against the thresholds ``limits`` (:func:`thresholds`). A NaN
    statistic or threshold never fires."""
    out = {}
    for check, value in zip(REGISTRY, values):
        limit = limits[check.name]
        fired = bool(value > limit if check.side == "high" else value < limit)  # NaN compares False
        out[check.name] = Outcome(float(value), float(limit), fired, check.message.format(value=value, threshold=limit) if fired else "")
    return out


def evaluate(records, analysis, cal, e: float | None, interval, level: float) -> dict:
    """Every check on ``records`` against the calibration ``cal``: :func:`judge` of
    :func:`statistics` and :func:`thresholds`."""
    return judge(statistics(records, analysis), thresholds(cal, e, interval, level))

"""What may be wrong with a measured record: the checks of ``rockdec estimate``, declared once.

Every check is a :class:`Check`: its name, the defect it names, a cheap dimensionless
statistic of the records and their analysis (:func:`rockdec.rdd.measured.analyse`), the side
on which a large (``"high"``) or small (``"low"``) value is suspicious, its one-sentence
message, and how its threshold is set. :data:`REGISTRY` lists them; the calibration, ``rockdec
estimate`` (:func:`rockdec.estimation.diagnose`), the study and the docs read it.
:func:`statistics` computes every statistic (one compiled pass, :func:`sums`; :func:`spikes`;
:func:`impact_ratios`); the calibration stores them on its simulated record sets, and
:func:`thresholds` takes the :data:`QUANTILE` quantile of the null (:func:`null`) of the grid
points about the record's interval of ``e``; ``coarse_sampling`` and ``few_triggers``
(:func:`segments`, :data:`MIN_SEGMENTS`) have structural floors instead; :func:`judge` fires
them. Their false-alarm and detection rates: :mod:`rockdec.studies.diagnostics_study`.

Explanation: docs/explanation/method/warnings.md (thresholds from the calibration, the
asymmetry's null, structural checks).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, NamedTuple

import numpy as np
from numba import njit

from rockdec.rdd import fits

__all__ = [
    "CHECKS", "FILTER_HELP", "IMPACT_MIN_STEPS", "MIN_SEGMENTS", "QUANTILE", "REGISTRY", "asymmetry",
    "evaluate", "impact_level", "impact_ratios", "impact_sharpness", "impact_sides", "impact_steps",
    "judge", "length_threshold", "nonstationarity", "null", "resolution", "segments", "side_sums",
    "spikes", "statistics", "sums", "thresholds",
]

#: Share of the null (:func:`null`, near the record's ``e``) below a ``"high"`` threshold; a
#: check fires on ``1 - QUANTILE`` of clean records in expectation (its rate on each cell:
#: the diagnostics study, ``snakemake --cores 2 diagnostics``; docs/explanation/constants.md).
QUANTILE = 0.985

#: Fewest finite values of a grid point's sets for its mean and spread to place the null's
#: shape there (:func:`null`).
NULL_MIN_SETS = 5

#: Consecutive blocks per record of the block statistics (drift and non-stationarity), each
#: of at least ``BLOCK_MIN`` samples (fewer blocks for short records; none below 4).
BLOCKS, BLOCK_MIN = 20, 1000

#: Quantile of a record's distances of samples from the line through their neighbours that
#: :func:`spikes` reads its largest distance against: in clean records the top per cent are
#: impacts, in noisy ones the noise; isolated spikes leave it where it is unless they are
#: many (docs/explanation/constants.md).
SPIKE_REFERENCE = 0.99

#: :func:`asymmetry` reads each side's ``g`` off the triples beyond ``GUARD_G g dt^2`` of the
#: record's impact level (``g dt^2`` read off the sides split at the record's median), the
#: level searched on steps of ``1/LEVEL_STEPS`` of that guard, up to ``LEVEL_RANGE``
#: standard deviations of the record from its median and with at least ``LEVEL_SHARE`` of
#: the triples on each side (:func:`impact_level`).
GUARD_G, LEVEL_STEPS, LEVEL_RANGE, LEVEL_SHARE = 8.0, 8, 1.0, 0.05

#: ``e`` at which the structural floor of ``coarse_sampling`` is taken when the record gives
#: no corrected ``e`` (the floor is highest for small ``e``; 0.95 is the paper's middle).
FLOOR_E = 0.95

#: Samples on each side of a zero crossing over which :func:`impact_ratios` reads the wide
#: velocities (the narrow ones: one sample).
IMPACT_WIDE = 4

#: Fewest steps of a quantised record's resolution that the one-sample velocities at its
#: fast zero crossings must span for :func:`impact_ratios` to read them (:func:`impact_steps`):
#: below it the rounding moves the statistic of ``filtered`` beyond the spread of clean
#: records (evidence: ``benchmarks/quantised_records.py``).
IMPACT_MIN_STEPS = 50

#: What a record that shows a steep filter after the block should do: the end of the decline
#: before any calibration (:func:`rockdec.estimation.filter_decline`; a soft contact
#: does not steepen the spectrum, so ``filtered``'s message ends with :data:`BLUNTED_HELP`).
FILTER_HELP = (
    "a low-pass filter after the block (a logger's anti-alias filter, a sensor's bandwidth, a smoothing) rounds the "
    "impacts, which moves e; declare it (`sensor_filter` butterworth:ORDER:CORNER:PHASE or rc:CORNER:PHASE, with `load` "
    "and `sensor_noise`) and the calibration filters its records alike, or `sensor_filter` none if the records are not "
    "filtered"
)

#: What a record whose impacts are blunted (``filtered`` fired) may hold and what to do: the
#: end of ``filtered``'s message. A soft contact spreads each impact's velocity change over
#: several samples as a filter does; the calibration's impacts are instantaneous (eq. 6), so
#: no declaration models it, but keeping every k-th sample (no anti-alias filter) can fit the
#: contact inside one sample step.
BLUNTED_HELP = (
    "either a low-pass filter between the block and the sensor (a logger's anti-alias filter, a sensor's bandwidth, "
    "a smoothing) or a soft contact (the block's impact on its base lasting several samples, where the model's impact "
    "is instantaneous, eq. 6), and either moves e; a filter: declare it (`sensor_filter` butterworth:ORDER:CORNER:PHASE "
    "or rc:CORNER:PHASE, with `load` and `sensor_noise`) and the calibration filters its records alike; a soft contact: "
    "rockdec cannot calibrate one and declaring `sensor_filter` none does not model it, but keeping every k-th sample "
    "(no anti-alias filter) so that the contact lasts less than one sample step, at no fewer samples per cycle than "
    "the analysis needs, can make the impacts sharp again"
)

#: Fewest of the records' trigger positions whose segment holds no NaN (:func:`segments`)
#: before ``few_triggers`` fires: the calibration's records have none, so gaps costing more
#: than a tenth of the triggers leave the interval too narrow (docs/method.md §10).
MIN_SEGMENTS = 0.9


@njit(nogil=True, cache=True)
def _record_sums(y, n_blocks, distance):
    """One record's sums in two passes. First, per block of ``n_blocks`` consecutive equal
    blocks (by sample index), the count of non-NaN samples and the sums of ``d`` and ``d^2``,
    ``d = y - c`` with ``c`` the first non-NaN sample (a shift that keeps the variances
    accurate). Then, over triples ``y[k-1], y[k], y[k+1]``, the largest ``|y[k] - (y[k-1] +
    y[k+1])/2|`` over non-NaN triples; the finite ``|y[k+1] - 2 y[k] + y[k-1]|`` go to the
    front of ``distance`` (``n - 2`` floats, scratch). Returns ``(c, block counts, block
    sums (2, n_blocks), largest, number of distances written)``."""
    n = y.size
    c = 0.0
    for k in range(n):
        if y[k] == y[k]:
            c = y[k]
            break
    counts, blocks = np.empty(n_blocks), np.empty((2, n_blocks))
    for j in range(n_blocks):
        q, t1, t2 = 0, 0.0, 0.0
        for k in range(j * n // n_blocks, (j + 1) * n // n_blocks):
            d = y[k] - c
            if d == d:  # NaN is not equal to itself
                q += 1
                t1 += d
                t2 += d * d
        counts[j], blocks[0, j], blocks[1, j] = q, t1, t2
    worst = 0.0
    written = 0
    for k in range(1, n - 1):
        a, b, e = y[k - 1], y[k], y[k + 1]
        d2 = e - 2.0 * b + a
        if abs(d2) > worst:  # NaN compares False
            worst = abs(d2)
        if abs(d2) < np.inf:  # finite: NaN compares False
            distance[written] = abs(d2)
            written += 1
    return c, counts, blocks, 0.5 * worst, written


@njit(nogil=True, cache=True)
def side_sums(y, level, guard):
    """Count and sum of the second differences ``y[k+1] - 2 y[k] + y[k-1]`` of the triples
    all below ``level - guard`` (side 0) and all above ``level + guard`` (side 1), as
    ``(n0, n1, s0, s1)``; a triple touching a NaN is left out (NaN compares False)."""
    low, high = level - guard, level + guard
    n0, n1, s0, s1 = 0.0, 0.0, 0.0, 0.0  # scalars: array elements here cost 6 times more
    for k in range(1, y.size - 1):
        a, b, e = y[k - 1], y[k], y[k + 1]
        if a > high and b > high and e > high:
            n1 += 1.0
            s1 += e - 2.0 * b + a
        elif a < low and b < low and e < low:
            n0 += 1.0
            s0 += e - 2.0 * b + a
    return n0, n1, s0, s1


@njit(nogil=True, cache=True)
def _level_histogram(y, centre, step, counts, totals):
    """Add the count and the sum of the finite second differences of ``y``'s triples to
    ``counts`` and ``totals`` (``2 h + 1`` bins) at the bin ``h + round((y[k] - centre) /
    step)`` of their middle sample, clipped to the end bins."""
    half = (counts.size - 1) // 2
    for k in range(1, y.size - 1):
        d2 = y[k + 1] - 2.0 * y[k] + y[k - 1]
        if abs(d2) < np.inf:  # finite: NaN compares False
            j = min(max((y[k] - centre) / step, -half), half)
            i = int(np.floor(j + 0.5)) + half
            counts[i] += 1.0
            totals[i] += d2


class Sums(NamedTuple):
    """What the checks read of the records (:func:`sums`), pooled over records: ``count``
    finite samples; ``block_mean``, ``block_var`` per block of each record (:data:`BLOCKS`,
    each of at least :data:`BLOCK_MIN` samples, fewer for short records, none below 4),
    with ``block_record`` the record of each; ``side_count``, ``side_sum`` the count and sum
    of the second differences of triples beyond a guard on each side of each record's
    impact level (``[0]`` below, ``[1]`` above, :func:`_sides`); ``off``: over records, the
    largest ratio of a record's largest distance of a sample from the line through its
    neighbours to its :data:`SPIKE_REFERENCE` quantile of those distances
    (:func:`_spike_ratio`); ``gaps``: per record, its length and the starts and ends
    (exclusive) of its runs of NaN (:func:`_nan_runs`); ``impact_narrow``, ``impact_wide``:
    over the fast zero crossings of every record, the logarithm of the ratio of the velocity
    after to that before, read over one sample and over :data:`IMPACT_WIDE` samples on each
    side (:func:`impact_ratios`)."""

    count: int
    block_mean: np.ndarray
    block_var: np.ndarray
    block_record: np.ndarray
    side_count: np.ndarray
    side_sum: np.ndarray
    off: float
    gaps: tuple
    impact_narrow: np.ndarray
    impact_wide: np.ndarray


def _spike_ratio(distance: np.ndarray, largest: float) -> float:
    """``largest`` (the largest ``|y[k] - (y[k-1] + y[k+1]) / 2|`` of a record) over the
    :data:`SPIKE_REFERENCE` quantile of those distances, ``distance`` holding twice each one
    of its finite triples (:func:`_record_sums`); NaN when there is none or the quantile is 0."""
    if not distance.size:
        return np.nan
    k = min(int(SPIKE_REFERENCE * distance.size), distance.size - 1)
    reference = 0.5 * float(np.partition(distance, k)[k])
    return largest / reference if reference > 0.0 else np.nan


def _median(y: np.ndarray) -> float:
    """The median of the non-NaN samples of ``y`` (NaN when there is none)."""
    finite = y[~np.isnan(y)]
    return float(np.median(finite, overwrite_input=True)) if finite.size else np.nan


def impact_sides(y: np.ndarray, var: float) -> tuple[float, float]:
    """``(level, guard)`` about which the asymmetry reads ``y``'s sides (:func:`side_sums`):
    its :func:`impact_level` and a guard of :data:`GUARD_G` ``g dt^2``, ``g dt^2`` read off
    the sides split at the median (no guard); ``var``: the variance of ``y`` (its spread,
    which bounds the level's search). ``(NaN, NaN)`` when the median's sides give no
    positive ``g`` or ``var`` is not positive. :mod:`rockdec.record.record_measure` reads
    the asymmetry it reports about the same level."""
    centre = _median(y)
    n0, n1, s0, s1 = side_sums(y, centre, 0.0)
    g_dt2 = 0.5 * (s0 / n0 - s1 / n1) if n0 > 0.0 and n1 > 0.0 else np.nan
    if not (g_dt2 > 0.0 and var > 0.0):
        return np.nan, np.nan
    guard = GUARD_G * g_dt2
    return impact_level(y, centre, math.sqrt(var), guard), guard


def _sides(y: np.ndarray, count: float, sum1: float, sum2: float) -> tuple:
    """``(n0, n1, s0, s1)`` of :func:`side_sums` of ``y`` about :func:`impact_sides`;
    ``count``, ``sum1``, ``sum2``: the non-NaN samples and the sums of their deviations from
    any one value and of their squares (the record's spread). All 0 when it has no level."""
    level, guard = impact_sides(y, sum2 / count - (sum1 / count) ** 2 if count > 0 else np.nan)
    return side_sums(y, level, guard) if np.isfinite(level) else (0.0, 0.0, 0.0, 0.0)


def impact_level(y: np.ndarray, centre: float, sd: float, guard: float) -> float:
    """The level of ``y``'s impacts: the level ``L``, within :data:`LEVEL_RANGE` ``sd`` of
    ``centre`` on steps of ``guard / LEVEL_STEPS``, at which the mean second difference of
    the triples whose middle sample lies below ``L - guard`` less that of those above
    ``L + guard`` is largest, with at least :data:`LEVEL_SHARE` of the triples on each side.
    Between impacts the block moves on parabolas, ``+g dt^2`` below the impact level and
    ``-g dt^2`` above it (eq. 4), so a triple placed on the wrong side lowers the
    difference: it is largest at the impact level, whatever the ``g`` of each side. The
    guard leaves out the triples near the level (the impacts and the chatter of a block near
    rest, whose second differences are about 0). Levels between the same samples part the
    triples alike: the middle of the run of steps with the largest difference is taken, so
    the mirrored record's level is the mirror image. ``centre`` when no level qualifies."""
    step = guard / LEVEL_STEPS
    half = int(min(math.ceil(LEVEL_RANGE * sd / step), 2**16))
    counts, totals = np.zeros(2 * half + 1), np.zeros(2 * half + 1)
    _level_histogram(y, centre, step, counts, totals)
    n, t = np.cumsum(counts), np.cumsum(totals)
    i = np.arange(LEVEL_STEPS + 1, 2 * half - LEVEL_STEPS)  # level bins with a full guard inside the range
    below, above = i - LEVEL_STEPS - 1, i + LEVEL_STEPS  # last bin below L - guard; last bin not above L + guard
    n_low, n_high = n[below], n[-1] - n[above]
    ok = (n_low >= LEVEL_SHARE * n[-1]) & (n_high >= LEVEL_SHARE * n[-1])
    if not ok.any():
        return centre
    gap = np.where(ok, t[below] / np.where(ok, n_low, 1.0) - (t[-1] - t[above]) / np.where(ok, n_high, 1.0), -np.inf)
    best = int(np.argmax(gap))
    other = np.flatnonzero(gap != gap[best])  # levels between the same samples share the largest gap
    first = int(other[other < best].max()) + 1 if (other < best).any() else 0
    last = int(other[other > best].min()) - 1 if (other > best).any() else gap.size - 1
    return centre + (0.5 * (i[first] + i[last]) - half) * step


def sums(records, replaced=None) -> Sums:
    """:class:`Sums` of ``records`` (1-D arrays, NaN allowed): one compiled pass per record
    (:func:`_record_sums`), the quantile of :func:`_spike_ratio`, the sides of
    :func:`asymmetry` (:func:`_sides`) and the runs of NaN (:func:`_nan_runs`).

    ``replaced``: per record, the indices of the samples the repair replaced
    (:attr:`rockdec.record.repair.Repair.spikes`), or ``None``. The spikes statistic leaves
    the triples that touch them out (a second pass over the record with them NaN): a
    replaced sample lies on its neighbours' line, and a per cent of them would lower the
    record's percentile of distances and lift its ratio above a clean record's."""
    count, off = 0, np.nan
    side_n, side_s = np.zeros(2), np.zeros(2)
    means, variances, owners, gaps, narrow_wide = [], [], [], [], []
    for i, y in enumerate(records):
        y = np.ascontiguousarray(y, dtype=np.float64)
        b = min(BLOCKS, y.size // BLOCK_MIN)
        distance = np.empty(max(y.size - 2, 0))  # allocated here: the kernel then compiles no np.empty
        _, bn, (b1, b2), worst, written = _record_sums(y, max(b, 1), distance)
        if replaced is not None and np.size(replaced[i]):
            masked = y.copy()
            masked[np.asarray(replaced[i], dtype=np.int64)] = np.nan
            worst, written = _record_sums(masked, max(b, 1), distance)[3:]
        count, off = count + int(bn.sum()), np.fmax(off, _spike_ratio(distance[:written], worst))
        n0, n1, s0, s1 = _sides(y, float(bn.sum()), float(b1.sum()), float(b2.sum()))
        side_n, side_s = side_n + (n0, n1), side_s + (s0, s1)
        gaps.append((y.size, *_nan_runs(y)))
        narrow_wide.append(impact_ratios(y))
        if b >= 4 and (bn > 1).all():
            means.append(b1 / bn)
            variances.append(b2 / bn - (b1 / bn) ** 2)
            owners.append(np.full(b, i))
    stack = (lambda parts: np.concatenate(parts) if parts else np.empty(0))
    narrow, wide = (stack([part[k] for part in narrow_wide]) for k in (0, 1))
    return Sums(count, stack(means), stack(variances), stack(owners), side_n, side_s, float(off), tuple(gaps), narrow, wide)


def impact_ratios(y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(narrow, wide)``: at each zero crossing of ``y`` about its median (an impact, eq. 6)
    at least as fast as the record's median crossing, ``log(v_after / v_before)`` with the
    velocities read as differences over one sample (``narrow``) and over :data:`IMPACT_WIDE`
    samples (``wide``) on each side of the crossing; crossings whose windows touch a NaN, or
    whose ratio is not positive, are left out.

    A record quantised so coarsely that the one-sample velocities at those crossings are
    fewer than :data:`IMPACT_MIN_STEPS` steps of its resolution (:func:`resolution`) gives
    none: its ratios are ratios of a few integers, whose median snaps to one of them (often
    0, at ``e`` near 1) whatever the impacts' cut (:func:`impact_steps`).

    Unfiltered, the velocity jumps within the crossing's sample step, so the one-sample ratio
    holds the whole jump (about ``ln e``) and the wide one, over which the restoring term (eq.
    4) speeds the block up before the impact and slows it after, a little less; a low-pass
    filter after the block spreads the jump over several samples, so the one-sample ratio
    holds less of it than the wide one (:func:`impact_sharpness`).

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(40.0)
    >>> y = np.where(t < 20, 19.5 - t, 0.8 * (19.5 - t))  # a straight fall through zero, the speed cut by 0.8
    >>> narrow, wide = impact_ratios(np.concatenate([y, -y]))
    >>> np.round(np.exp(narrow), 3).tolist(), np.round(np.exp(wide), 3).tolist()
    ([0.8, 0.8], [0.8, 0.8])
    """
    y = np.asarray(y, dtype=np.float64)
    w = IMPACT_WIDE
    if np.count_nonzero(np.isfinite(y)) < 2 * w + 3:
        return np.empty(0), np.empty(0)
    d = y - np.nanmedian(y)
    n = np.flatnonzero(d[:-1] * d[1:] < 0.0)
    n = n[(n >= w) & (n + 1 + w < y.size)]
    before = y[n] - y[n - 1]
    fast = np.abs(before) >= np.nanmedian(np.abs(before)) if n.size else np.zeros(0, dtype=bool)
    n, before = n[fast], before[fast]
    if n.size and np.median(np.abs(before)) < IMPACT_MIN_STEPS * resolution(y):
        return np.empty(0), np.empty(0)  # the one-sample ratios are ratios of a few counts (impact_steps)
    with np.errstate(divide="ignore", invalid="ignore"):
        narrow = (y[n + 2] - y[n + 1]) / before
        wide = (y[n + 1 + w] - y[n + 1]) / (y[n] - y[n - w])
        keep = (narrow > 0.0) & (wide > 0.0)  # NaN compares False
        return np.log(narrow[keep]), np.log(wide[keep])


def resolution(y) -> float:
    """The step of the lattice the finite values of ``y`` lie on (integer counts of an
    encoder or a logger, or such counts times a scale), taken as the smallest nonzero
    difference between consecutive samples when every difference is a whole multiple of it
    (to 1e-6 of it); 0 for a record on no lattice, as a float record is.

    Examples
    --------
    >>> resolution(np.round(100 * np.sin(np.arange(2000) / 9.0)) * 0.25)
    0.25
    >>> resolution(np.sin(np.arange(2000) / 9.0))
    0.0
    """
    x = np.asarray(y, dtype=np.float64)
    d = np.abs(np.diff(x[np.isfinite(x)]))
    d = d[d > 0.0]
    if d.size == 0:
        return 0.0
    step = float(d.min())
    ratio = d / step
    return step if np.all(np.abs(ratio - np.round(ratio)) <= 1e-6) else 0.0


def impact_steps(y) -> float:
    """The median one-sample velocity at the fast zero crossings of ``y`` (those
    :func:`impact_ratios` reads) in steps of its resolution (:func:`resolution`); ``inf``
    for a record on no lattice, NaN without crossings.

    Examples
    --------
    >>> t = np.arange(4000.0)
    >>> round(impact_steps(np.round(40 * np.sin(t / 20.0))))  # a cycle of 126 samples crosses zero at 2 counts a sample
    2
    """
    y = np.asarray(y, dtype=np.float64)
    step = resolution(y)
    d = y - np.nanmedian(y)
    n = np.flatnonzero(d[:-1] * d[1:] < 0.0)
    n = n[(n >= IMPACT_WIDE) & (n + 1 + IMPACT_WIDE < y.size)]
    if not n.size:
        return math.nan
    before = np.abs(y[n] - y[n - 1])
    speed = float(np.median(before[before >= np.nanmedian(before)]))
    return speed / step if step > 0.0 else math.inf


def _nan_runs(y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Starts and ends (exclusive) of the runs of NaN in ``y``, in order."""
    edges = np.diff(np.isnan(y).astype(np.int8), prepend=0, append=0)
    return np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)


def _von_neumann_z(values: np.ndarray, owners: np.ndarray) -> float:
    """Von Neumann's ratio ``eta`` of consecutive ``values`` (mean square successive
    difference over variance, each record's ``values``, marked by ``owners``, about their
    own mean, pooled) as the z score ``(2 - eta) / sd0``, ``sd0^2 = 4 (B - 2)/(B^2 - 1)`` for
    ``B`` values: about N(0, 1) for independent values, large when they follow a slow
    trend. NaN for fewer than 4 values."""
    num = den = 0.0
    for i in np.unique(owners):
        v = values[owners == i]
        v = v - v.mean()
        num += float(np.sum(np.diff(v) ** 2))
        den += float(np.sum(v**2))
    count = values.size
    if count < 4 or not den > 0.0:
        return np.nan
    return (2.0 - num / den) / np.sqrt(4.0 * (count - 2) / (count**2 - 1))


def _split_t(values: np.ndarray, owners: np.ndarray) -> float:
    """The largest two-sample ``|t|`` between the first ``k`` and the other consecutive
    ``values`` of a record (marked by ``owners``) over every split ``k`` leaving at least two
    on each side, each split's variance pooled within its two parts; over records, the root
    mean square. A step of the values lifts it without bound (von Neumann's ratio of
    :data:`BLOCKS` values reaches about 4.2 at most, for a step infinitely large);
    about 2-3 for independent values. NaN for no values, fewer than 4 values in a record, or
    no spread within the parts.

    Examples
    --------
    >>> v = np.r_[np.zeros(10), np.ones(10)] + np.tile([0.01, -0.01], 10)  # a step of 100 spreads
    >>> print(round(_split_t(v, np.zeros(20))), round(float(_von_neumann_z(v, np.zeros(20))), 1))
    212 4.2
    """
    squares = []
    for i in np.unique(owners):
        v = values[owners == i]
        n = v.size
        if n < 4:
            return np.nan
        k = np.arange(2, n - 1)
        c1, c2 = np.cumsum(v)[k - 1], np.cumsum(v**2)[k - 1]
        left_mean, right_mean = c1 / k, (v.sum() - c1) / (n - k)
        within = (c2 - k * left_mean**2) + ((v**2).sum() - c2 - (n - k) * right_mean**2)
        var = within / (n - 2)
        if not np.all(var > 0.0):
            return np.nan
        squares.append(float(np.max((left_mean - right_mean) ** 2 / (var * (1.0 / k + 1.0 / (n - k))))))
    return float(np.sqrt(np.mean(squares))) if squares else np.nan


def nonstationarity(s: Sums, analysis) -> float:
    """The larger of :func:`_von_neumann_z` and :func:`_split_t` of ``ln`` of the blocks'
    variances (each block about its own mean, so an offset does not count): large when the
    load's strength changes slowly along the record (von Neumann's ratio) or steps (the
    split's ``t``, which a step of any size lifts; von Neumann's ratio of 20 blocks stays
    below about 4.2, a range that stationary records near ``e = 1`` reach, so a load that
    doubles halfway would pass unseen there). Scale-free; the threshold is calibrated on
    the larger of the two."""
    v = np.log(s.block_var)
    return float(np.fmax(_von_neumann_z(v, s.block_record), _split_t(v, s.block_record)))


def _trend_z(values: np.ndarray, owners: np.ndarray) -> float:
    """The straight-line trend of consecutive ``values`` (each record's, marked by ``owners``,
    against its own block index), as ``sqrt(T / k)`` with ``T`` the sum over the ``k``
    records of the squared slope over its variance (the residual variance about the lines,
    pooled): the ``|t|`` of the least-squares slope for one record, about 1 for trendless
    values. NaN for fewer than 3 values in a record or no residual spread."""
    slopes, residual, dof = [], 0.0, 0
    for i in np.unique(owners):
        v = values[owners == i]
        if v.size < 3:
            return np.nan
        x = np.arange(v.size) - (v.size - 1) / 2.0
        b = float(x @ (v - v.mean()) / (x @ x))
        residual += float(np.sum((v - v.mean() - b * x) ** 2))
        dof += v.size - 2
        slopes.append(b * b * float(x @ x))
    if not residual > 0.0:
        return np.nan
    return float(np.sqrt(np.mean(slopes) / (residual / dof)))


def drift(s: Sums, analysis) -> float:
    """The larger of :func:`_von_neumann_z` and :func:`_trend_z` of the block means: large for
    a slow offset. Von Neumann's ratio (the ``drift_z`` of
    :mod:`rockdec.record.record_measure`, on equal blocks) sees any smooth wander; the slope's
    ``|t|`` sees a straight trend where the block means scatter widely (a record at small
    ``e``, which rests long and swings wide), where von Neumann's ratio misses one record in
    five (docs/method.md §10). The threshold is calibrated on the larger of the two."""
    return float(np.fmax(_von_neumann_z(s.block_mean, s.block_record), _trend_z(s.block_mean, s.block_record)))


def spikes(s: Sums, analysis) -> float:
    """Largest ``|y[k] - (y[k-1] + y[k+1]) / 2|`` over the :data:`SPIKE_REFERENCE` quantile
    of the same record's distances (the largest over records): how far one sample stands off
    the line through its neighbours, against the record's own largest distances. Between
    impacts the block moves on parabolas, so in a clean record the top per cent of the
    distances are the velocity jumps at impacts and in a noisy one the sensor noise; either
    way the ratio is about 1.5-3 (1.7 in noise; clean records from 1.5 at ``e = 0.98`` to
    3 at 0.6), whatever the noise level and the samples per cycle (both scale the largest
    distance and the quantile alike), while an isolated spike of ``k sigma_Y`` stands
    ``k sigma_Y`` off: about 6 times the percentile for ``k = 1`` in 5 % noise. Triples
    touching a NaN are left out."""
    return s.off


def asymmetry(s: Sums, analysis) -> float:
    """``|g_+ - g_-| / (g_+ + g_-)``: between impacts the block moves on parabolas (eq. 4), so
    the mean second difference of triples on one side is ``-g dt^2`` there and ``+g dt^2``
    on the other; a block leaning on one side (or a load pushing one way) falls back with
    a different ``g`` on each (:mod:`rockdec.record.record_measure` reports it signed, read
    about the same level, :func:`impact_sides`). Scale-free, free of an offset, the same for
    the mirrored record, and 0 for a symmetric block.

    The sides are the triples beyond a guard of :data:`GUARD_G` ``g dt^2`` below and above
    the record's impact level (:func:`impact_level`, :func:`_sides`), so a lean of ``b``
    reads ``b`` (3 % reads 0.030, 60 % reads 0.600 at ``e = 0.98``, white or low-pass
    load). The guard leaves out the chatter near rest: under a low-pass load at 3 rocking
    frequencies a tenth of the triples lie within 0.5 % of ``sigma_Y`` of the impact level,
    their second differences about 0 instead of ``-+g dt^2``. Split at the record's mean
    (0.1-1 % of ``sigma_Y`` off the level, moved by the rare wide swings) one side takes
    them and reads its ``g`` up to 10 % low: clean records under that load read 0.09
    (median of 100 at ``e = 0.9``), a value that moves steeply with the load's pole and the
    step the calibration bins; read as here, 0.002. Split at the median, a lean moves the
    split into the weak side and cancels itself (30 % reads 0.05) (docs/method.md §10)."""
    if not (s.side_count > 0).all():
        return np.nan
    g_minus, g_plus = s.side_sum[0] / s.side_count[0], -s.side_sum[1] / s.side_count[1]
    return abs(g_plus - g_minus) / (g_plus + g_minus) if g_plus + g_minus > 0.0 else np.nan


def segments(s: Sums, analysis) -> float:
    """Share of the trigger positions of the records whose segment holds no NaN: a trigger
    at sample ``k`` adds the segment ``y[k - L .. k + L]`` to its signature (eq. 8, ``L``
    the analysis's ``n_lag``) and is skipped when the segment holds a NaN, so a gap of
    ``G`` samples costs every trigger of ``G + 2 L`` positions. Positions ``L .. n - L - 1``
    of each record of ``n`` samples (where a segment fits), pooled over records; 1 for
    records without NaN, whatever their load, noise or ``e``, and NaN when no segment fits.
    Triggers fall on the kept positions as on the lost ones (a gap does not choose where
    the block swings), so the share is the ratio of the records' trigger count to that of
    the same records without gaps (the study's gaps: within 0.01 in the median), and the
    spread of the estimates grows about as its inverse square root (docs/method.md §10)."""
    lag = int(analysis.n_lag)
    positions = lost = 0
    for n, starts, ends in s.gaps:
        if n <= 2 * lag:
            continue
        positions += n - 2 * lag
        low, high = np.clip(starts - lag, lag, n - lag), np.clip(ends + lag, lag, n - lag)
        # runs in order, each widened by L on both sides: ends in order too, so each run
        # adds what lies beyond the end of the one before it
        before = np.concatenate([[lag], high[:-1]])
        lost += int(np.maximum(high - np.maximum(low, before), 0).sum())
    return (positions - lost) / positions if positions else np.nan


def impact_sharpness(s: Sums, analysis) -> float:
    """How much more of the impacts' velocity jump a one-sample reading holds than a wide one
    (:func:`impact_ratios`): the median of the narrow log ratios less the median of the wide
    ones, over every record's fast zero crossings. Negative on unfiltered records (the jump is
    sharp); a low-pass filter after the block spreads it over several samples and makes it
    larger, towards or beyond zero. NaN without crossings."""
    if s.impact_narrow.size == 0:
        return np.nan
    return float(np.median(s.impact_narrow) - np.median(s.impact_wide))


def sampling(s: Sums, analysis) -> float:

    """Samples per cycle at amplitude ``sigma_Y`` (eq. 5)."""
    return float(analysis.points_per_cycle)


@dataclass(frozen=True)
class Check:
    """One diagnostic of the records.

    ``name``: the ``check`` coordinate of the calibration's ``diagnostic`` variable and the
    key of ``rockdec estimate``'s JSON ``diagnostics``; ``defect``: what it finds, in a few
    words; ``statistic``: ``f(sums, analysis) -> float`` (dimensionless; :func:`sums` of the
    records, their :class:`rockdec.rdd.measured.Analysis`); ``side``:
    ``"high"`` fires above the threshold, ``"low"`` below;
    ``message``: the warning, formatted with ``value`` and ``threshold``; ``floor``: the
    threshold of a structural check (``few_triggers``, ``coarse_sampling``: module docstring),
    ``f(e, level)`` (``e`` the record's corrected ``e``, :data:`FLOOR_E` without one;
    ``level`` the trigger level in ``sigma_Y``), ``None`` for a check whose threshold the
    calibration gives (:func:`thresholds`; :attr:`threshold` says which); ``length``: how
    the statistic of a clean record goes with its length, for records longer than the
    calibration's (:func:`length_threshold`): ``"free"`` (a z score, a ratio of means, a
    share), ``"root"`` (as ``1/sqrt(length)``: a difference of means)
    or ``"max"`` (the largest of the samples'); ``null_model``: how :func:`thresholds` reads
    the null of the grid points about the record's ``e``: ``"pooled"`` (their nulls pooled,
    each point's location and spread its own) or ``"widest"`` (each point's location its
    own, one spread for the whole grid, :func:`null`'s ``shared_spread``; the threshold the
    loosest of the points').
    """

    name: str
    defect: str
    statistic: Callable
    side: str
    message: str
    length: str = "free"
    null_model: str = "pooled"
    floor: Callable | None = None

    @property
    def threshold(self) -> str:
        """``"structural"`` for a check with a :attr:`floor`, else ``"calibrated"``."""
        return "calibrated" if self.floor is None else "structural"


REGISTRY = (
    Check("nonstationary", "the load's strength changes along the record", nonstationarity, "high",
          "the response is not stationary: the rms of its blocks follows a trend or steps more than in stationary records like it "
          "(z {value:.1f}, calibrated limit {threshold:.1f}); the load changes along the record, so estimate stretches "
          "of steady load apart"),
    Check("drift", "a slow offset of the zero", drift, "high",
          "the record's block means wander more than rocking makes them (drift z {value:.1f}, calibrated limit "
          "{threshold:.1f}): the sensor's zero drifts; remove the trend (high-pass well below the rocking frequency)"),
    Check("spikes", "isolated wrong samples", spikes, "high",
          "a sample stands {value:.1f} times as far off the line through its neighbours as the record's 99th percentile "
          "of that distance, where rocking records like it reach {threshold:.1f}: the record holds spikes; remove them "
          "or mark them as gaps (NaN)", "max"),
    Check("asymmetry", "a block leaning on one side", asymmetry, "high",
          "the response is asymmetric: the block falls back with a different g on each side (|g+ - g-|/(g+ + g-) "
          "{value:.3f}, calibrated limit {threshold:.3f}); it may lean on one side or the load push one way, and the "
          "model assumes a symmetric block", "root", "widest"),
    Check("filtered", "a low-pass filter after the block, or a soft contact", impact_sharpness, "high",
          "the impacts' velocity jumps are spread over several samples: read over one sample they hold {value:+.3f} more "
          "of the jump's logarithm than read over " + str(IMPACT_WIDE) + ", where records of this model (unfiltered, "
          "instantaneous impacts) reach {threshold:+.3f}: " + BLUNTED_HELP),
    Check("few_triggers", "gaps (NaN) that cost triggers", segments, "low",
          "gaps (NaN) leave {value:.0%} of the record's trigger positions a whole segment (below {threshold:.0%}): the "
          "record gives that share of the triggers of the calibration's records, which have no gaps, so its interval is "
          "too narrow by about 1/sqrt({value:.2f}); cut the record into pieces without gaps", floor=lambda e, level: MIN_SEGMENTS),
    Check("coarse_sampling", "too few samples per cycle for e1..e4", sampling, "low",
          "{value:.1f} samples per cycle at sigma_Y is below {threshold:.1f}, too coarse for the local fits of e1..e4 "
          "(eq. 27); sample faster", floor=fits.min_points_per_cycle),
)
"""Every check, in the order of the ``check`` coordinate."""

CHECKS = tuple(check.name for check in REGISTRY)
"""Names of the checks, in registry order."""


def statistics(records, analysis, replaced=None) -> np.ndarray:
    """Every check's statistic on ``records`` (1-D arrays, NaN allowed) and their
    :class:`rockdec.rdd.measured.Analysis`, in registry order; ``replaced``: the samples the
    repair replaced, per record (:func:`sums`)."""
    s = sums(records, replaced)
    return np.array([check.statistic(s, analysis) for check in REGISTRY], dtype=float)


def _near(e_grid: np.ndarray, e: float, interval, side: int = 1) -> np.ndarray:
    """Grid points pooled for a record of corrected ``e`` and 95 % ``interval``: those inside
    the interval and the ``side`` nearest beyond each of its ends (beyond ``e`` without an
    interval), so that the points bracket every ``e`` the interval allows: a statistic that
    moves with ``e`` (``filtered`` at low ``e``) read against points on one side of the
    truth alone would fire on clean records whose ``e`` came out low."""
    keep = np.zeros(e_grid.size, dtype=bool)
    low, high = (np.nan, np.nan) if interval is None else (np.nan if v is None else v for v in interval)
    if np.isfinite(low) and np.isfinite(high):
        keep |= (e_grid >= low) & (e_grid <= high)
    else:
        low = high = e
    below, above = np.flatnonzero(e_grid <= min(e, low)), np.flatnonzero(e_grid >= max(e, high))
    keep[below[-side:] if below.size else 0] = True
    keep[above[:side] if above.size else -1] = True
    return keep


def length_threshold(check: Check, column: np.ndarray, q: float, ratio: float) -> float:
    """The ``q`` quantile of ``check``'s statistic on records ``ratio`` (> 1) times as long as
    the calibration's, from its values ``column`` on the calibration's records: by the
    check's ``length`` law, the quantile of ``column`` over ``sqrt(ratio)`` (``"root"``); for ``"max"`` the largest of ``ratio`` records like the
    calibration's, the values taken as Gumbel (moments: scale ``beta = sd sqrt(6) / pi``), whose
    ``q`` quantile is ``mu + beta (ln ratio - ln(-ln q))``; ``"free"``: the quantile itself."""
    if check.length == "root":
        return float(np.quantile(column, q)) / np.sqrt(ratio)
    if check.length == "max" and column.size > 1:
        beta = float(np.std(column, ddof=1)) * np.sqrt(6.0) / np.pi
        mu = float(np.mean(column)) - np.euler_gamma * beta
        return mu + beta * (np.log(ratio) - np.log(-np.log(q)))
    return float(np.quantile(column, q))


def null(values: np.ndarray, group: np.ndarray, shared_spread: bool = False) -> np.ndarray:
    """The null of one check for the grid points ``group`` (a mask of the grid) from its
    values ``(e_true, set)`` on the calibration's sets: each grid point's mean plus its
    standard deviation times every standardized value of the calibration (each grid point's
    values less their mean, over their standard deviation, pooled over the grid), the
    points of ``group`` pooled. ``shared_spread``: one standard deviation for every grid
    point, the root mean of the usable points' variances (a statistic whose spread, as a
    logarithm, is the same at every ``e``: :data:`REGISTRY`'s ``"widest"`` nulls), so only
    the location is read off each point's sets. The shape of the null's tail is read off every set of the
    calibration, only its location and scale off the sets near the record's ``e`` (those of
    three or so grid points): a tail quantile of so few sets rests on their few largest values. Values all positive (counts, ratios, magnitudes) are
    located and scaled as logarithms, so the null stays positive. A grid point with fewer
    than :data:`NULL_MIN_SETS` finite values or none spread contributes its values as they
    are."""
    finite = np.isfinite(values)
    log = bool((values[finite] > 0.0).all())
    values = np.log(np.where(finite, values, 1.0)) if log else values
    usable = finite.sum(axis=1) >= NULL_MIN_SETS
    mean, sd = np.full(values.shape[0], np.nan), np.full(values.shape[0], np.nan)
    for j in np.flatnonzero(usable):
        v = values[j][finite[j]]
        mean[j], sd[j] = v.mean(), v.std(ddof=1)
    usable &= sd > 0.0
    if shared_spread and usable.any():
        sd[usable] = np.sqrt(np.mean(sd[usable] ** 2))
    shape = np.concatenate([(values[j][finite[j]] - mean[j]) / sd[j] for j in np.flatnonzero(usable)] or [np.empty(0)])
    parts = [mean[j] + sd[j] * shape if usable[j] else values[j][finite[j]] for j in np.flatnonzero(group)]
    out = np.concatenate(parts) if parts else np.empty(0)
    return np.exp(out) if log else out


def thresholds(cal, e: float | None, interval, level: float, length_ratio: float = 1.0) -> dict:
    """Each check's threshold for a record of corrected ``e`` and 95 % ``interval``, from the
    calibration ``cal``'s ``diagnostic(e_true, set, check)`` (module docstring): the
    :data:`QUANTILE` quantile (``1 - QUANTILE`` for a ``"low"`` check) of the :func:`null`
    of the grid points pooled about ``e`` (where the record's estimators place it,
    :func:`rockdec.estimation.checks_place`; for a ``"widest"`` :class:`Check`, the
    loosest of those points' own). A record without an ``e`` (``None`` or
    NaN: no estimator places it) gets the strictest grid point's threshold, each grid point's
    null apart. ``level``: the trigger level in ``sigma_Y`` (for the structural floor). NaN
    for a check the calibration's records never gave a value. ``length_ratio``: the records'
    length over the calibration's records' (above 1 for records longer than
    :data:`rockdec.calibrate.calibration.LENGTH_CAP`: :func:`length_threshold`, and the two
    nearest grid points on each side of ``e`` pooled, :func:`_near`)."""
    grid = np.asarray(cal["e_true"].values, dtype=float)
    placed = e is not None and np.isfinite(e)
    # a long record's narrow interval holds few grid points: two on each side keep the quantile's own error small
    groups = [_near(grid, e, interval, 2 if length_ratio > 1.0 else 1)] if placed else [grid == g for g in grid]
    values = cal["diagnostic"].values  # (e_true, set, check)
    out = {}
    for j, check in enumerate(REGISTRY):
        if check.threshold == "structural":
            out[check.name] = float(check.floor(e if placed else FLOOR_E, level))
            continue
        q = QUANTILE if check.side == "high" else 1.0 - QUANTILE
        widest = check.null_model == "widest"
        limits = []
        for group in groups:
            # "widest": each grid point of the group its own null, the loosest of their thresholds
            columns = [null(values[:, :, j], grid == g, True) for g in grid[group]] if widest else [null(values[:, :, j], group)]
            own = [length_threshold(check, c, q, length_ratio) if length_ratio > 1.0 else float(np.quantile(c, q)) for c in columns if c.size]
            if own:
                limits.append(max(own) if check.side == "high" else min(own))
        out[check.name] = (min(limits) if check.side == "high" else max(limits)) if limits else np.nan
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


def evaluate(records, analysis, cal, e: float | None, interval, level: float, length_ratio: float = 1.0, replaced=None) -> dict:
    """Every check on ``records`` against the calibration ``cal``: :func:`judge` of
    :func:`statistics` and :func:`thresholds` (``length_ratio``: the records' length over
    the calibration's records'; ``replaced``: the samples the repair replaced, per record)."""
    return judge(statistics(records, analysis, replaced), thresholds(cal, e, interval, level, length_ratio))

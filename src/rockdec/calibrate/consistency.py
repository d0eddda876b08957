"""Whether records given together are consistent with one coefficient of restitution.

Records pooled by :func:`rockdec.calibrate.inference.estimate` are taken to be of one block:
their triggers add into one signature per window and one ``e`` is calibrated for them
all. Records of two blocks (or of one block whose ``e`` changed between tests) pool into
an ``e`` that holds neither. This module tests that assumption; the estimate calls it in
its stage :func:`rockdec.calibrate.inference.check_pooled`.

The test (no equation of the paper: a test of homogeneity, Cochran's ``Q``). Record ``i``
of ``n_i`` samples, analysed alone (:func:`rockdec.rdd.measured.analyse`), gives the raw
zero-window value ``x_i`` of the reported estimator. Under the null, one ``e`` for every
record, ``x_i`` scatters about the belt's mean ``m(e)`` with the belt's spread at the
length of the calibration's simulated record sets, ``s(e)`` at ``N`` samples, scaled to the
record's length (the spread falls as ``1/sqrt(length)``, which is how the belt of records
longer than the calibration's is scaled too,
:func:`rockdec.calibrate.calibration.spread_scale`)::

    s_i = s(e) sqrt(N / n_i),   w_i = 1 / s_i^2  (proportional to n_i),
    x_w = sum(n_i x_i) / sum(n_i),
    Q   = sum(w_i (x_i - x_w)^2)  ~  chi^2 with k - 1 degrees of freedom (k records).

``Q`` compares the records with each other, not with ``m(e)``: the error of the
calibration's mean curve, and any bias that the records share, cancel; only the spread is
read off the belt, at ``e_w``, where the mean curve takes ``x_w`` (:func:`reads`; the end
of the curve nearest ``x_w`` beyond it). Not at the pooled records' corrected ``e``: records
of two blocks at ``e`` = 0.85 and 0.6 (one step, so the second has a smaller amplitude and
fewer samples per cycle) pool into an ``e`` near the lower one, where the spread is several
times the one at 0.85, and the test read there missed such pairs
(``benchmarks/pooled_consistency.py``); their own mean lies between them. The records'
own values also say where each lies (:func:`reads`), which the message names.

Before any of this, the records' scales are compared (:func:`scales_apart`): ``g`` (the
restoring acceleration, rad/s^2) is one block's constant, and each record reads its own off
its free response (:func:`rockdec.rdd.measured.analyse` of the record alone). A record in
degrees (or mrad) beside one in rad reads ``g`` 57.3 (1000) times the other's, and pooled,
the first's triggers, at a level from the pooled ``sigma_Y``, are the only ones: an interval
calibrated for both records' samples on the triggers of one. The records' ``sigma_Y`` do not
tell it: at one load independent records of one block differ in ``sigma_Y`` up to 20 times
at 2,000 samples, and records of one block at loads 2-3 times apart (which pool today)
differ by 3-300 times, while their ``g`` agree.

The threshold is the :data:`LEVEL` quantile of ``chi^2_{k-1}`` (:func:`threshold`); its
false-alarm rate on pairs of records of one block and its detection rate on pairs of two
blocks are measured by ``benchmarks/pooled_consistency.py``.

Limits. Every record is taken to share the mean ``m(e)`` of the pooled records' belt: a
record much shorter than the others, or read at other samples per cycle, has a bias of its
own, which the test counts as disagreement (measured on records of equal length only). The
raw values are taken as normal; where they are not (``e_v`` at low ``e``), the point
:data:`LEVEL` absorbs it.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

__all__ = [
    "G_FACTOR", "LEVEL", "UNITS", "UNITS_RATIO", "check", "reads", "record_spreads", "scales_apart",
    "spread_at", "statistic", "threshold",
]

#: Share of the ``chi^2_{k-1}`` distribution below the threshold (:func:`threshold`): a pool
#: of records of one block whose raw values were normal with the belt's spread would fire on
#: ``1 - LEVEL`` of pools. Far stricter than 95 % because neither holds at low ``e``: a single
#: record's ``e_v`` there has a heavy right tail, and the belt's spread, from the finite
#: sets per grid point of such values, falls short of their scatter. The rates of pairs of one
#: block and of two blocks at each level: ``benchmarks/pooled_consistency.py``
#: (docs/explanation/method/warnings.md, "Records given together").
LEVEL = 0.999


#: Records of one block whose own ``g`` differ by more than this factor are declined
#: (:func:`scales_apart`): independent pairs of records of one block at one load, each read
#: alone, exceed it on 0.07 % of pairs of 1,000 samples, 0.01 % of 2,000 and none of 5,000 to
#: 200,000 (at ``e`` 0.6, 0.85, 0.95 and 25 and 75 samples per cycle, the project's simulator and
#: the independent one of the tests, 21,240 pairs a length; ``benchmarks/pooled_scales.py``);
#: records of one block at loads 2-3 times apart (``sigma_Y`` 3-300 times apart) pass.
G_FACTOR = 4.0

#: Records whose own ``g`` differ by this factor or more are refused as given in different
#: units (:func:`scales_apart`): no pair of one block reached it in the measurement of
#: :data:`G_FACTOR`; of 260 pairs of independent records (2,000 and 20,000 samples) whose
#: second is in degrees, mrad, µrad or (against degrees) mrad, or whose first is in degrees,
#: all were refused but one of mrad against degrees at 2,000 samples, which was declined.
UNITS_RATIO = 10.0

#: Ratios of one angle in two units, and the units they tell apart (a ratio within
#: :data:`UNITS_NEAR` of one is named).
UNITS = {
    180.0 / math.pi: "degrees against rad",
    1e3 * math.pi / 180.0: "mrad against degrees",
    1e3: "mrad against rad (or mdeg against degrees)",
    1e6: "µrad against rad",
}

#: Relative distance of a ``g`` ratio from a ratio of :data:`UNITS` within which it is named.
UNITS_NEAR = 0.25


class Scales(NamedTuple):
    """The outcome of :func:`scales_apart`: ``kind`` ``"units"`` (refused) or ``"blocks"``
    (declined), and the sentence."""

    kind: str
    message: str


def scales_apart(sources, sigmas, gs) -> Scales | None:
    """Whether records given together read ``g`` too far apart to be of one block in one unit
    (module docstring), or ``None``.

    The records with a finite ``g`` are compared, the largest against the smallest: a ratio of
    :data:`UNITS_RATIO` or more is ``"units"`` (the ratio of :data:`UNITS` nearest it named
    when within :data:`UNITS_NEAR`), one beyond :data:`G_FACTOR` ``"blocks"``; each names
    every record's ``g`` (and, for units, ``sigma_Y`` against the smallest's).

    Parameters
    ----------
    sources : sequence of str
        The records' names.
    sigmas : sequence of float
        Each record's ``sigma_Y`` (its units).
    gs : sequence of float
        Each record's own ``g`` (its units per s^2; NaN: not read, left out).

    Returns
    -------
    Scales or None

    Examples
    --------
    >>> scales_apart(["a.csv", "b.csv"], [0.003, 0.17], [1.0, 57.5]).message
    "the records seem to be in different units (b.csv's g reads 57.5 times a.csv's and its sigma_Y 56.7 times, as degrees against rad give): give them in one unit (rad)"
    >>> scales_apart(["a.csv", "b.csv"], [0.003, 0.009], [1.0, 1.3]) is None
    True
    """
    g = np.asarray(gs, dtype=float)
    ok = np.flatnonzero(np.isfinite(g) & (g > 0.0))
    if ok.size < 2:
        return None
    low, high = int(ok[np.argmin(g[ok])]), int(ok[np.argmax(g[ok])])
    ratio = float(g[high] / g[low])
    if ratio <= G_FACTOR:
        return None
    if ratio >= UNITS_RATIO:
        factor = min(UNITS, key=lambda f: abs(math.log(ratio / f)))
        named = f", as {UNITS[factor]} give" if abs(ratio / factor - 1.0) <= UNITS_NEAR else ""
        return Scales("units", (
            f"the records seem to be in different units ({sources[high]}'s g reads {ratio:.3g} times {sources[low]}'s and its "
            f"sigma_Y {sigmas[high] / sigmas[low]:.3g} times{named}): give them in one unit (rad)"
        ))
    readings = ", ".join(f"{sources[i]} {g[i]:.3g}" for i in ok)
    return Scales("blocks", (
        f"the records given together read g alone {ratio:.3g} times apart ({readings} rad/s^2), beyond the {G_FACTOR:g} within "
        "which records of one block agree: they are not of one block, or one is not in rad; estimate each record alone, "
        "or pool only records of one block"
    ))


class Consistency(NamedTuple):
    """The outcome of :func:`check`: Cochran's ``statistic`` ``Q``, its ``threshold``,
    whether it ``fired``, the degrees of freedom ``dof`` (records tested less one), each
    record's standardised offset ``z_i = (x_i - x_w) / s_i`` (NaN for a record left out)."""

    statistic: float
    threshold: float
    fired: bool
    dof: int
    z: np.ndarray


def record_spreads(spread: float, simulated_samples: int, lengths) -> np.ndarray:
    """The spread of each record's raw value alone: ``s_i = s sqrt(N / n_i)``.

    Parameters
    ----------
    spread : float
        The belt's spread ``s(e)`` at the pooled ``e``, for record sets of
        ``simulated_samples`` in all (:attr:`rockdec.calibrate.belt.Belt.spread` of the
        belt at the calibration's simulated length).
    simulated_samples : int
        ``N``: samples in all of one of the calibration's simulated record sets.
    lengths : sequence of int
        ``n_i``: samples of each record.

    Returns
    -------
    numpy.ndarray
        ``s_i``, one per record.

    Examples
    --------
    >>> record_spreads(0.01, 400_000, [200_000, 100_000]).round(5).tolist()
    [0.01414, 0.02]
    """
    return float(spread) * np.sqrt(float(simulated_samples) / np.asarray(lengths, dtype=float))


def statistic(raws, spreads) -> tuple[float, np.ndarray]:
    """Cochran's ``Q`` of the raw values ``x_i`` with spreads ``s_i`` (module docstring),
    and each record's standardised offset from their weighted mean; records whose raw
    value or spread is not finite are left out (their offset NaN).

    Parameters
    ----------
    raws : sequence of float
        ``x_i``: each record's raw value of the estimator.
    spreads : sequence of float
        ``s_i``: the spread of each (:func:`record_spreads`).

    Returns
    -------
    tuple of (float, numpy.ndarray)
        ``Q`` (NaN with fewer than two usable records) and ``z_i = (x_i - x_w) / s_i``.

    Examples
    --------
    Two records one spread either side of their mean: ``Q = 1 + 1``.

    >>> q, z = statistic([0.79, 0.81], [0.01, 0.01])
    >>> round(q, 6), z.round(6).tolist()
    (2.0, [-1.0, 1.0])
    """
    x, s = np.asarray(raws, dtype=float), np.asarray(spreads, dtype=float)
    ok = np.isfinite(x) & np.isfinite(s) & (s > 0.0)
    z = np.full(x.shape, np.nan)
    if ok.sum() < 2:
        return math.nan, z
    w = 1.0 / s[ok] ** 2
    centre = float(np.sum(w * x[ok]) / np.sum(w))
    z[ok] = (x[ok] - centre) / s[ok]
    return float(np.sum(z[ok] ** 2)), z


def threshold(dof: int, level: float = LEVEL) -> float:
    """The ``level`` quantile of ``chi^2`` with ``dof`` degrees of freedom (NaN for none).

    Parameters
    ----------
    dof : int
        Records tested less one.
    level : float
        Share of the null below the threshold (:data:`LEVEL`).

    Returns
    -------
    float

    Examples
    --------
    With one degree of freedom, the square of the normal quantile:

    >>> round(threshold(1, 0.95), 4)
    3.8415
    """
    if dof < 1:
        return math.nan
    from scipy.special import chdtri

    return float(chdtri(dof, 1.0 - level))


def centre(raws, lengths) -> float:
    """``x_w = sum(n_i x_i) / sum(n_i)`` over the records with a finite raw value (NaN for none).

    Examples
    --------
    >>> round(centre([0.80, 0.90, float("nan")], [100_000, 300_000, 50_000]), 6)
    0.875
    """
    x, n = np.asarray(raws, dtype=float), np.asarray(lengths, dtype=float)
    ok = np.isfinite(x)
    return float(np.sum(n[ok] * x[ok]) / np.sum(n[ok])) if ok.any() else math.nan


def spread_at(mean_e: np.ndarray, mean: np.ndarray, spread: np.ndarray, raw: float) -> float:
    """The belt's spread where its mean curve takes the value ``raw`` (:func:`reads`), at
    the end of the curve nearest ``raw`` when the curve never takes it; NaN for an empty belt.

    Examples
    --------
    >>> import numpy as np
    >>> e = np.linspace(0.4, 0.99, 60)
    >>> round(spread_at(e, e, 0.1 * (1 - e), 0.9), 6), round(spread_at(e, e, 0.1 * (1 - e), 1.5), 6)
    (0.01, 0.001)
    """
    if mean.size == 0 or not np.isfinite(raw):
        return math.nan
    e = reads(mean_e, mean, raw)
    if not np.isfinite(e):
        e = mean_e[int(np.argmin(np.abs(mean - raw)))]
    return float(np.interp(e, mean_e, spread))


def check(raws, lengths, mean_e: np.ndarray, mean: np.ndarray, spread: np.ndarray, simulated_samples: int,
          level: float = LEVEL) -> Consistency:
    """Whether the records' raw values agree with one ``e`` (module docstring): Cochran's
    ``Q`` (:func:`statistic`) with the spreads of :func:`record_spreads`, the belt's spread
    read where its mean takes the records' weighted mean (:func:`centre`,
    :func:`spread_at`), against the ``level`` quantile of ``chi^2_{k-1}``
    (:func:`threshold`), ``k`` the records with a finite raw value. Fewer than two such
    records: NaN statistic, never fired.

    Parameters
    ----------
    raws : sequence of float
        Each record's raw value of the estimator, analysed alone (NaN: not analysed).
    lengths : sequence of int
        Samples of each record.
    mean_e, mean, spread : numpy.ndarray
        The belt of the estimator at the length of the calibration's simulated record sets:
        its dense ``e``, mean curve and spread (:class:`rockdec.calibrate.belt.Belt`).
    simulated_samples : int
        Samples in all of one of the calibration's simulated record sets.
    level : float
        :data:`LEVEL`.

    Returns
    -------
    Consistency

    Examples
    --------
    Two records of 200,000 samples, calibrated on pairs (400,000 samples) whose raw value
    reads ``e`` with a spread of 0.004: each record alone scatters by 0.0057, and raw
    values 0.03 apart are 3.7 spreads of their difference apart.

    >>> import numpy as np
    >>> e = np.linspace(0.4, 0.995, 200)
    >>> c = check([0.80, 0.83], [200_000, 200_000], e, e, np.full(e.size, 0.004), 400_000)
    >>> c.fired, round(c.statistic, 2), c.dof
    (True, 14.06, 1)
    >>> check([0.80, float("nan")], [200_000, 200_000], e, e, np.full(e.size, 0.004), 400_000).fired
    False
    """
    s = spread_at(mean_e, mean, spread, centre(raws, lengths))
    q, z = statistic(raws, record_spreads(s, simulated_samples, lengths))
    dof = int(np.isfinite(z).sum()) - 1
    limit = threshold(dof, level)
    return Consistency(q, limit, bool(q > limit), max(dof, 0), z)


def reads(mean_e: np.ndarray, mean: np.ndarray, raw: float) -> float:
    """The ``e`` at which the belt's mean curve ``mean(mean_e)`` takes the value ``raw``:
    where a record's raw value alone places it (its bias corrected at the pooled records'
    length), for the message; NaN when the curve never takes it.

    Parameters
    ----------
    mean_e, mean : numpy.ndarray
        The belt's dense ``e`` and its mean curve (:class:`rockdec.calibrate.belt.Belt`).
    raw : float
        A record's raw value.

    Returns
    -------
    float

    Examples
    --------
    >>> import numpy as np
    >>> e = np.linspace(0.4, 0.99, 60)
    >>> round(reads(e, e + 0.01, 0.86), 4)
    0.85
    """
    if not np.isfinite(raw) or mean.size < 2:
        return math.nan
    gap = np.asarray(mean) - raw
    crossing = np.flatnonzero(np.diff(np.sign(gap)) != 0)
    if crossing.size == 0:
        return math.nan
    i = int(crossing[0])
    return float(mean_e[i] + (mean_e[i + 1] - mean_e[i]) * gap[i] / (gap[i] - gap[i + 1]))

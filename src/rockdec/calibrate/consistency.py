"""Whether records given together are consistent with one coefficient of restitution.

Records pooled by :func:`rockdec.estimation.estimate` are taken to be of one block;
this module tests it, for the stage :func:`rockdec.estimation.check_pooled` (no
equation of the paper: Cochran's test of homogeneity). First the scales
(:func:`scales_apart`): ``g`` is one block's constant, so records whose own ``g`` lie
:data:`G_FACTOR` times apart are not of one block, :data:`UNITS_RATIO` times not in one unit
(:data:`UNITS`). Then record ``i`` of ``n_i`` samples, analysed alone, gives the raw value
``x_i``, and (:func:`record_spreads`, :func:`centre`, :func:`statistic`)::

    s_i = s(e_w) sqrt(N / n_i),   x_w = sum(n_i x_i) / sum(n_i),
    Q   = sum((x_i - x_w)^2 / s_i^2)  ~  chi^2 with k - 1 degrees of freedom,

``s`` the belt's spread at the calibration's length ``N``, read where its mean takes ``x_w``
(:func:`spread_at`); :func:`threshold` is its :data:`LEVEL` quantile, :func:`check` the test,
:func:`reads` the ``e`` each record reads alone. Its rates: ``benchmarks/pooled_consistency.py``, ``benchmarks/pooled_scales.py``.

Explanation: docs/explanation/method/warnings.md (records given together).
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

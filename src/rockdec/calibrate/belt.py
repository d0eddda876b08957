"""The confidence belt: a calibration (:mod:`rockdec.calibrate.calibration`) turned into a
bias-corrected ``e`` and its 95 % interval, and ``g``'s (a Neyman construction).

:func:`fit` reads, across the calibration's grid of ``e``, the mean ``m(e)`` of the raw
estimate (its bias smoothed by a weighted cubic smoothing spline along one of
:data:`MEAN_VARIABLES`, chosen by generalised cross-validation, :data:`GCV_GAMMA`), its
spread ``s(e)`` (the same smoother in ``log(1 - e)``), both past the sets beyond
:data:`FENCE`, and the band's 2.5 % and 97.5 % quantiles ``q_low``, ``q_high`` in units of
the spread (pooled over :data:`QUANTILE_BANDWIDTH`). The band at ``e`` is
``m(e) + [q_low, q_high] sqrt(s(e)^2 + var m(e))``; :func:`correct` solves ``m(e) = x``, and
the interval is every ``e`` whose band holds ``x`` (:func:`intervals`). ``g`` is corrected
by the calibration's mean ratio at the corrected ``e`` (:func:`correct_g`), its interval from
the belt of the sets' corrected ``g`` (:func:`g_band`, :func:`g_interval`). Kept apart from
the calibration so that a change here never makes stored calibrations stale. Whether it
covers: :mod:`rockdec.studies.belt_study`, :mod:`rockdec.studies.coverage`.

Explanation: docs/explanation/method/measured-record.md (the confidence belt, ``g``'s interval).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np

if TYPE_CHECKING:  # annotations only: xarray loads where a function needs it
    import xarray as xr

    from rockdec.calibrate import ncread

__all__ = [
    "Belt", "Corrected", "GCV_GAMMA", "QUANTILE_BANDWIDTH", "Z95", "belt", "belts",
    "calibration_coverage", "correct", "correct_g", "fit", "g_band", "g_calibration_coverage",
    "g_interval", "g_intervals", "held_e", "held_es", "intervals", "width_at",
]

#: Two-sided normal quantile of the 95 % interval.
Z95 = 1.959963984540054


class Corrected(NamedTuple):
    """A bias-corrected estimate: ``value`` and the 95 % interval ``[low, high]``; ``notes``
    say when the interval reaches the end of the calibrated range or the raw value lies
    outside what any calibrated ``e`` produces."""

    value: float
    low: float
    high: float
    notes: tuple[str, ...]


class Belt(NamedTuple):
    """Smooth mean and spread of one estimator against the true ``e`` (module docstring);
    ``failed``: the fraction of calibration sets on which the estimator gave NaN; the 95 %
    band at each ``e`` is ``[mean + q_low spread, mean + q_high spread]`` (``q_low``,
    ``q_high``: the 2.5 % and 97.5 % quantiles of the standardised raw value, widened by
    Student's t for a spread estimated from few sets; a normal estimator known exactly has
    ``-Z95`` and ``Z95``)."""

    e: np.ndarray
    mean: np.ndarray
    spread: np.ndarray
    failed: float
    q_low: np.ndarray | float = -Z95
    q_high: np.ndarray | float = Z95


#: Fences of the raw values: those more than this many interquartile ranges beyond their
#: grid point's quartiles are left out of its mean and spread (they stay in the band's
#: quantiles). A normal estimator puts 1e-13 of its sets there (7.4 standard deviations),
#: a gamma of shape 4 (skewness 1, ``e_v`` at low ``e``) 2e-5; one set that fails wildly
#: (``e_v`` near 1 under a low-pass load, the CHANGELOG says how far) would otherwise set the
#: spread of its grid point and, through the smoothing, of its neighbours.
FENCE = 5.0

#: Bandwidth (in ``log(1 - e)``) of the Gaussian kernel that pools the standardised raw
#: values of neighbouring grid points into the quantiles of the band.
QUANTILE_BANDWIDTH = 0.8

#: Penalty on the degrees of freedom in the generalised cross-validation of the smoothing
#: splines (1 is plain GCV; above 1 guards against its undersmoothing on few points).
GCV_GAMMA = 1.4

#: The penalty of :data:`GCV_GAMMA` for a belt scaled to longer records than its sets
#: (:func:`fit`, ``scale`` below 1): plain GCV, which follows the bias's bends closer (on
#: records of millions of samples ``e_v``'s bias bends between ``e`` = 0.8 and 0.92 by
#: several of their spreads, which :data:`GCV_GAMMA` smooths away in part; the long-records
#: coverage benchmark ``benchmarks/long_coverage.py`` shows it).
GCV_GAMMA_LONG = 1.0

#: Variables along which the mean's offset from ``e`` is smoothed (:func:`fit`), each a
#: function of ``e`` that increases as ``e`` falls (the order of the grid points); the one
#: whose smoothing cross-validates best is taken. ``1/e`` stretches low ``e``, where ``e_v``'s
#: bias bends (evidence: docs/explanation/constants.md).
MEAN_VARIABLES = {"e": np.negative, "log(1 - e)": lambda e: np.log1p(-e), "1/e": np.reciprocal}

#: Smoothing parameters tried by the cross-validation, relative to the weights' scale.
_LAMBDAS = np.logspace(-6, 8, 57)


def _reinsch(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The matrices ``Q`` ``(n, n-2)`` and ``R`` ``(n-2, n-2)`` of the natural cubic spline
    through values ``f`` at the knots ``x`` (increasing): its second derivatives at the
    inner knots are ``R^-1 Q^T f`` (zero at the ends), and the integral of its squared
    second derivative is ``f @ Q R^-1 Q^T @ f`` (Green and Silverman, 1994, section 2.1)."""
    h = np.diff(x)
    n = x.size
    q = np.zeros((n, n - 2))
    r = np.zeros((n - 2, n - 2))
    for j in range(1, n - 1):
        q[j - 1, j - 1], q[j, j - 1], q[j + 1, j - 1] = 1.0 / h[j - 1], -1.0 / h[j - 1] - 1.0 / h[j], 1.0 / h[j]
        r[j - 1, j - 1] = (h[j - 1] + h[j]) / 3.0
        if j < n - 2:
            r[j - 1, j] = r[j, j - 1] = h[j] / 6.0
    return q, r


def _penalty(x: np.ndarray) -> np.ndarray:
    """Roughness matrix ``K`` of the natural cubic spline through values at the knots ``x``:
    ``f @ K @ f`` is the integral of its squared second derivative (:func:`_reinsch`)."""
    q, r = _reinsch(x)
    return q @ np.linalg.solve(r, q.T)


def _spline_basis(x: np.ndarray, at: np.ndarray) -> np.ndarray:
    """``(at, knots)``: the natural cubic spline through values ``f`` at the knots ``x``
    (increasing) takes the values ``basis @ f`` at the points ``at`` (within the knots)."""
    q, r = _reinsch(x)
    second = np.zeros((x.size, x.size))
    second[1:-1] = np.linalg.solve(r, q.T)  # second derivatives at the knots per unit value
    i = np.clip(np.searchsorted(x, at, side="right") - 1, 0, x.size - 2)
    h = x[i + 1] - x[i]
    b = (at - x[i]) / h
    a = 1.0 - b
    basis = np.zeros((at.size, x.size))
    rows = np.arange(at.size)
    basis[rows, i] += a
    basis[rows, i + 1] += b
    basis += ((a**3 - a) * h**2 / 6.0)[:, None] * second[i] + ((b**3 - b) * h**2 / 6.0)[:, None] * second[i + 1]
    return basis


def _smooth(x: np.ndarray, y: np.ndarray, w: np.ndarray, gamma: float = GCV_GAMMA) -> tuple[np.ndarray, np.ndarray, float, float]:
    """Weighted cubic smoothing spline through ``(x, y)`` (``x`` increasing, weights ``w``:
    inverse variances), its smoothing chosen by generalised cross-validation (penalty
    ``gamma``, :data:`GCV_GAMMA`); from a straight line (infinite smoothing) to interpolation.

    Returns the fitted values at ``x``, the hat matrix ``H`` (fitted = ``H @ y``), the
    residual variance in units of ``1/w`` (1 when the weights are right, more when the
    points scatter about any smooth curve by more than their weights say) and the
    cross-validation score.
    """
    n = x.size
    k = _penalty(x)
    wm = np.diag(w)
    lams = _LAMBDAS * w.sum() / np.trace(k)
    hats = np.linalg.solve(wm + lams[:, None, None] * k, np.broadcast_to(wm, (lams.size, n, n)))  # every smoothing at once
    fits = hats @ y
    dfs = np.trace(hats, axis1=1, axis2=2)
    rss = np.sum(w * (y - fits) ** 2, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        scores = np.where(n - gamma * dfs > 0.0, n * rss / (n - gamma * dfs) ** 2, np.inf)
    best = int(np.argmin(scores))  # the first of equal scores, the smoothest
    return fits[best], hats[best], float(rss[best] / (n - dfs[best])), float(scores[best])


def _weighted_quantiles(z: np.ndarray, w: np.ndarray, p) -> np.ndarray:
    """Quantiles ``p`` of the values ``z`` with weights ``w`` (midpoint rule)."""
    order = np.argsort(z)
    z, w = z[order], w[order]
    cum = (np.cumsum(w) - 0.5 * w) / w.sum()
    return np.interp(p, cum, z)


def belt(cal: ncread.Stored | xr.Dataset, name: str, points: int = 4001, scale: float = 1.0) -> Belt:
    """The belt of estimator ``name`` (or of ``g``'s ratio to the true ``g``) on a dense
    grid of ``points`` values of ``e``, its spread scaled by ``scale`` (:func:`fit`)."""
    from rockdec.rdd.measured import G_NAME

    return fit(cal["e_true"].values, cal["raw"].sel(name=name).values, name == G_NAME, points, scale)


def fit(e_grid: np.ndarray, raw: np.ndarray, ratio: bool = False, points: int = 4001, scale: float = 1.0) -> Belt:
    """The belt of raw values ``raw(e, set)`` simulated at the true ``e_grid``, on a dense grid
    of ``points`` values of ``e`` (module docstring): the mean is smoothed as its offset from
    ``e`` (from 1 for a ``ratio``) along whichever of :data:`MEAN_VARIABLES` cross-validates
    best; the spread along ``u = log(1 - e)``.

    ``scale``: the belt of records whose spread is ``scale`` times the simulated sets'
    (records longer than the simulated ones:
    :func:`rockdec.calibrate.calibration.spread_scale`): the fitted spread ``s(e)`` is
    scaled, the error of the fitted mean (``var m``, from the sets as simulated) is not, and
    both curves are smoothed with the penalty :data:`GCV_GAMMA_LONG`.

    ``failed``: the fraction of sets that gave NaN. Fewer than 5 usable grid points (3 sets
    at least) give an empty belt, which :func:`correct` refuses to invert.
    """
    e_grid = np.asarray(e_grid, dtype=float)
    ok = np.isfinite(raw)
    kept = ok & _within_fences(raw)
    n = kept.sum(axis=1)
    use = n >= 3
    means = np.array([raw[j, kept[j]].mean() if use[j] else np.nan for j in range(e_grid.size)])
    sds = np.array([raw[j, kept[j]].std(ddof=1) if use[j] else np.nan for j in range(e_grid.size)])
    use &= sds > 0
    failed = float(1.0 - ok.sum() / ok.size)
    if use.sum() < 5:  # an empty belt: correct() says why
        return Belt(np.empty(0), np.empty(0), np.empty(0), failed)
    order = np.argsort(np.log1p(-e_grid[use]))  # increasing u = log(1 - e): decreasing e
    x = e_grid[use][order]
    u = np.log1p(-x)
    counts = n[use][order]
    gamma = GCV_GAMMA if scale == 1.0 else GCV_GAMMA_LONG
    log_s, hat_s, scatter_s, _ = _smooth(u, np.log(sds[use][order]), 2.0 * (counts - 1.0), gamma)
    s_fit = np.exp(log_s)
    w = counts / s_fit**2
    centre = np.ones_like(x) if ratio else x
    # the mean along the variable that cross-validates best
    along, (bias, hat, scatter, _) = min(((f, _smooth(f(x), means[use][order] - centre, w, gamma)) for f in MEAN_VARIABLES.values()), key=lambda t: t[1][3])
    cov = (hat / w) @ hat.T * max(scatter, 1.0)
    sets = raw[use][order]
    # scatter about each point's own mean (the mean curve's error is var_mean's), in units of the
    # fitted spread, so that the quantiles also take up what the spread curve misses locally
    z = (sets - means[use][order][:, None]) / s_fit[:, None] * np.sqrt(counts / (counts - 1.0))[:, None]
    zok = np.isfinite(z)
    q = np.array([
        _weighted_quantiles(z[zok], (np.exp(-0.5 * ((u[:, None] - uj) / QUANTILE_BANDWIDTH) ** 2) / counts[:, None] * np.ones(z.shape))[zok], [0.025, 0.975])
        for uj in u
    ])
    dense = np.linspace(x.min(), x.max(), points)
    ud = np.log1p(-dense)
    basis = _spline_basis(along(x), along(dense))  # (dense, grid): the natural spline through the fitted values
    mean = (1.0 if ratio else dense) + basis @ bias
    var_mean = np.einsum("ij,jk,ik->i", basis, cov, basis)
    basis_s = _spline_basis(u, ud)
    spread = np.sqrt((scale * np.exp(basis_s @ log_s)) ** 2 + var_mean)
    var_log_s = np.einsum("ij,jk,ik->i", basis_s, (hat_s / (2.0 * (counts - 1.0))) @ hat_s.T * max(scatter_s, 1.0), basis_s)
    widen = _t_quantile(1.0 / (2.0 * var_log_s)) / Z95  # a spread estimated from few sets: Student's t
    return Belt(dense, mean, spread, failed, widen * np.interp(ud, u, q[:, 0]), widen * np.interp(ud, u, q[:, 1]))


def _within_fences(raw: np.ndarray) -> np.ndarray:
    """``(e, set)``: whether each raw value lies within the fences of its grid point,
    :data:`FENCE` interquartile ranges beyond its quartiles (every finite value when the
    quartiles coincide); NaN lies outside.

    Examples
    --------
    >>> raw = np.array([[0.80, 0.81, 0.79, 0.80, 0.21, np.nan]])
    >>> _within_fences(raw).tolist()
    [[True, True, True, True, False, False]]
    """
    finite = np.isfinite(raw)
    some = finite.any(axis=1)  # a grid point of NaN only has no quartiles
    q1, q3 = np.full((2, raw.shape[0], 1), np.nan)
    if some.any():
        q1[some], q3[some] = np.nanpercentile(np.where(finite[some], raw[some], np.nan), [25.0, 75.0], axis=1, keepdims=True)
    reach = FENCE * (q3 - q1)
    with np.errstate(invalid="ignore"):
        return finite & ((reach == 0.0) | ((raw >= q1 - reach) & (raw <= q3 + reach)))


def _t_quantile(dof: np.ndarray) -> np.ndarray:
    """The 97.5 % quantile of Student's t with ``dof`` degrees of freedom (Cornish-Fisher
    expansion about the normal's: within 1 % for ``dof >= 5``, 0.1 % for ``dof >= 10``)."""
    z = Z95
    return z + (z**3 + z) / (4.0 * dof) + (5.0 * z**5 + 16.0 * z**3 + 3.0 * z) / (96.0 * dof**2)


def belts(cal: ncread.Stored | xr.Dataset, scale: float = 1.0) -> dict[str, Belt]:
    """The belt of every name the calibration holds (each estimator of ``e``, and ``g``),
    spreads scaled by ``scale`` (:func:`fit`)."""
    return {str(name): belt(cal, str(name), scale=scale) for name in cal["name"].values}


def _edges(b: Belt) -> tuple[np.ndarray, np.ndarray]:
    """The lower and upper edge of the belt's 95 % band at each dense ``e``."""
    return b.mean + b.q_low * b.spread, b.mean + b.q_high * b.spread


def _inside(b: Belt, observed: np.ndarray) -> np.ndarray:
    """``(observation, dense e)``: where the 95 % band of the belt holds each observation."""
    lower, upper = _edges(b)
    x = np.asarray(observed, dtype=float)[:, None]
    return (x >= lower[None, :]) & (x <= upper[None, :])


def _spans(b: Belt, observed: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """The first and last dense ``e`` (indices) whose band holds each observation (first
    above last where none does, and for NaN), and the ``(observation, e)`` table of
    :func:`_inside` they were read from, or ``None`` when the band's edges both rise with
    ``e``: then every observation is held on one run of ``e``, found by bisection."""
    lower, upper = _edges(b)
    observed = np.asarray(observed, dtype=float)
    rising = bool(np.all(np.diff(lower) >= 0.0) and np.all(np.diff(upper) >= 0.0))
    if rising:
        return np.searchsorted(upper, observed, side="left"), np.searchsorted(lower, observed, side="right") - 1, None
    inside = _inside(b, observed)
    held = inside.any(axis=1)
    n = b.e.size
    return np.where(held, np.argmax(inside, axis=1), n), np.where(held, n - 1 - np.argmax(inside[:, ::-1], axis=1), -1), inside


def intervals(b: Belt, raws) -> tuple[np.ndarray, np.ndarray]:
    """The 95 % interval of :func:`correct` for every raw value of ``raws`` (flattened), at
    once: its low and high ends, NaN where no calibrated ``e`` holds the value or the belt
    is empty.

    Examples
    --------
    >>> e = np.linspace(0.4, 0.99, 60)
    >>> b = Belt(e, e, np.full(e.size, 0.01), 0.0)
    >>> low, high = intervals(b, [0.8, 2.0])
    >>> bool(low[0] < 0.8 < high[0]), bool(np.isnan(low[1]))
    (True, True)
    """
    raws = np.ravel(np.asarray(raws, dtype=float))
    low, high = np.full(raws.size, np.nan), np.full(raws.size, np.nan)
    if b.e.size == 0:
        return low, high
    first, last, _ = _spans(b, raws)
    found = first <= last
    low[found], high[found] = b.e[first[found]], b.e[last[found]]
    return low, high


def width_at(b: Belt, e: float) -> float:
    """Width of the 95 % interval the belt gives a raw value equal to its mean at ``e``:
    the interval an estimator gives at ``e`` apart from one record's scatter (wider where
    the band is wide or the mean curve flat, narrower where it meets an end of the
    calibrated range); NaN for an empty belt or a NaN ``e``."""
    if b.e.size == 0 or not np.isfinite(e):
        return float("nan")
    low, high = intervals(b, [np.interp(e, b.e, b.mean)])
    return float(high[0] - low[0])


def correct_g(g_belt: Belt, g_raw, e):
    """``g`` read off a record, corrected for its window bias: ``g_raw`` over the mean
    ratio (measured ``g`` / true ``g``) of the calibration at the corrected ``e``; NaN where
    ``e`` is NaN or when the ``g`` belt is empty. ``g_raw`` and ``e``: numbers, or arrays of
    one shape (one value each)."""
    if g_belt.e.size == 0:
        return np.full(np.shape(e), np.nan)[()]
    return np.asarray(g_raw, dtype=float) / np.interp(e, g_belt.e, g_belt.mean)


def g_band(cal: ncread.Stored | xr.Dataset, name: str, e_belt: Belt, g_belt: Belt) -> Belt:
    """The belt of the ratio corrected ``g`` / true ``g`` over the calibration's own sets,
    ``e`` read by estimator ``name`` (its belt ``e_belt``; ``g_belt`` the belt of ``g``).

    Each set's ``g`` is corrected as a record's is (:func:`correct_g` at the set's corrected
    ``e``, when its interval lies inside the calibrated range: :func:`held_es`), so the ratio
    holds both the scatter of ``g`` at a given ``e`` and the error of the corrected ``e`` it
    is divided by, and their correlation; its belt (:func:`fit`) gives :func:`g_interval`.
    """
    from rockdec.rdd.measured import G_NAME

    raw_e = cal["raw"].sel(name=name).values
    raw_g = cal["raw"].sel(name=G_NAME).values
    e = held_es(e_belt, np.where(np.isfinite(raw_g), raw_e, np.nan))
    return fit(cal["e_true"].values, correct_g(g_belt, raw_g, e), ratio=True)


def held_e(b: Belt, raw: float) -> float:
    """The corrected ``e`` of ``raw`` when its 95 % interval lies inside the calibrated range,
    else NaN: the ``e`` at which ``g``'s band applies (:func:`g_band`, :func:`g_interval`).
    An interval that reaches an end of the range holds ``e`` too loosely (on records of
    20,000 samples nearly every interval reaches ``e = 0.4``), and dividing ``g`` by the
    ratio at such an ``e`` under-covers ``g`` (``tests/calibrate/test_estimate.py``)."""
    return float(held_es(b, np.array([raw]))[0])


def held_es(b: Belt, raws: np.ndarray) -> np.ndarray:
    """:func:`held_e` of every raw value of ``raws`` (any shape), their bands found at once."""
    raws = np.asarray(raws, dtype=float)
    out = np.full(raws.shape, np.nan)
    if b.e.size == 0:
        return out
    with np.errstate(invalid="ignore"):
        on_curve = np.isfinite(raws) & (b.mean.min() <= raws) & (raws <= b.mean.max())  # beyond the mean curve: no estimate (estimation.beyond)
    where = np.flatnonzero(on_curve.ravel())
    observed = raws.ravel()[where]
    first, last, table = _spans(b, observed)
    held = (first <= last) & (first > 0) & (last < b.e.size - 1)
    flat = out.reshape(-1)
    for i in np.flatnonzero(held):
        idx = np.arange(first[i], last[i] + 1) if table is None else np.flatnonzero(table[i])
        flat[where[i]] = _corrected_value(b, observed[i], idx)[0]
    return out


def g_interval(band: Belt, e_belt: Belt, g_belt: Belt, raw_e: float, raw_g: float) -> tuple[float, float]:
    """95 % interval of the true ``g`` of a record whose raw values are ``raw_e`` (of the
    estimator of ``e_belt``) and ``raw_g``: ``g`` corrected at the corrected ``e``
    (:func:`correct_g`) over the ends of the 95 % band of :func:`g_band` at that ``e``.

    NaN ends when ``e`` is not held inside the calibrated range (:func:`held_e`), or when
    the band is empty or its lower end not positive.
    """
    low, high = g_intervals(e_belt, g_belt, band, np.array([raw_e]), np.array([raw_g]))[0]
    return float(low), float(high)


def g_intervals(e_belt: Belt, g_belt: Belt, band: Belt, raw_e: np.ndarray, raw_g: np.ndarray) -> np.ndarray:
    """``(set, 2)``: :func:`g_interval` for each pair of raw values ``raw_e``, ``raw_g``."""
    raw_e, raw_g = np.ravel(raw_e).astype(float), np.ravel(raw_g).astype(float)
    out = np.full((raw_e.size, 2), np.nan)
    if band.e.size == 0 or g_belt.e.size == 0:
        return out
    e = held_es(e_belt, raw_e)
    ok = np.isfinite(e)
    e = e[ok]
    g_value = correct_g(g_belt, raw_g[ok], e)
    mean, spread = np.interp(e, band.e, band.mean), np.interp(e, band.e, band.spread)
    low = mean + np.interp(e, band.e, np.broadcast_to(band.q_low, band.e.shape)) * spread
    high = mean + np.interp(e, band.e, np.broadcast_to(band.q_high, band.e.shape)) * spread
    good = (low > 0.0) & np.isfinite(g_value)
    rows = np.flatnonzero(ok)[good]
    out[rows, 0], out[rows, 1] = g_value[good] / high[good], g_value[good] / low[good]
    return out


def g_calibration_coverage(cal: ncread.Stored | xr.Dataset, name: str, e_belt: Belt, g_belt: Belt, band: Belt) -> float:
    """Share of the calibration's own record sets with an interval of ``g`` (:func:`g_interval`,
    ``e`` read by estimator ``name``) whose interval holds their true ``g``: in-sample, like
    :func:`calibration_coverage`; NaN when no set has one."""
    from rockdec.rdd.measured import G_NAME

    ends = g_intervals(e_belt, g_belt, band, cal["raw"].sel(name=name).values, cal["raw"].sel(name=G_NAME).values)
    given = np.isfinite(ends[:, 0])
    if band.e.size == 0 or not given.any():
        return float("nan")
    return float(np.mean((ends[given, 0] <= 1.0) & (1.0 <= ends[given, 1])))


def correct(b: Belt, observed: float) -> Corrected:
    """Invert the belt at ``observed``: the corrected ``e`` and its 95 % interval."""
    if not np.isfinite(observed):
        return Corrected(np.nan, np.nan, np.nan, ("no raw estimate",))
    if b.e.size == 0:
        return Corrected(np.nan, np.nan, np.nan, (f"the estimator failed on {b.failed:.0%} of the calibration records, too many for a belt",))
    notes = []
    inside = _inside(b, np.array([observed]))[0]
    if not inside.any():
        nearest = int(np.argmin(np.abs(observed - b.mean) / b.spread))
        return Corrected(np.nan, np.nan, np.nan, (f"the raw value {observed:.4f} is not produced by any calibrated e (nearest e = {b.e[nearest]:.3f})",))
    idx = np.flatnonzero(inside)
    low, high = b.e[idx[0]], b.e[idx[-1]]
    if idx[0] == 0 or idx[-1] == b.e.size - 1:
        notes.append(f"the interval reaches the end of the calibrated range [{b.e[0]:.3f}, {b.e[-1]:.3f}]")
    value, on_curve = _corrected_value(b, observed, idx)
    if not on_curve:
        notes.append("the raw value lies beyond the calibrated mean curve; the corrected value is its nearest point")
    return Corrected(value, float(low), float(high), tuple(notes))


def _corrected_value(b: Belt, observed: float, idx: np.ndarray) -> tuple[float, bool]:
    """The corrected value of ``observed`` whose band holds the dense ``e`` at ``idx``: where the
    mean curve meets the observation inside the interval, and ``True``; else the interval's
    point of the curve nearest it, and ``False``."""
    gap = b.mean[idx] - observed
    crossing = np.flatnonzero(np.diff(np.sign(gap)) != 0)
    if crossing.size:
        i = idx[crossing[0]]
        return float(np.interp(observed, sorted([b.mean[i], b.mean[i + 1]]), [b.e[i], b.e[i + 1]][:: 1 if b.mean[i] <= b.mean[i + 1] else -1])), True
    return float(b.e[idx[np.argmin(np.abs(gap))]]), False


def calibration_coverage(cal: ncread.Stored | xr.Dataset, name: str, b: Belt) -> float:
    """Share of the calibration's own record sets whose 95 % interval (:func:`correct`)
    holds their true ``e``: the coverage of the interval at the record's own settings.

    In-sample (the belt was fitted to these sets), so it can only flatter the interval a
    little; the out-of-sample check is :mod:`rockdec.studies.coverage`. Sets at a true ``e``
    outside the belt's range, and failed sets, count as not covered. NaN for an empty belt.
    """
    if b.e.size == 0:
        return float("nan")
    raw = cal["raw"].sel(name=name).values  # (e_true, set)
    truth = np.broadcast_to(cal["e_true"].values[:, None], raw.shape).ravel()
    low, high = intervals(b, raw)
    return float(np.mean((low <= truth) & (truth <= high)))

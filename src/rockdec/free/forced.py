"""The forced stretch of a shake-table test: ``e`` from every impact, the base a known load.

Between two impacts the simplified block (eq. 4) under the base's load ``k r(t)`` (``r``
the base over the uplift level, :func:`rockdec.free.shake.uplift_ratio`) flies as
``theta = c0 + c1 tau - sign g tau^2 / 2 + k L(t)``, ``L`` the base's double integral
from the arc's first sample (:func:`base_integrals`). That is linear in each arc's ``c0, c1``
and the record's ``g, k``, so all arcs of a record are fitted at once by least squares
(:func:`fit_arcs`); ``k / g`` is 1 when the base's units and the block's angle are right
(the ``load_gain``; past :data:`LOAD_GAIN_LIMIT` ``e`` is refused). A base record does not
say how the base moved between samples: each record is read twice (:data:`READINGS`), the
base linear between samples and held over each, each reading with the lag of the base
behind the angle that fits it best within :data:`MAX_SHIFT` samples (:func:`base_shift`).
Each impact's ``e`` is the ratio of the arcs' speeds where each meets zero, its error from
the arcs' fit; outliers beyond :data:`OUTLIER_MADS` set aside, the impacts' ``log e`` are
pooled as the free-rocking test's (:func:`rockdec.free.analysis.impact_mean`). Its standard
error is the delete-a-group jackknife's over :data:`GROUPS` runs of arcs, each refitted,
with Student's ``t``; records are pooled by their errors, each reading apart. The interval
(never narrower than :data:`FLOOR`) is the union of the two readings', so it holds
whichever way the base moved: their gap is systematic and does not average down over
records. Entry points: :func:`analyse_forced`, :func:`pool_forced`.

Explanation: docs/how-to/shake-table.md (every impact, the base a known load).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
from scipy import stats

from rockdec.free.analysis import impact_mean, pooled_mean
from rockdec.free.impacts import CROSSING_BAND_SIGMAS, find_crossings, noise_std

__all__ = ["FEWEST_IMPACTS", "FLOOR", "ForcedFit", "GROUPS", "LOAD_GAIN_LIMIT", "MAX_SHIFT", "MIN_ARC_SAMPLES", "OUTLIER_MADS", "READINGS",
           "REST_SAMPLES", "analyse_forced", "arc_covariances", "base_integrals", "base_shift", "fit_arcs", "pool_forced"]

#: How the base may move between its samples, each a reading of the arcs: ``"linear"``
#: (a sampled smooth motion) and ``"held"`` (constant over each sample, a staircase).
READINGS = ("linear", "held")

#: Fewest samples off zero for an arc to be fitted.
MIN_ARC_SAMPLES = 6

#: More samples than this within the noise band inside a flight are a rest: the flight ends.
REST_SAMPLES = 3

#: Impacts whose ``log e`` lies further than this many (normal-scaled) median absolute
#: deviations from the median are set aside (an arc cut short by a rest, a chatter).
OUTLIER_MADS = 5.0

#: Largest lag (samples) of the base behind the angle, or ahead, that :func:`base_shift` seeks.
MAX_SHIFT = 2.0

#: Widest ratio of the fitted load to the declared one (either way) that is read as one: past it
#: the base's units, the block's angle or its ``g`` are wrong, and ``e`` is refused.
LOAD_GAIN_LIMIT = 1.2

#: Runs of arcs the jackknife leaves out one at a time.
GROUPS = 10

#: Fewest impacts for an ``e``.
FEWEST_IMPACTS = 5

#: Half-width floor of the interval in ``log e``: the arcs' fit reads a noise-free record's
#: ``e`` to about 1e-6 (the base's reading between samples), so an interval is never narrower.
FLOOR = 1e-5


@dataclass(frozen=True)
class ForcedFit:
    """What :func:`analyse_forced` found in one record, or :func:`pool_forced` in several:
    ``log_e`` of each impact used and their ``covariance`` from the arcs' fit, ``set_aside``
    (outliers), the fitted ``g`` (rad/s^2), ``load_gain`` (``|k| / g``) and the base's lag
    ``shift`` (samples; both NaN for a pool), ``e``, the standard error ``se`` of ``log e``
    (the jackknife's), its 95 % ``e_interval`` and the impact-to-impact ``spread`` of ``log e``
    (NaN when ``reason`` says why there is none); ``readings``: the fit under each of
    :data:`READINGS` (empty for one of them, and where the arcs were never fitted)."""

    log_e: np.ndarray
    covariance: np.ndarray
    set_aside: int
    g: float
    load_gain: float
    shift: float
    e: float
    se: float
    e_interval: tuple[float, float]
    spread: float
    reason: str | None
    readings: dict[str, ForcedFit] = field(default_factory=dict)

    @classmethod
    def none(cls, reason: str, g: float = math.nan, load_gain: float = math.nan, shift: float = math.nan) -> ForcedFit:
        """No reading, for ``reason``."""
        return cls(np.empty(0), np.empty((0, 0)), 0, g, load_gain, shift, math.nan, math.nan, (math.nan, math.nan), math.nan, reason)

    @property
    def impacts(self) -> int:
        """The impacts ``e`` is read from."""
        return int(self.log_e.size)

    @property
    def reading_gap(self) -> float:
        """``|log e|`` between the readings' ``e`` (the widest), NaN without two that answer."""
        values = [math.log(f.e) for f in self.readings.values() if f.reason is None]
        return max(values) - min(values) if len(values) > 1 else math.nan


def _slopes(a: np.ndarray, dt: float, reading: str) -> np.ndarray:
    """The base's slope over each sample under ``reading`` (one of :data:`READINGS`): the
    base at ``t_j + u`` within sample ``j`` is ``a_j + slope_j u`` (0 past the last sample)."""
    if reading not in READINGS:
        raise ValueError(f"`reading` {reading!r} is not one of {', '.join(READINGS)}")
    slope = np.zeros(a.size)
    if reading == "linear":
        slope[:-1] = np.diff(a) / dt
    return slope


def base_integrals(ratio, dt: float, reading: str = "linear") -> tuple[np.ndarray, np.ndarray]:
    """The base's integral and double integral from the first sample, the base between
    samples as ``reading`` says (one of :data:`READINGS`): ``(V, L)`` at each sample (units of
    ``ratio`` times s and s^2). Over sample ``j`` the base is ``a_j + s_j u`` (``s_j`` the
    slope to the next sample, or 0 held), so ``V`` steps by ``a_j dt + s_j dt^2 / 2`` and ``L``
    by ``V_j dt + a_j dt^2 / 2 + s_j dt^3 / 6``.

    Examples
    --------
    >>> v, l = base_integrals(np.ones(3), 0.5)
    >>> v.tolist(), l.tolist()
    ([0.0, 0.5, 1.0], [0.0, 0.125, 0.5])
    >>> v, l = base_integrals([1.0, 0.0, 0.0], 0.5, reading="held")
    >>> v.tolist(), l.tolist()
    ([0.0, 0.5, 0.5], [0.0, 0.125, 0.375])
    """
    a = np.asarray(ratio, dtype=float)
    s = _slopes(a, dt, reading)[:-1]
    v = np.concatenate([[0.0], np.cumsum(a[:-1] * dt + s * dt * dt / 2.0)])
    step = v[:-1] * dt + a[:-1] * dt * dt / 2.0 + s * dt**3 / 6.0
    return v, np.concatenate([[0.0], np.cumsum(step)])


def _arcs(theta: np.ndarray, band: float):
    """``(lo, hi, side, crossing before, crossing after)`` of every flight between crossings
    (crossings as indices into the crossings found, -1 where a rest or the record's end bounds
    it): the samples from the first beyond ``band`` on its side to the last, both left out
    (chosen by their noise, they would bias the arc's ends), split at a rest (more than
    :data:`REST_SAMPLES` samples within the band), at least :data:`MIN_ARC_SAMPLES` long."""
    c = find_crossings(theta, band)
    edges = np.concatenate([[-0.5], c.position, [theta.size - 0.5]])
    sides = np.concatenate([c.side, [-c.side[-1]]]) if c.side.size else np.array([1 if theta[np.argmax(np.abs(theta))] > 0 else -1])
    out = []
    for k in range(edges.size - 1):
        lo, hi = max(int(np.floor(edges[k])) + 1, 0), min(int(np.floor(edges[k + 1])) + 1, theta.size)
        off = np.flatnonzero(sides[k] * theta[lo:hi] > band) + lo
        runs = np.split(off, np.flatnonzero(np.diff(off) > REST_SAMPLES + 1) + 1) if off.size else []
        for j, run in enumerate(runs):
            if run[-1] - run[0] - 1 >= MIN_ARC_SAMPLES:
                before = k - 1 if j == 0 and k > 0 else -1
                after = k if j == len(runs) - 1 and k < edges.size - 2 else -1
                out.append((int(run[0]) + 1, int(run[-1]), int(sides[k]), before, after))
    return c.position, out


def fit_arcs(theta, ratio, dt: float, arcs, reading: str = "linear") -> tuple[float, float, np.ndarray]:
    """Least-squares ``g``, ``k`` and each arc's ``(c0, c1)`` of the forced flight (module
    docstring) over the ``arcs`` ``(lo, hi, side, ...)``: each arc's ``c0, c1`` projected out
    exactly, ``g`` and ``k`` from what remains (:func:`arc_covariances` gives their errors),
    the base between samples as ``reading`` says (:func:`base_integrals`).

    Examples
    --------
    >>> t = np.arange(40) * 0.01
    >>> r = np.sin(3.0 * t)
    >>> v, l = base_integrals(r, 0.01)
    >>> theta = 0.1 + 0.5 * t - 2.0 * t**2 / 2 + 1.5 * l
    >>> g, k, c = fit_arcs(theta, r, 0.01, [(0, 40, 1)])
    >>> round(g, 9), round(k, 9), c.round(9).tolist()
    (2.0, 1.5, [[0.1, 0.5]])
    """
    theta = np.asarray(theta, dtype=float)
    v, l = base_integrals(ratio, dt, reading)
    ys, zs, bases = [], [], []
    for lo, hi, side, *_ in arcs:
        tau = dt * np.arange(hi - lo)
        x = np.column_stack([np.ones(tau.size), tau])
        z = np.column_stack([-side * tau * tau / 2.0, l[lo:hi] - l[lo] - v[lo] * tau])
        q, _ = np.linalg.qr(x)
        y = theta[lo:hi]
        ys.append(y - q @ (q.T @ y))
        zs.append(z - q @ (q.T @ z))
        bases.append((x, z, y))
    beta = np.linalg.lstsq(np.concatenate(zs), np.concatenate(ys), rcond=None)[0]
    coef = np.array([np.linalg.lstsq(x, y - z @ beta, rcond=None)[0] for x, z, y in bases])
    return float(beta[0]), float(beta[1]), coef


def arc_covariances(theta, ratio, dt: float, arcs, g: float, k: float, coef: np.ndarray, reading: str = "linear") -> np.ndarray:
    """The covariance of each arc's ``(c0, c1)`` given ``g`` and ``k`` (``(arcs, 2, 2)``), the
    residual variance pooled over the arcs (``reading`` as :func:`fit_arcs`).

    Examples
    --------
    >>> t = np.arange(40) * 0.01
    >>> theta = 0.1 + 0.5 * t - t**2 + 1e-3 * np.random.default_rng(0).standard_normal(40)
    >>> g, k, coef = fit_arcs(theta, np.zeros(40), 0.01, [(0, 40, 1)])
    >>> c = arc_covariances(theta, np.zeros(40), 0.01, [(0, 40, 1)], g, k, coef)
    >>> c.shape, bool(0 < c[0, 1, 1] < 1e-3)
    ((1, 2, 2), True)
    """
    v, l = base_integrals(ratio, dt, reading)
    rss, inverses = 0.0, []
    for (lo, hi, side, *_), (c0, c1) in zip(arcs, coef):
        tau = dt * np.arange(hi - lo)
        rss += float(np.sum((theta[lo:hi] - c0 - c1 * tau + side * g * tau * tau / 2.0 - k * (l[lo:hi] - l[lo] - v[lo] * tau)) ** 2))
        x = np.column_stack([np.ones(tau.size), tau])
        inverses.append(np.linalg.inv(x.T @ x))
    n = sum(hi - lo for lo, hi, *_ in arcs)
    return rss / max(n - 2 * len(arcs) - 2, 1) * np.array(inverses)


def _shifted(ratio: np.ndarray, lag: float) -> np.ndarray:
    """``ratio`` read ``lag`` samples later (linear between samples, held past the ends)."""
    i = np.arange(ratio.size, dtype=float)
    return np.interp(i - lag, i, ratio)


def _misfit(theta, ratio, dt, arcs, lag, reading) -> float:
    """The arcs' sum of squared residuals with the base lagged by ``lag`` samples."""
    r = _shifted(ratio, lag)
    g, k, coef = fit_arcs(theta, r, dt, arcs, reading)
    v, l = base_integrals(r, dt, reading)
    total = 0.0
    for (lo, hi, side, *_), (c0, c1) in zip(arcs, coef):
        tau = dt * np.arange(hi - lo)
        total += float(np.sum((theta[lo:hi] - c0 - c1 * tau + side * g * tau * tau / 2.0 - k * (l[lo:hi] - l[lo] - v[lo] * tau)) ** 2))
    return total


def base_shift(theta, ratio, dt: float, arcs, reading: str = "linear") -> float:
    """The lag (samples, within :data:`MAX_SHIFT`) of the base behind the angle that fits the
    ``arcs`` best, the base between samples as ``reading`` says (:func:`base_integrals`): a
    grid of quarter samples, then a bounded search about its best point. A base linear
    between samples read as held lags it by half a sample, and the other way round.

    Examples
    --------
    >>> t = np.arange(60) * 0.01
    >>> r = np.sin(7.0 * t)
    >>> theta = 0.05 - t**2 + 2.0 * base_integrals(np.sin(7.0 * (t - 0.003)), 0.01)[1]
    >>> round(base_shift(theta, r, 0.01, [(0, 60, 1)]), 2)
    0.3
    >>> round(base_shift(theta, r, 0.01, [(0, 60, 1)], reading="held"), 1)
    -0.2
    """
    from scipy import optimize

    theta, ratio = np.asarray(theta, dtype=float), np.asarray(ratio, dtype=float)
    grid = np.arange(-MAX_SHIFT, MAX_SHIFT + 0.125, 0.25)
    best = grid[int(np.argmin([_misfit(theta, ratio, dt, arcs, d, reading) for d in grid]))]
    lo, hi = max(best - 0.25, -MAX_SHIFT), min(best + 0.25, MAX_SHIFT)
    return float(optimize.minimize_scalar(lambda d: _misfit(theta, ratio, dt, arcs, d, reading), bounds=(lo, hi), method="bounded",
                                          options={"xatol": 1e-4}).x)


def _root(arc, coef, g, k, ratio, slope, v, l, dt, guess):
    """Where one fitted arc meets zero near ``guess`` (s), its speed there and the speed's
    gradient in the arc's ``(c0, c1)`` (the zero's time moving with them; Newton's method,
    NaN when it does not settle within two samples of the guess); ``slope`` the base's over
    each sample (:func:`_slopes`)."""
    lo, _, side = arc[:3]
    c0, c1 = coef
    a = ratio
    t = guess
    for _ in range(12):
        j = min(max(int(t // dt), 0), a.size - 2)
        u = t - j * dt
        vt = v[j] + a[j] * u + slope[j] * u * u / 2.0
        lt = l[j] + v[j] * u + a[j] * u * u / 2.0 + slope[j] * u**3 / 6.0
        tau = t - lo * dt
        f = c0 + c1 * tau - side * g * tau * tau / 2.0 + k * (lt - l[lo] - v[lo] * tau)
        speed = c1 - side * g * tau + k * (vt - v[lo])
        if speed == 0.0 or not math.isfinite(speed):
            return math.nan, math.nan, None
        t -= f / speed
    if not abs(t - guess) < 2.0 * dt:
        return math.nan, math.nan, None
    tau = t - lo * dt
    j = min(max(int(t // dt), 0), a.size - 1)
    acceleration = -side * g + k * (a[j] + slope[j] * (t - j * dt))
    return t, speed, np.array([-acceleration / speed, 1.0 - acceleration * tau / speed])


def _screened(log_e: np.ndarray, covariance: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """The impacts within :data:`OUTLIER_MADS` of their median, their covariance, and how
    many were set aside."""
    if log_e.size == 0:
        return log_e, covariance, 0
    spread = stats.median_abs_deviation(log_e, scale="normal")
    keep = np.abs(log_e - np.median(log_e)) <= OUTLIER_MADS * spread if spread > 0 else np.ones(log_e.size, bool)
    return log_e[keep], covariance[np.ix_(keep, keep)], int(log_e.size - keep.sum())


def _mean_log_e(log_e: np.ndarray, covariance: np.ndarray):
    """The impacts within :data:`OUTLIER_MADS` of their median pooled
    (:func:`rockdec.free.analysis.impact_mean`), with what was kept and set aside; ``None``
    for fewer than :data:`FEWEST_IMPACTS`."""
    kept, cov, aside = _screened(log_e, covariance)
    if kept.size < FEWEST_IMPACTS:
        return None, kept, cov, aside
    return impact_mean([kept], [cov]), kept, cov, aside


def _interval(mu: float, se: float, dof: int) -> tuple[float, float]:
    """``exp(mu +- t se)``, Student's ``t`` at ``dof``, the half-width at least :data:`FLOOR`."""
    half = max(float(stats.t.ppf(0.975, dof)) * se, FLOOR)
    return math.exp(mu - half), math.exp(mu + half)


def _jackknife_se(theta, ratio, dt, crossings, arcs, reading) -> tuple[float, int]:
    """The delete-a-group jackknife's standard error of the pooled ``log e`` (module
    docstring) and its degrees of freedom (NaN, 0 with fewer than 3 groups that give one)."""
    edges = np.linspace(0, len(arcs), GROUPS + 1).round().astype(int)
    leave_out = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        rest = arcs[:lo] + arcs[hi:]
        g, k, coef = fit_arcs(theta, ratio, dt, rest, reading)
        pooled = _mean_log_e(*_impacts(theta, ratio, dt, crossings, rest, g, k, coef, reading))[0]
        if pooled is not None:
            leave_out.append(pooled.mu)
    n = len(leave_out)
    if n < 3:
        return math.nan, 0
    values = np.asarray(leave_out)
    return math.sqrt((n - 1) / n * float(np.sum((values - values.mean()) ** 2))), n - 1


def _read(theta, ratio, dt, crossings, arcs, reading) -> ForcedFit:
    """One reading of a record's arcs, the base between samples as ``reading`` says: its own
    lag, fit, impacts and jackknife (:func:`analyse_forced`)."""
    shift = base_shift(theta, ratio, dt, arcs, reading)
    ratio = _shifted(ratio, shift)
    g, k, coef = fit_arcs(theta, ratio, dt, arcs, reading)
    gain = abs(k) / g if g > 0 else math.nan
    if not 1.0 / LOAD_GAIN_LIMIT <= gain <= LOAD_GAIN_LIMIT:
        return ForcedFit.none(f"the arcs read the base's load on the block as {gain:.3g} times what its units and the block's angle say; "
                              "check the base's units and theta_cr (or g_block)", g, gain, shift)
    pooled, kept, cov, aside = _mean_log_e(*_impacts(theta, ratio, dt, crossings, arcs, g, k, coef, reading))
    if pooled is None:
        return ForcedFit(kept, cov, aside, g, gain, shift, math.nan, math.nan, (math.nan, math.nan), math.nan,
                         f"the record gives {kept.size} impacts whose arcs fit either side, fewer than {FEWEST_IMPACTS}")
    se, dof = _jackknife_se(theta, ratio, dt, crossings, arcs, reading)
    if dof == 0:
        return ForcedFit(kept, cov, aside, g, gain, shift, math.nan, math.nan, (math.nan, math.nan), pooled.tau,
                         f"the record's {kept.size} impacts are too few to read the error of their e")
    return ForcedFit(kept, cov, aside, g, gain, shift, math.exp(pooled.mu), se, _interval(pooled.mu, se, dof), pooled.tau, None)


def _enveloped(readings: dict[str, ForcedFit]) -> ForcedFit:
    """The readings of :data:`READINGS` as one: the union of their intervals, ``e`` its
    midpoint in ``log e``, ``se`` the larger of theirs, the rest the first reading's. Unless
    every reading answers there is no ``e`` (the envelope needs them all): the reason is the
    first refused reading's, naming it when another answered."""
    first = readings[READINGS[0]]
    refused = [name for name in READINGS if readings[name].reason is not None]
    if refused:
        fit = readings[refused[0]]
        reason = fit.reason if len(refused) == len(READINGS) else f"with the base read {refused[0]} between samples, {fit.reason}"
        return replace(fit, e=math.nan, se=math.nan, e_interval=(math.nan, math.nan), reason=reason, readings=readings)
    low = min(f.e_interval[0] for f in readings.values())
    high = max(f.e_interval[1] for f in readings.values())
    return replace(first, e=math.sqrt(low * high), se=max(f.se for f in readings.values()), e_interval=(low, high), readings=readings)


def analyse_forced(theta, ratio, dt: float) -> ForcedFit:
    """``e`` of one record from the impacts of its forced stretch (module docstring), read
    with the base linear between samples and held over each, the interval the union of the
    two readings' (:attr:`ForcedFit.readings`).

    Parameters
    ----------
    theta : array_like
        The block's angle (rad), finite, one sample each ``dt``.
    ratio : array_like
        The base acceleration over the uplift level at the same samples
        (:func:`rockdec.free.shake.uplift_ratio`).
    dt : float
        The sampling step (s).

    Returns
    -------
    ForcedFit
        ``e`` the midpoint in ``log e`` of the union of the readings' intervals, that union
        its ``e_interval``, ``se`` the larger of the readings' standard errors; the impacts,
        ``g``, load gain and lag the linear reading's. No ``e`` unless both readings give one.

    Examples
    --------
    >>> from rockdec.physics.base_motion import shake_test
    >>> theta, base = shake_test(0.85, 8_000, 0.005, 3, peak=1.6, g=2.0)
    >>> fit = analyse_forced(theta, base / 2.0, 0.005)
    >>> abs(fit.e - 0.85) < 2e-3, fit.impacts > 20, round(fit.load_gain, 2)
    (True, True, 1.0)
    >>> all(fit.e_interval[0] <= r.e <= fit.e_interval[1] for r in fit.readings.values()), fit.reading_gap < 2e-3
    (True, True)
    """
    theta, ratio = np.asarray(theta, dtype=float), np.asarray(ratio, dtype=float)
    if theta.size < 2 * MIN_ARC_SAMPLES:
        return ForcedFit.none(f"the record holds {theta.size} samples, too few for two flight arcs")
    crossings, arcs = _arcs(theta, CROSSING_BAND_SIGMAS * noise_std(theta))
    if len(arcs) < 2:
        return ForcedFit.none("the record holds fewer than two flight arcs")
    return _enveloped({name: _read(theta, ratio, dt, crossings, arcs, name) for name in READINGS})


def _impacts(theta, ratio, dt, crossings, arcs, g, k, coef, reading) -> tuple[np.ndarray, np.ndarray]:
    """``log e`` of every impact between two fitted arcs that meet zero together, and their
    covariance (each arc's speeds at both ends share its ``(c0, c1)``)."""
    v, l = base_integrals(ratio, dt, reading)
    slope = _slopes(ratio, dt, reading)
    cov = arc_covariances(theta, ratio, dt, arcs, g, k, coef, reading)
    log_e, rows = [], []  # rows: (arc, gradient of log speed) pairs entering each impact, + for out, - for in
    for i, (left, right) in enumerate(zip(arcs[:-1], arcs[1:])):
        if not (left[4] >= 0 and left[4] == right[3] and left[2] == -right[2] and right[0] - left[1] <= 6):
            continue
        guess = dt * crossings[left[4]]
        t_in, speed_in, grad_in = _root(left, coef[i], g, k, ratio, slope, v, l, dt, guess)
        t_out, speed_out, grad_out = _root(right, coef[i + 1], g, k, ratio, slope, v, l, dt, guess)
        if abs(t_in - t_out) < dt and speed_out / speed_in > 0.0:  # NaN fails both
            log_e.append(math.log(speed_out / speed_in))
            rows.append(((i + 1, grad_out / speed_out), (i, -grad_in / speed_in)))
    jac = np.zeros((len(rows), 2 * len(arcs)))
    for r, pairs in enumerate(rows):
        for arc, grad in pairs:
            jac[r, 2 * arc : 2 * arc + 2] += grad
    blocks = np.zeros((2 * len(arcs), 2 * len(arcs)))
    for j, c in enumerate(cov):
        blocks[2 * j : 2 * j + 2, 2 * j : 2 * j + 2] = c
    return np.asarray(log_e), jac @ blocks @ jac.T


def _pool(fits: list[ForcedFit]) -> ForcedFit:
    """One reading's records together (:func:`pool_forced`)."""
    log_e = np.concatenate([f.log_e for f in fits]) if fits else np.empty(0)
    covariance = np.zeros((log_e.size, log_e.size))
    at = 0
    for f in fits:
        covariance[at : at + f.impacts, at : at + f.impacts] = f.covariance
        at += f.impacts
    g = float(np.nanmean([f.g for f in fits])) if any(np.isfinite(f.g) for f in fits) else math.nan
    answered = [f for f in fits if f.reason is None]
    if not answered:
        return ForcedFit(log_e, covariance, sum(f.set_aside for f in fits), g, math.nan, math.nan, math.nan, math.nan, (math.nan, math.nan),
                         math.nan, "no record gives an e: " + "; ".join(f"record {k}: {f.reason}" for k, f in enumerate(fits)))
    mu, se = pooled_mean([math.log(f.e) for f in answered], [f.se for f in answered])
    dof = sum(GROUPS - 1 for _ in answered) if len(answered) > 1 else GROUPS - 1
    spread = float(np.nanmedian([f.spread for f in answered]))
    return ForcedFit(log_e, covariance, sum(f.set_aside for f in fits), g, math.nan, math.nan, math.exp(mu), se, _interval(mu, se, dof),
                     spread, None)


def pool_forced(fits) -> ForcedFit:
    """The records' readings of :func:`analyse_forced` together, one block's ``e``: under
    each of :data:`READINGS`, the records' ``log e`` weighted by their errors, the error
    widened by their scatter beyond it (the Birge ratio), Student's ``t`` at the records'
    jackknife degrees of freedom; the answer the union of the readings' pooled intervals, as
    :func:`analyse_forced`'s (the readings' gap is systematic, the same in every record, and
    does not average down). An answered fit without :attr:`ForcedFit.readings` (made by
    hand) counts as every reading's; fits none of which has readings are pooled as one.

    Examples
    --------
    >>> one = ForcedFit(np.log([0.9, 0.91, 0.89]), 1e-4 * np.eye(3), 0, 2.0, 1.0, 0.0, 0.9, 0.01, (0.88, 0.92), 0.01, None)
    >>> both = pool_forced([one, one])
    >>> round(both.e, 4), both.impacts, round(both.se / one.se, 4)
    (0.9, 6, 0.7071)
    """
    fits = list(fits)
    if not any(f.readings for f in fits):
        return _pool(fits)
    return _enveloped({name: _pool([f.readings.get(name, f) if f.reason is None else f for f in fits]) for name in READINGS})

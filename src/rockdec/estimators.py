"""Estimators of the coefficient of restitution ``e`` from RDD signatures (paper §5).

Inputs
    ``r``: a free-response estimate, ``r[k]`` at lag ``tau = k*dt`` (``k = 0..L``), the even
    part of a two-sided ``D_a`` signature (eq. 19); ``r[0] > 0`` is the trigger level.
    Ideally (eqs. 4, 6) it is the free rocking response from ``(a, 0)``: the parabola
    ``a - g tau^2/2`` down to the first zero crossing ``t1 = sqrt(2a/g)``, the velocity
    multiplied by ``e`` at every crossing, the first minimum ``-e^2 a`` at ``t2 = (1+e) t1``.
    ``d``: a two-sided ``D_v`` signature (eq. 19), ``2L+1`` lags, lag 0 at index ``L``.

Estimators (each returns :class:`Estimate`: a value and, when the value is NaN, why)
    ``e_g``  global logarithmic decrement over all extremes, eqs. 25 and 7;
    ``e_0``  first maximum and first minimum, eq. 26;
    ``e1..e4`` local second-order fits on the first half cycle, eq. 27 (``e4`` corrected);
    ``e_v``  slope ratio through the impact at lag 0 of ``D_v`` (eq. 6).
Then :func:`extrapolate_to_zero` takes an estimator over the window sizes ``da`` of eq. 19
to zero window by weighted least squares (§5).

Kernels take NumPy arrays and never raise on bad data: a NaN comes with a reason.
:func:`estimate_cube` and :func:`extrapolate` are the labelled (xarray/Dask) wrappers; they
keep the values only, and :func:`estimate_all` on one signature gives the reasons.

Units: ``r`` and ``d`` in rad, ``dt`` and the fitted times in s, slopes in rad/s; every
``e`` estimate is dimensionless.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import xarray as xr

from rockdec import __version__
from rockdec import validate as checks

ESTIMATORS = ("e_g", "e_0", "e1", "e2", "e3", "e4", "e_v")
"""Names of the estimators, in the order of the ``estimator`` coordinate."""

LOCAL_ESTIMATORS = ("e1", "e2", "e3", "e4")

MIN_FIT_POINTS = 3
"""Fewest points of any second-order fit: three coefficients need three points (with three
the fit interpolates). Fits that would get fewer give NaN, ``"fewer than 3 points for a fit"``."""

def min_points_per_cycle(e: float, level: float) -> float:
    """Fewest samples per cycle at amplitude ``sigma_Y`` for which ``e1..e4`` can be fitted.

    The start and crossing fits of eq. 27 take ``N_h // 8`` points and need
    :data:`MIN_FIT_POINTS`, so ``N_h >= 8 * MIN_FIT_POINTS``. For the free response from
    ``a = level * sigma_Y`` the first minimum comes at ``(1 + e)/4`` of a period at
    amplitude ``a``, which is ``sqrt(level)`` times the period at ``sigma_Y`` (eq. 5):
    ``N_h = (1 + e)/4 * sqrt(level) * points_per_cycle``. At ``e = 0.95``, level 2: 35.
    """
    return 4.0 * 8 * MIN_FIT_POINTS / ((1.0 + e) * level**0.5)


DEFAULT_FIT_POINTS = 5
"""Points on each side of lag 0 for ``e_v``: about ``N_h/8`` at 75 points per cycle
(``N_h`` about 37), the size of the slope fits of ``e2``."""


class Estimate(NamedTuple):
    """One estimate of ``e`` (dimensionless); ``reason`` is ``""`` unless ``value`` is NaN."""

    value: float
    reason: str = ""


class HalfCycle(NamedTuple):
    """Second-order-fit features of the first half cycle of ``r`` (eq. 27).

    ``c1`` value at ``tau = 0`` (rad); ``t1`` first zero crossing (s); ``v1``, ``v2`` slopes
    just before and just after it, both taken at ``t1`` (rad/s); ``t2``, ``c2`` time (s)
    and value (rad) of the first minimum. All NaN when ``reason`` is not ``""``.
    """

    c1: float
    t1: float
    v1: float
    v2: float
    t2: float
    c2: float
    reason: str = ""


class Extrapolation(NamedTuple):
    """A weighted straight line ``y = value + slope * x`` and the standard error of ``value``."""

    value: float
    stderr: float
    slope: float
    reason: str = ""


class _Parabola(NamedTuple):
    """``y = c0 + c1 (t - tc) + c2 (t - tc)^2``: a least-squares parabola about ``tc``."""

    tc: float
    c0: float
    c1: float
    c2: float

    def value(self, t):
        u = t - self.tc
        return self.c0 + u * (self.c1 + u * self.c2)

    def slope(self, t):
        return self.c1 + 2.0 * self.c2 * (t - self.tc)

    def vertex(self):
        return self.tc - self.c1 / (2.0 * self.c2)

    def roots(self) -> np.ndarray:
        """Real roots in ``t``, computed without cancellation."""
        c0, c1, c2 = self.c0, self.c1, self.c2
        if c2 == 0.0:
            return np.array([self.tc - c0 / c1]) if c1 != 0.0 else np.array([])
        disc = c1 * c1 - 4.0 * c2 * c0
        if disc < 0.0:
            return np.array([])
        q = -0.5 * (c1 + np.copysign(np.sqrt(disc), c1))
        us = [q / c2] + ([c0 / q] if q != 0.0 else [])
        return self.tc + np.array(us)


def _fit2(t: np.ndarray, y: np.ndarray) -> _Parabola:
    """Least-squares parabola through ``(t, y)`` (at least 3 points).

    Solved by the 3x3 normal equations in the scaled variable ``u = (t - tc)/h`` in
    ``[-1, 1]`` (``tc``, ``h`` the centre and half-range of ``t``): well conditioned for
    the few points of each fit, and far cheaper than a general polynomial fit.
    """
    tc = 0.5 * (t[0] + t[-1])
    h = 0.5 * (t[-1] - t[0])
    u = (t - tc) / h
    u2 = u * u
    s = (u.size, u.sum(), u2.sum(), (u2 * u).sum(), (u2 * u2).sum())
    normal = np.array([[s[0], s[1], s[2]], [s[1], s[2], s[3]], [s[2], s[3], s[4]]])
    a0, a1, a2 = np.linalg.solve(normal, np.array([y.sum(), (u * y).sum(), (u2 * y).sum()]))
    return _Parabola(float(tc), float(a0), float(a1 / h), float(a2 / h**2))


def _failed(reason: str) -> Estimate:
    return Estimate(np.nan, reason)


def _estimate(value: float) -> Estimate:
    """An estimate, or NaN with a reason when the arithmetic left the floating-point range."""
    if np.isfinite(value):
        return Estimate(float(value))
    return _failed("not finite: the signature values overflow the arithmetic")


def _failed_half_cycle(reason: str) -> HalfCycle:
    return HalfCycle(*([np.nan] * 6), reason=reason)


def _lobes(r: np.ndarray) -> tuple[list[tuple[int, int, int]], str]:
    """Half cycles of ``r`` and their sampled extremes.

    A lobe is a maximal run of samples of one sign; samples exactly zero belong to no lobe
    and do not split a run of one sign (touching zero is no crossing). Returns
    ``(start, stop, k_extreme)`` per lobe (``stop`` exclusive, ``k_extreme`` the sample of
    largest ``|r|``), and a reason when fewer than two lobes remain. The last lobe is
    dropped when its extreme is the last sample of the record: ``|r|`` is still growing,
    so its extreme lies beyond the lag range.
    """
    if r.ndim != 1 or r.size == 0:
        return [], "empty signature"
    if not np.all(np.isfinite(r)):
        return [], "NaN in signature"
    if r[0] <= 0:
        return [], "r[0] not positive"
    nonzero = np.flatnonzero(r)
    sign = np.sign(r[nonzero])
    runs = np.split(nonzero, np.flatnonzero(sign[1:] != sign[:-1]) + 1)
    if len(runs) < 2:
        return [], "no zero crossing"
    lobes = []
    for run in runs:
        start, stop = int(run[0]), int(run[-1]) + 1
        lobes.append((start, stop, start + int(np.argmax(np.abs(r[start:stop])))))
    if lobes[-1][2] == r.size - 1:
        lobes.pop()
    if len(lobes) < 2:
        return [], "first minimum beyond the lag range"
    return lobes, ""


def e_global(r, lobes=None) -> Estimate:
    """``e_g``: logarithmic decrement from all extremes of ``r`` (eqs. 25, 7).

    The extremes ``r_i`` are the sampled values of largest ``|r|`` between successive zero
    crossings (``r_0`` the largest value before the first crossing, normally ``r[0]``; the
    last half cycle only if its extreme lies inside the lag range). Taking sampled extrema
    per half cycle needs no derivative and no threshold, so it stays robust on noisy
    estimates; it misses a true extreme by at most ``g dt^2/8`` (a sample at most half a
    step off the vertex of a parabola of curvature ``g``, when the half cycle is longer
    than a step). With ``2 ln|r_i| = 2 ln r_0 - i delta``
    (eq. 25), the least-squares slope of ``2 ln|r_i|`` on ``i`` is ``-delta``, and
    ``e = exp(-delta/4)`` (eq. 7). ``lobes``: the result of :func:`_lobes` when the caller
    has it already (:func:`estimate_all`).
    """
    r = np.asarray(r, dtype=float)
    lobes, reason = _lobes(r) if lobes is None else lobes
    if reason:
        return _failed(reason)
    k = np.array([extreme for _, _, extreme in lobes])
    i = np.arange(k.size) - 0.5 * (k.size - 1)  # centred index: the slope needs no intercept
    slope = float(np.dot(i, 2.0 * np.log(np.abs(r[k]))) / np.dot(i, i))
    with np.errstate(over="ignore"):
        return _estimate(np.exp(slope / 4.0))


def e_first_peak(r, lobes=None) -> Estimate:
    """``e_0 = sqrt(|r_1| / r_0)`` (eq. 26): the first two sampled extremes of ``r``.

    ``r_0`` is the maximum and ``r_1`` the first minimum, located as in :func:`e_global`;
    for a decaying response they are the maximum and minimum of the whole estimate.
    """
    r = np.asarray(r, dtype=float)
    lobes, reason = _lobes(r) if lobes is None else lobes
    if reason:
        return _failed(reason)
    r0, r1 = r[lobes[0][2]], r[lobes[1][2]]
    with np.errstate(over="ignore"):
        return _estimate(np.sqrt(abs(r1) / r0))


def half_cycle(r, dt: float, lobes=None) -> HalfCycle:
    """Fit the first half cycle of ``r`` with second-order polynomials (eq. 27).

    ``N_h = m + 1`` is the number of samples from ``tau = 0`` to the sampled first minimum
    ``m`` (see :func:`e_global`). Fits, each least squares of degree 2
    (:func:`_fit2`) in ``tau = k*dt``:

    - start: the first ``N_h // 8`` samples; ``c1`` = the fit at ``tau = 0``;
    - minimum: ``N_h // 4`` samples centred on ``m``; ``t2``, ``c2`` = its vertex;
    - before: the last ``N_h // 8`` samples before the first crossing; ``t1`` = its root
      nearest the crossing (between the last positive and the first negative sample),
      ``v1`` = its slope at ``t1``;
    - after: the first ``N_h // 8`` samples after the crossing; ``v2`` = its slope at ``t1``.

    Every window is clipped to the half cycle it describes, so no fit straddles a zero
    crossing (across one the response is no single parabola), and gets at least
    :data:`MIN_FIT_POINTS` points, or the result is NaN with a reason. For the ideal
    response (eqs. 4, 6) every window holds samples of one parabola and the features are
    exact to rounding.
    """
    checks.positive(dt, "dt", "give the sampling interval in s, > 0")
    r = np.asarray(r, dtype=float)
    lobes, reason = _lobes(r) if lobes is None else lobes
    if reason:
        return _failed_half_cycle(reason)
    (_, end0, _), (start1, end1, m) = lobes[0], lobes[1]
    n_h = m + 1
    n8 = max(MIN_FIT_POINTS, n_h // 8)
    n4 = max(MIN_FIT_POINTS, n_h // 4)
    windows = {
        "start": (0, min(n8, end0)),
        "before": (max(0, end0 - n8), end0),
        "after": (start1, min(start1 + n8, end1)),
        "minimum": (max(start1, m - (n4 - 1) // 2), min(end1, m + n4 // 2 + 1)),
    }
    if any(stop - start < MIN_FIT_POINTS for start, stop in windows.values()):
        return _failed_half_cycle(f"fewer than {MIN_FIT_POINTS} points for a fit")
    tau = dt * np.arange(r.size)
    fit = {name: _fit2(tau[a:b], r[a:b]) for name, (a, b) in windows.items()}

    roots = fit["before"].roots()
    if roots.size == 0:
        return _failed_half_cycle("before-crossing fit has no real root")
    crossing = 0.5 * (tau[end0 - 1] + tau[start1])
    t1 = roots[np.argmin(np.abs(roots - crossing))]
    v1 = fit["before"].slope(t1)
    if v1 == 0:
        return _failed_half_cycle("before-crossing fit touches zero without crossing")
    if not fit["minimum"].c2 > 0:
        return _failed_half_cycle("minimum fit has no minimum")
    t2 = fit["minimum"].vertex()
    c1 = fit["start"].value(0.0)
    if not c1 > 0:
        return _failed_half_cycle("fitted c1 not positive")
    if not 0 < t1 < t2:
        return _failed_half_cycle("fitted crossing t1 not between 0 and t2")
    return HalfCycle(
        c1=float(c1),
        t1=float(t1),
        v1=float(v1),
        v2=float(fit["after"].slope(t1)),
        t2=float(t2),
        c2=float(fit["minimum"].value(t2)),
    )


def local_measures(r, dt: float, lobes=None) -> dict[str, Estimate]:
    """``e1..e4`` of eq. 27 from one set of half-cycle fits (:func:`half_cycle`).

    ``e1 = sqrt(|c2|/c1)``, ``e2 = v2/v1``, ``e3 = (|c2|/c1) t1/(t2 - t1)``,
    ``e4 = (t2 - t1)/t1``.

    Derivation for the ideal response (eqs. 4, 6): ``c1 = a`` and ``r = a - g tau^2/2``
    reaches zero at ``t1 = sqrt(2a/g)`` with velocity ``v1 = -g t1``. The impact leaves
    ``v2 = e v1``; gravity (now of the other sign) brings that velocity to zero after a
    time ``e t1``, so ``t2 = (1 + e) t1`` and ``c2 = -e^2 g t1^2/2 = -e^2 a``. Hence
    ``|c2|/c1 = e^2``, ``v2/v1 = e``, ``(t2 - t1)/t1 = e`` and ``e3 = e^2 / e = e``.
    The paper prints ``e4 = t1/(t2 - t1)``, which is ``1/e`` for this response; ``e4``
    here is its reciprocal.
    """
    h = half_cycle(r, dt, lobes)
    if h.reason:
        return {name: _failed(h.reason) for name in LOCAL_ESTIMATORS}
    with np.errstate(all="ignore"):
        ratio = np.float64(abs(h.c2)) / h.c1
        return {
            "e1": _estimate(np.sqrt(ratio)),
            "e2": _estimate(np.float64(h.v2) / h.v1),
            "e3": _estimate(ratio * h.t1 / (h.t2 - h.t1)),
            "e4": _estimate(np.float64(h.t2 - h.t1) / h.t1),
        }


def e_impact_slope(d, dt: float, fit_points: int = DEFAULT_FIT_POINTS) -> Estimate:
    """``e_v``: ratio of the slopes of a ``D_v`` signature after and before lag 0 (eq. 6).

    Lag 0 (index ``L`` of the ``2L+1`` lags) is a zero crossing where the velocity is
    multiplied by ``e``. Each side is fitted by a second-order polynomial (the free flight
    of eq. 4 is a parabola, so the fit has no curvature bias) on the ``fit_points`` lags
    strictly on that side, ``tau = -fit_points*dt .. -dt`` and ``dt .. fit_points*dt``;
    lag 0 belongs to neither side, because the slope is discontinuous there and where the
    sampled trigger sits relative to the true crossing is uncertain. Both fits are
    differentiated at ``tau = 0``: ``e_v = slope_after / slope_before``.

    ``fit_points`` below :data:`MIN_FIT_POINTS` is a caller error (``ValueError``).
    """
    if not (checks.is_whole(fit_points) and fit_points >= MIN_FIT_POINTS):
        raise checks.InputError(f"fit_points={fit_points}: need a whole number of at least {MIN_FIT_POINTS} points")
    checks.positive(dt, "dt", "give the sampling interval in s, > 0")
    d = np.asarray(d, dtype=float)
    if d.ndim != 1 or d.size % 2 == 0:
        return _failed("D_v signature length not odd: no lag 0")
    if not np.all(np.isfinite(d)):
        return _failed("NaN in signature")
    lag0 = d.size // 2
    if lag0 < fit_points:
        return _failed(f"fewer than fit_points={fit_points} lags on a side")
    tau = dt * np.arange(1, fit_points + 1)
    before = _fit2(-tau[::-1], d[lag0 - fit_points : lag0]).slope(0.0)
    after = _fit2(tau, d[lag0 + 1 : lag0 + 1 + fit_points]).slope(0.0)
    if before == 0:
        return _failed("zero slope before the impact")
    with np.errstate(all="ignore"):
        return _estimate(after / before)


def estimate_all(r, d, dt: float, fit_points: int = DEFAULT_FIT_POINTS) -> dict[str, Estimate]:
    """Every estimator of :data:`ESTIMATORS` on one free response ``r`` and one ``D_v``
    signature ``d`` (``None`` when there is none: ``e_v`` is then NaN)."""
    r = np.asarray(r, dtype=float)
    lobes = _lobes(r)
    e_v = _failed("no D_v signature") if d is None else e_impact_slope(d, dt, fit_points)
    return {"e_g": e_global(r, lobes), "e_0": e_first_peak(r, lobes), **local_measures(r, dt, lobes), "e_v": e_v}


def extrapolate_to_zero(x, y, weights=None) -> Extrapolation:
    """Weighted least-squares line ``y = value + slope * x``; ``value`` is ``y`` at ``x = 0``.

    Paper §5: ``x`` is the window size, ``y`` an estimate of ``e`` at that window; the
    weights stand for reciprocal variances, about proportional to the trigger count, which
    is about proportional to the window size: ``weights=None`` means ``weights = x``; pass
    the trigger counts to use them directly. Only relative weights matter.

    Points with a NaN in ``x``, ``y`` or the weight, or a weight of zero, are left out (a
    point of weight zero has no influence). With ``W = sum w``, weighted means
    ``xm = sum w x / W``, ``ym = sum w y / W`` and ``Sxx = sum w (x - xm)^2``:
    ``slope = sum w (x - xm)(y - ym) / Sxx``, ``value = ym - slope * xm``. The standard
    error takes ``Var(y_i) = s^2 / w_i`` with ``s^2`` estimated from the weighted residuals,
    ``s^2 = sum w (y - value - slope x)^2 / (n - 2)``:
    ``stderr = sqrt(s^2 (1/W + xm^2/Sxx))``. With exactly two points there is no residual
    degree of freedom and ``stderr`` is NaN (``value`` and ``slope`` are exact).
    Fewer than two usable points, or all at one ``x``: everything NaN, with a reason.
    Negative weights are a caller error (``ValueError``).
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    w = x if weights is None else np.asarray(weights, dtype=float)
    if np.any(w < 0):
        raise ValueError("weights must be non-negative")
    use = np.isfinite(x) & np.isfinite(y) & np.isfinite(w) & (w > 0)
    x, y, w = x[use], y[use], w[use]
    if x.size < 2:
        return Extrapolation(np.nan, np.nan, np.nan, "fewer than 2 usable points")
    total = w.sum()
    xm = np.dot(w, x) / total
    ym = np.dot(w, y) / total
    sxx = np.dot(w, (x - xm) ** 2)
    if sxx == 0:
        return Extrapolation(np.nan, np.nan, np.nan, "all points at one window size")
    slope = np.dot(w, (x - xm) * (y - ym)) / sxx
    value = ym - slope * xm
    if x.size == 2:
        return Extrapolation(float(value), np.nan, float(slope))
    s2 = np.dot(w, (y - value - slope * x) ** 2) / (x.size - 2)
    stderr = np.sqrt(s2 * (1.0 / total + xm**2 / sxx))
    return Extrapolation(float(value), float(stderr), float(slope))


def _estimate_values(r, d, dt, fit_points) -> np.ndarray:
    return np.array([est.value for est in estimate_all(r, d, dt, fit_points).values()])


def estimate_cube(
    free_response: xr.DataArray,
    dv_signature: xr.DataArray | None,
    dt: float,
    fit_points: int = DEFAULT_FIT_POINTS,
) -> xr.Dataset:
    """:func:`estimate_all` over every free response of a labelled cube.

    ``free_response`` has core dimension ``lag_pos`` (``tau >= 0``), ``dv_signature`` core
    dimension ``lag`` (two-sided) or is ``None``; their other dimensions broadcast by
    name. Dask arrays chunked along the other dimensions stay lazy. Returns ``e_hat``
    with dimension ``estimator`` (:data:`ESTIMATORS`) first; NaN where an estimator
    failed (:func:`estimate_all` on that signature says why).
    """
    common = dict(
        vectorize=True,
        dask="parallelized",
        output_core_dims=[["estimator"]],
        output_dtypes=[float],
        dask_gufunc_kwargs={"output_sizes": {"estimator": len(ESTIMATORS)}},
    )
    if dv_signature is None:
        e_hat = xr.apply_ufunc(
            lambda r: _estimate_values(r, None, dt, fit_points),
            free_response,
            input_core_dims=[["lag_pos"]],
            **common,
        )
    else:
        e_hat = xr.apply_ufunc(
            lambda r, d: _estimate_values(r, d, dt, fit_points),
            free_response,
            dv_signature,
            input_core_dims=[["lag_pos"], ["lag"]],
            **common,
        )
    e_hat = e_hat.transpose("estimator", ...).assign_coords(estimator=list(ESTIMATORS))
    e_hat.attrs = {
        "units": "1",
        "long_name": "estimated coefficient of restitution",
        "fit_points": fit_points,
    }
    e_hat["estimator"].attrs["long_name"] = "estimator of e (paper eqs. 25-27, e_v from D_v)"
    return xr.Dataset({"e_hat": e_hat}, attrs={"history": f"rockdec {__version__}: estimate_cube"})


def _extrapolation_values(x, y, w) -> tuple[float, float, float]:
    value, stderr, slope, _ = extrapolate_to_zero(x, y, w)
    return value, stderr, slope


def extrapolate(e_hat: xr.DataArray, weights: xr.DataArray | None = None) -> xr.Dataset:
    """:func:`extrapolate_to_zero` along ``window`` for every other index of ``e_hat``.

    ``x`` is the ``window`` coordinate; ``weights`` default to it (paper §5), or pass the
    trigger counts (dimension ``window``, broadcast by name). Returns ``e_hat0`` (value at
    zero window), ``e_hat0_stderr`` and ``slope``; reasons are dropped (NaN stays NaN).
    """
    window = e_hat["window"]
    w = window if weights is None else weights
    value, stderr, slope = xr.apply_ufunc(
        _extrapolation_values,
        window,
        e_hat,
        w,
        input_core_dims=[["window"]] * 3,
        output_core_dims=[[], [], []],
        vectorize=True,
        dask="parallelized",
        output_dtypes=[float] * 3,
    )
    window_units = window.attrs.get("units", "1")
    return xr.Dataset(
        {
            "e_hat0": value.assign_attrs(
                units="1", long_name="estimated coefficient of restitution at zero window"
            ),
            "e_hat0_stderr": stderr.assign_attrs(
                units="1", long_name="standard error of e_hat0 (weighted least squares)"
            ),
            "slope": slope.assign_attrs(
                units="1" if window_units == "1" else f"1/({window_units})",
                long_name="slope of the estimate in the window size",
            ),
        },
        attrs={"history": f"rockdec {__version__}: extrapolate"},
    )

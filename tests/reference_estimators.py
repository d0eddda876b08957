"""The per-signature NumPy implementation of :func:`rockdec.rdd.estimators.estimate_all`, and
single-estimator entry points of its numba kernels.

Same conventions, reasons and input checks as the numba kernels, written with
``np.linalg.solve`` for each parabola fit and NumPy runs for the lobes; slower by about two
orders of magnitude. It checks the kernels (``tests/rdd/test_estimators.py``) and times them
(``benchmarks/bench_estimators.py``).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from rockdec import validate as checks
from rockdec.rdd.estimators import (
    _C1_NOT_POSITIVE,
    _EVEN_LENGTH,
    _FEW_LAGS,
    _FEW_POINTS,
    _NAN,
    _NO_DV,
    _NO_MINIMUM,
    _NO_ROOT,
    _NOT_FINITE,
    _T1_OUTSIDE,
    _TOUCHES_ZERO,
    _ZERO_SLOPE,
    DEFAULT_FIT_POINTS,
    FLAT_ULPS,
    LOCAL_ESTIMATORS,
    MIN_FIT_POINTS,
    Estimate,
    HalfCycle,
    _as_estimate,
    _as_row,
    _check_options,
    _e_first_peak,
    _e_global,
    _e_impact_slope,
    _half_cycle,
    _lobes_of,
    _local_measures,
    _reason,
)
from rockdec.rdd.registry import ESTIMATORS


# --------------------------------------------------------------------------- single estimators


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
    ``e = exp(-delta/4)`` (eq. 7). ``lobes``: the result of :func:`rockdec.rdd.estimators._lobes` on ``r`` when
    the caller has it already.
    """
    r = _as_row(r)
    return _as_estimate(*_e_global(r, *_lobes_of(r, lobes)))


def e_first_peak(r, lobes=None) -> Estimate:
    """``e_0 = sqrt(|r_1| / r_0)`` (eq. 26): the first two sampled extremes of ``r``.

    ``r_0`` is the maximum and ``r_1`` the first minimum, located as in :func:`rockdec.rdd.estimators._e_global`;
    for a decaying response they are the maximum and minimum of the whole estimate.
    """
    r = _as_row(r)
    return _as_estimate(*_e_first_peak(r, *_lobes_of(r, lobes)))


def local_measures(r, dt: float, lobes=None) -> dict[str, Estimate]:
    """``e1..e4`` of eq. 27 from one set of half-cycle fits (:func:`rockdec.rdd.estimators.half_cycle`).

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
    dt = checks.positive(dt, "dt", "give the sampling interval in s, > 0")
    r = _as_row(r)
    values, codes = np.empty(len(LOCAL_ESTIMATORS)), np.empty(len(LOCAL_ESTIMATORS), np.int64)
    _local_measures(*_half_cycle(r, dt, *_lobes_of(r, lobes)), values, codes, np.arange(len(LOCAL_ESTIMATORS)))
    return {name: _as_estimate(v, c) for name, v, c in zip(LOCAL_ESTIMATORS, values, codes)}


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
    dt, fit_points = _check_options(dt, fit_points, with_dv=True)
    return _as_estimate(*_e_impact_slope(_as_row(d), dt, fit_points), fit_points)


# --------------------------------------------------------------------------- reference


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
        c0, c1, c2 = self.c0, self.c1, self.c2
        if c2 == 0.0:
            return np.array([self.tc - c0 / c1]) if c1 != 0.0 else np.array([])
        disc = c1 * c1 - 4.0 * c2 * c0
        if disc < 0.0:
            return np.array([])
        q = -0.5 * (c1 + np.copysign(np.sqrt(disc), c1))
        us = [q / c2] + ([c0 / q] if q != 0.0 else [])
        return self.tc + np.array(us)


def reference_fit2(t: np.ndarray, y: np.ndarray) -> _Parabola:
    tc = 0.5 * (t[0] + t[-1])
    h = 0.5 * (t[-1] - t[0])
    u = (t - tc) / h
    u2 = u * u
    s = (u.size, u.sum(), u2.sum(), (u2 * u).sum(), (u2 * u2).sum())
    normal = np.array([[s[0], s[1], s[2]], [s[1], s[2], s[3]], [s[2], s[3], s[4]]])
    a0, a1, a2 = np.linalg.solve(normal, np.array([y.sum(), (u * y).sum(), (u2 * y).sum()]))
    return _Parabola(float(tc), float(a0), float(a1 / h), float(a2 / h**2))


def reference_lobes(r: np.ndarray) -> tuple[list[tuple[int, int, int]], str]:
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


def _reference_estimate(value: float) -> Estimate:
    if np.isfinite(value):
        return Estimate(float(value))
    return Estimate(np.nan, _reason(_NOT_FINITE))


def reference_half_cycle(r: np.ndarray, dt: float, lobes) -> HalfCycle:
    def failed(code):
        return HalfCycle(*([np.nan] * 6), reason=_reason(code))

    lobes, reason = lobes
    if reason:
        return HalfCycle(*([np.nan] * 6), reason=reason)
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
        return failed(_FEW_POINTS)
    tau = dt * np.arange(r.size)
    fit = {name: reference_fit2(tau[a:b], r[a:b]) for name, (a, b) in windows.items()}
    roots = fit["before"].roots()
    if roots.size == 0:
        return failed(_NO_ROOT)
    crossing = 0.5 * (tau[end0 - 1] + tau[start1])
    t1 = roots[np.argmin(np.abs(roots - crossing))]
    v1 = fit["before"].slope(t1)
    if v1 == 0:
        return failed(_TOUCHES_ZERO)
    if not fit["minimum"].c2 > 0:
        return failed(_NO_MINIMUM)
    t2 = fit["minimum"].vertex()
    c1 = fit["start"].value(0.0)
    if not c1 > 0:
        return failed(_C1_NOT_POSITIVE)
    if not 0 < t1 < t2:
        return failed(_T1_OUTSIDE)
    return HalfCycle(
        c1=float(c1),
        t1=float(t1),
        v1=float(v1),
        v2=float(fit["after"].slope(t1)),
        t2=float(t2),
        c2=float(fit["minimum"].value(t2)),
    )


def _reference_e_impact_slope(d, dt: float, fit_points: int) -> Estimate:
    d = np.asarray(d, dtype=float)
    if d.ndim != 1 or d.size % 2 == 0:
        return Estimate(np.nan, _reason(_EVEN_LENGTH))
    if not np.all(np.isfinite(d)):
        return Estimate(np.nan, _reason(_NAN))
    lag0 = d.size // 2
    if lag0 < fit_points:
        return Estimate(np.nan, _reason(_FEW_LAGS, fit_points))
    tau = dt * np.arange(1, fit_points + 1)
    before = reference_fit2(-tau[::-1], d[lag0 - fit_points : lag0]).slope(0.0)
    after = reference_fit2(tau, d[lag0 + 1 : lag0 + 1 + fit_points]).slope(0.0)
    if abs(before) * tau[-1] <= FLAT_ULPS * np.finfo(float).eps * np.abs(d[lag0 - fit_points : lag0]).max():
        return Estimate(np.nan, _reason(_ZERO_SLOPE))
    with np.errstate(all="ignore"):
        return _reference_estimate(after / before)


def reference_estimate_all(r, d, dt: float, fit_points: int = DEFAULT_FIT_POINTS) -> dict[str, Estimate]:
    """:func:`rockdec.rdd.estimators.estimate_all`, one signature at a time in NumPy (module docstring)."""
    dt, fit_points = _check_options(dt, fit_points, with_dv=d is not None)
    r = np.asarray(r, dtype=float)
    lobes = reference_lobes(r)
    (ks, reason) = lobes
    if reason:
        e_g = e_0 = Estimate(np.nan, reason)
    else:
        k = np.array([extreme for _, _, extreme in ks])
        i = np.arange(k.size) - 0.5 * (k.size - 1)
        slope = float(np.dot(i, 2.0 * np.log(np.abs(r[k]))) / np.dot(i, i))
        with np.errstate(over="ignore"):
            e_g = _reference_estimate(np.exp(slope / 4.0))
            e_0 = _reference_estimate(np.sqrt(abs(r[k[1]]) / r[k[0]]))
    h = reference_half_cycle(r, dt, lobes)
    if h.reason:
        local = {name: Estimate(np.nan, h.reason) for name in ("e1", "e2", "e3", "e4")}
    else:
        with np.errstate(all="ignore"):
            ratio = np.float64(abs(h.c2)) / h.c1
            local = {
                "e1": _reference_estimate(np.sqrt(ratio)),
                "e2": _reference_estimate(np.float64(h.v2) / h.v1),
                "e3": _reference_estimate(ratio * h.t1 / (h.t2 - h.t1)),
                "e4": _reference_estimate(np.float64(h.t2 - h.t1) / h.t1),
            }
    e_v = Estimate(np.nan, _reason(_NO_DV)) if d is None else _reference_e_impact_slope(d, dt, fit_points)
    out = {"e_g": e_g, "e_0": e_0, **local, "e_v": e_v}
    return {name: out[name] for name in ESTIMATORS}

"""Flight arcs with a continuous loss: ``theta'' = -g sign(theta) - c theta'`` between impacts.

A block that loses energy in flight (air, a soft interface that drags) flies arcs that are no
longer symmetric: it leaves an impact at ``v = g T B(cT)`` and lands at ``w = g T B(-cT)``
after a flight of ``T`` s, with ``B(y) = (y/(1 - exp(-y)) - 1)/y`` (``B(0) = 1/2``: the
parabola of eq. 4), so ``w/v`` falls below 1 as ``cT`` grows. The fall from rest reaches the
first impact at ``g T0 phi(cT0)``, ``phi(x) = (1 - exp(-x))/x``. Each height is evaluated in
a form without cancellation as ``c -> 0`` (power series below :data:`SERIES_BELOW`), so
``c = 0`` gives the simplified model's arcs to rounding.

:func:`loss_score` tests ``c`` from the fit without it (the score test), :func:`fit_sequence`
fits a release with ``g`` and ``c`` (the simplified model's fit of :mod:`rockdec.free.arcs` plus
one parameter) and :func:`log_ratios` reads the impacts' ``log e`` (``log v_k - log w_(k-1)``)
with their covariance. Explanation: docs/explanation/free-rocking.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import optimize

from rockdec.free import arcs

__all__ = [
    "DampedFit", "SERIES_BELOW", "fall_height", "fit_sequence", "flight_height", "impact_speeds",
    "log_ratios", "loss_score", "speeds",
]

#: Below this ``|c T|`` the heights and speeds are read from their power series in ``c``
#: (truncation below 1e-17 of the height), above it from the exponentials (rounding below
#: about ``1e-14`` of the height).
SERIES_BELOW = 1e-2


def _phi(x: float) -> float:
    """``phi(x) = (1 - exp(-x))/x`` (``phi(0) = 1``): the fall from rest lands at ``g T0 phi(c T0)``."""
    if abs(x) < SERIES_BELOW:
        return 1.0 - x / 2.0 + x**2 / 6.0 - x**3 / 24.0 + x**4 / 120.0
    return float(-np.expm1(-x) / x)


def _b(y):
    """``B(y) = (y/(1 - exp(-y)) - 1)/y`` (``B(0) = 1/2``), the speed at an end of a flight over ``g T``."""
    y = np.asarray(y, dtype=float)
    small = np.abs(y) < SERIES_BELOW
    safe = np.where(small, 1.0, y)
    direct = (safe / -np.expm1(-safe) - 1.0) / safe
    series = 0.5 + y / 12.0 - y**3 / 720.0 + y**5 / 30240.0
    return np.where(small, series, direct)


def speeds(T, g: float, c: float):
    """Speeds (rad/s) leaving and landing of a flight of ``T`` s: ``(g T B(cT), g T B(-cT))``.

    Examples
    --------
    >>> [float(v) for v in speeds(0.4, 2.0, 0.0)]
    [0.4, 0.4]
    """
    T = np.asarray(T, dtype=float)
    return g * T * _b(c * T), g * T * _b(-c * T)


def flight_height(tau, T, g: float, c: float):
    """Height (rad) at ``tau`` s into a flight of ``T`` s that starts and ends at zero:
    ``(g/c) (T (1 - exp(-c tau))/(1 - exp(-c T)) - tau)``, which is ``g tau (T - tau)/2`` at ``c = 0``.

    Examples
    --------
    >>> round(float(flight_height(0.2, 0.4, 2.0, 0.0)), 12)
    0.04
    """
    tau, T = np.broadcast_arrays(np.asarray(tau, dtype=float), np.asarray(T, dtype=float))
    x = c * T
    small = np.abs(x) < SERIES_BELOW
    # h = g tau (D/c) expm1(D)/D with D = L(c tau) - L(c T), L(x) = log((1 - exp(-x))/x)
    # = -x/2 + x^2/24 - x^4/2880 + x^6/181440 - ...
    series = (T - tau) / 2.0 - c * (T**2 - tau**2) / 24.0 + c**3 * (T**4 - tau**4) / 2880.0 - c**5 * (T**6 - tau**6) / 181440.0
    c_safe = c if c != 0.0 else 1.0

    def log_phi(z):
        z_safe = np.where(z == 0.0, 1.0, z)
        return np.where(z == 0.0, 0.0, np.log(-np.expm1(-z_safe) / z_safe))

    direct = (log_phi(c_safe * tau) - log_phi(c_safe * T)) / c_safe
    ratio = np.where(small, series, direct)  # D / c
    d = c * ratio
    d_safe = np.where(d == 0.0, 1.0, d)
    grow = np.where(d == 0.0, 1.0, np.expm1(d_safe) / d_safe)
    return g * tau * ratio * grow


def fall_height(s, T0, g: float, c: float):
    """Height (rad) ``s`` s before the first impact of a fall from rest that lasts ``T0`` s:
    ``g integral_{T0-s}^{T0} sigma phi(c sigma) d sigma``, ``g (T0^2 - (T0 - s)^2)/2`` at ``c = 0``.

    Examples
    --------
    >>> float(fall_height(1.0, 1.0, 2.0, 0.0))
    1.0
    """
    s, T0 = np.broadcast_arrays(np.asarray(s, dtype=float), np.asarray(T0, dtype=float))
    tau = T0 - s
    x = c * T0
    small = np.abs(x) < SERIES_BELOW
    series = (T0**2 - tau**2) / 2.0 - c * (T0**3 - tau**3) / 6.0 + c**2 * (T0**4 - tau**4) / 24.0 - c**3 * (T0**5 - tau**5) / 120.0 \
        + c**4 * (T0**6 - tau**6) / 720.0 - c**5 * (T0**7 - tau**7) / 5040.0
    c_safe = c if c != 0.0 else 1.0
    # exp(-c T0) expm1(c s) written as exp(c (s - T0)) - exp(-c T0): s <= T0, so a large loss
    # (c T0 past ~700) underflows to 0 instead of overflowing to inf * 0.
    direct = (c_safe * s - (np.exp(c_safe * (s - T0)) - np.exp(-c_safe * T0))) / c_safe**2
    return g * np.where(small, series, direct)


@dataclass(frozen=True)
class DampedFit:
    """The fit of one release with a loss in flight: ``times`` (release, then impacts, s),
    ``g`` (rad/s^2), ``c`` (1/s), ``covariance`` of ``(*times, g, c)``, ``residual_std``
    (rad), ``rss`` (the residuals' sum of squares, rad^2), ``n_samples`` and ``side``."""

    times: np.ndarray
    g: float
    c: float
    covariance: np.ndarray
    residual_std: float
    rss: float
    n_samples: int
    side: int


def _model(t, times, g, c, side):
    """The angle at ``t`` of a release held until ``times[0]``, falling to ``times[1]``, then
    flying from impact to impact (heights of :func:`fall_height` and :func:`flight_height`)."""
    n = times.size - 1
    j = np.minimum(np.searchsorted(times, t, side="right"), n)  # 0: held, 1: fall, k >= 2: flight k - 1
    arc = np.maximum(j - 1, 0)
    sign = side * np.where(arc % 2 == 0, 1.0, -1.0)
    fall = fall_height(np.clip(times[1] - t, 0.0, times[1] - times[0]), times[1] - times[0], g, c)
    lo = np.clip(j - 1, 1, n - 1) if n >= 2 else np.ones_like(j)
    start = times[np.minimum(lo, n)]
    length = times[np.minimum(lo + 1, n)] - start
    flight = flight_height(t - start, length, g, c) if n >= 2 else np.zeros_like(t)
    return sign * np.where(j <= 1, fall, flight)


def _sparsity(t, times):
    """Which parameters ``(*times, g, c)`` each sample's angle depends on: the two ends of its
    arc (the release and the first impact for the held block and the fall), ``g`` and ``c``."""
    from scipy import sparse

    n = times.size - 1
    j = np.minimum(np.searchsorted(times, t, side="right"), n)
    lo = np.where(j <= 1, 0, j - 1)
    hi = np.where(j <= 1, 1, j)
    rows = np.repeat(np.arange(t.size), 4)
    cols = np.column_stack([lo, hi, np.full(t.size, n + 1), np.full(t.size, n + 2)]).ravel()
    return sparse.coo_matrix((np.ones(rows.size), (rows, cols)), shape=(t.size, n + 3)).tocsr()


def fit_sequence(t, y, start: arcs.SequenceFit, floor: float = 0.0, c0: float = 0.0) -> DampedFit:
    """Least-squares fit of one release with ``g`` and ``c``, started from the simplified
    model's fit ``start`` (:func:`rockdec.free.arcs.fit_sequence`) at ``c = c0`` (1/s; the
    score test's :func:`loss_score` is close to the optimum).

    Parameters
    ----------
    t, y : numpy.ndarray
        Sample times (s) and angles (rad) that ``start`` was fitted to.
    start : rockdec.free.arcs.SequenceFit
        The fit without loss in flight (``model="simplified"``).
    floor : float
        Smallest standard deviation (rad) the samples' scatter is taken to have.
    c0 : float
        First guess of ``c`` (1/s); a guess that is not finite (a release whose score
        :func:`loss_score` could not read) starts at 0.

    Returns
    -------
    DampedFit
        Its covariance is the scatter about the fit (at least ``floor``) times the inverse of
        the Gauss-Newton matrix of a central-difference Jacobian.

    Examples
    --------
    >>> tt = np.linspace(0.0, 1.5, 61)
    >>> first = arcs.fit_sequence(tt, np.where(tt < 0.5, 0.25 - tt**2, -(tt - 0.5) * (1.5 - tt)), side=1,
    ...                           times0=[0.0, 0.5, 1.5], q0=2.0, model="simplified", theta_cr=None)
    >>> fit = fit_sequence(tt, np.where(tt < 0.5, 0.25 - tt**2, -(tt - 0.5) * (1.5 - tt)), first)
    >>> round(fit.g, 6), round(abs(fit.c), 6)
    (2.0, 0.0)
    """
    t, y = np.asarray(t, dtype=float), np.asarray(y, dtype=float)
    t_ref, t_unit, y_unit = t[0], t[1] - t[0], float(np.max(np.abs(y)))
    g_unit = y_unit / t_unit**2
    ts, ys = (t - t_ref) / t_unit, y / y_unit
    c0 = c0 if math.isfinite(c0) else 0.0
    x0 = np.concatenate([(start.times - t_ref) / t_unit, [start.q / g_unit, c0 * t_unit]])

    def residual(x):
        return _model(ts, x[:-2], x[-2], x[-1], start.side) - ys

    p = x0.size
    result = optimize.least_squares(residual, x0, jac="3-point", method="trf", jac_sparsity=_sparsity(ts, x0[:-2]), x_scale="jac",
                                    ftol=arcs.FIT_TOLERANCE, xtol=arcs.FIT_TOLERANCE, gtol=arcs.FIT_TOLERANCE, max_nfev=200 * p)
    jac = result.jac.toarray() if hasattr(result.jac, "toarray") else np.asarray(result.jac)
    rss = float(np.sum(residual(result.x) ** 2))
    variance = rss / max(t.size - p, 1)
    norms = np.linalg.norm(jac, axis=0)
    norms[norms == 0.0] = 1.0
    scaled = jac / norms
    inverse = np.linalg.pinv(scaled.T @ scaled, hermitian=True) / np.outer(norms, norms)
    units = np.concatenate([np.full(p - 2, t_unit), [g_unit, 1.0 / t_unit]])
    covariance = max(variance, (floor / y_unit) ** 2) * inverse * np.outer(units, units)
    x = np.concatenate([t_ref + t_unit * result.x[:-2], [g_unit * result.x[-2], result.x[-1] / t_unit]])
    return DampedFit(x[:-2], float(x[-2]), float(x[-1]), covariance, float(np.sqrt(variance) * y_unit), rss * y_unit**2,
                     int(t.size), int(start.side))


def loss_score(t, y, start: arcs.SequenceFit, floor: float = 0.0) -> tuple[float, float]:
    """The loss in flight ``c`` (1/s) that one Gauss-Newton step from ``start`` (the fit at
    ``c = 0``) reaches, and its standard error: the score test of ``c``, the residuals'
    projection on the derivative of the angle in ``c`` made orthogonal to the derivatives in
    the times and ``g`` (central differences), so no fit with ``c`` is needed to test it.

    Examples
    --------
    >>> tt = np.linspace(0.0, 1.5, 61)
    >>> yy = np.where(tt < 0.5, 0.25 - tt**2, -(tt - 0.5) * (1.5 - tt))
    >>> first = arcs.fit_sequence(tt, yy, side=1, times0=[0.0, 0.5, 1.5], q0=2.0, model="simplified", theta_cr=None)
    >>> c, se = loss_score(tt, yy, first)
    >>> abs(c) < 1e-6
    True
    """
    t, y = np.asarray(t, dtype=float), np.asarray(y, dtype=float)
    x = np.concatenate([start.times, [start.q, 0.0]])
    _, lo, d_lo, hi, d_hi, d_g = arcs._model(t, start.times, start.q, start.side, "simplified", None)  # noqa: SLF001
    jac = np.zeros((t.size, x.size))
    rows = np.arange(t.size)
    jac[rows, lo] += d_lo
    jac[rows, hi] += d_hi
    jac[:, -2] = d_g
    h = 1e-3 / float(np.min(np.diff(start.times)))
    jac[:, -1] = (_model(t, start.times, start.q, h, start.side) - _model(t, start.times, start.q, -h, start.side)) / (2.0 * h)
    residual = y - _model(t, x[:-2], x[-2], 0.0, start.side)
    rest = jac[:, :-1]
    norms = np.linalg.norm(rest, axis=0)
    norms[norms == 0.0] = 1.0
    scaled = rest / norms  # the normal equations of unit columns: the projection, without a QR of every sample
    column = jac[:, -1] - scaled @ np.linalg.lstsq(scaled.T @ scaled, scaled.T @ jac[:, -1], rcond=None)[0]
    size = float(column @ column)
    if not size > 0.0:
        return math.nan, math.nan
    sigma = max(start.residual_std, floor)
    return float(column @ residual) / size, sigma / math.sqrt(size)


def _impact_speeds(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The speeds landing before and leaving after each impact, of the parameters
    ``x = (*times, g, c)``: the fall lands at ``g T0 phi(c T0)``, each later flight leaves and
    lands at :func:`speeds`."""
    times, g, c = x[:-2], x[-2], x[-1]
    T0 = times[1] - times[0]
    landing0 = g * T0 * _phi(c * T0)
    leave, land = speeds(np.diff(times[1:]), g, c)
    return np.concatenate([[landing0], land[:-1]]), leave


def impact_speeds(fit: DampedFit) -> tuple[np.ndarray, np.ndarray]:
    """The speeds (rad/s) landing before and leaving after each impact of ``fit``."""
    return _impact_speeds(np.concatenate([fit.times, [fit.g, fit.c]]))


def _log_ratio_values(x: np.ndarray) -> np.ndarray:
    """``log e_k = log v_k - log w_(k-1)`` of the parameters ``x = (*times, g, c)``."""
    landing, leaving = _impact_speeds(x)
    return np.log(leaving) - np.log(landing)


def log_ratios(fit: DampedFit) -> tuple[np.ndarray, np.ndarray]:
    """Each impact's ``log e`` (the speed leaving over the speed landing, eq. 6) and their
    covariance, carried from the fit's by a central-difference gradient (the delta method).

    Examples
    --------
    >>> fit = DampedFit(np.array([0.0, 1.0, 2.8]), 2.0, 0.0, np.zeros((5, 5)), 0.0, 0.0, 10, 1)
    >>> np.round(np.exp(log_ratios(fit)[0]), 9).tolist()
    [0.9]
    """
    x = np.concatenate([fit.times, [fit.g, fit.c]])
    values = _log_ratio_values(x)
    grad = np.zeros((values.size, x.size))
    shortest = float(np.min(np.diff(fit.times)))
    steps = np.concatenate([np.full(x.size - 2, 1e-5 * shortest), [1e-6 * abs(fit.g), 1e-6 * max(abs(fit.c), 1.0 / shortest)]])
    for i, h in enumerate(steps):
        up, down = x.copy(), x.copy()
        up[i] += h
        down[i] -= h
        grad[:, i] = (_log_ratio_values(up) - _log_ratio_values(down)) / (2.0 * h)
    return values, grad @ fit.covariance @ grad.T

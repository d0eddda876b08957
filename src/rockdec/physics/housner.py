"""Linearized Housner rocking model (paper eqs. 1-3, 6), simulated exactly between impulses.

On each side of zero ``theta'' = nu^2 (theta - theta_cr sign(theta)) + F(t)``, whose free
solution from rest is eq. 2 and whose period is eq. 3; every zero crossing multiplies the
angular velocity by ``e`` (eq. 6), and the block falls over when ``|theta|`` reaches
``theta_cr``. For ``theta/theta_cr -> 0`` it tends to the simplified model (eq. 4,
:mod:`rockdec.physics.simulate`) with ``g = nu^2 theta_cr``. The load is exactly that of
:func:`rockdec.physics.simulate.simulate_block` (eqs. 21-24 with ``cosh``/``sinh`` arcs for
the parabolas), so both models fed one seed see one load.

:func:`housner_flight` advances a state exactly (the chattering limit summed in closed form),
:func:`integrate_housner` and :func:`simulate_block_housner` run series, :func:`choose_model`
picks the model a scene runs. Units: rad, rad/s, s. Sampling as in
:mod:`rockdec.physics.simulate`: ``theta[n]`` is the angle at ``t = n dt``, ``theta_dot[n]``
the velocity just after the impulse applied then.

Explanation: docs/explanation/method/models.md (the exact flight: §2.1).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from rockdec import validate as checks
from rockdec.physics.models import MODEL_TOLERANCE, amplitude_limit, check_finite_series, check_run, period_mismatch
from rockdec.physics.loading import draw_impulses, series_rng

__all__ = ["choose_model", "housner_flight", "integrate_housner", "simulate_block_housner"]

#: Bounces from ``theta = 0`` with ``w/c`` at most this are counted in closed form.
_SERIES_RATIO = 0.5
#: Relative size below which a term of the bounce-time series is dropped.
_SERIES_EPS = 1e-18
#: Largest number of Newton steps for the bounce count, and of its integer corrections.
_NEWTON_MAX = 60
_COUNT_FIX = 4
#: Passes of the event loop beyond the long bounces before giving up with NaN: a valid
#: state needs a handful; only NaN or overflow could loop for ever.
_MAX_PASSES = 64


@numba.njit(nogil=True, cache=True)
def _arc(h, u, t, nu, theta_cr):
    """Height and speed away from zero after ``t`` s on one side with no event (eq. 2).

    ``h(t) = h cosh(nu t) + (u/nu) sinh(nu t) - theta_cr (cosh(nu t) - 1)``, with
    ``cosh - 1`` and ``sinh`` both from one ``E = expm1(nu t)`` (``E^2/(2(1+E))`` and
    ``E(E+2)/(2(1+E))``), so that short arcs and small heights keep their relative precision.
    """
    em = math.expm1(nu * t)
    inv = 0.5 / (1.0 + em)
    chm1 = em * em * inv  # cosh - 1
    sh = em * (em + 2.0) * inv
    return h + h * chm1 + u * sh / nu - theta_cr * chm1, u + u * chm1 - nu * (theta_cr - h) * sh


@numba.njit(nogil=True, cache=True)
def _event(h, u, nu, theta_cr):
    """Next event from height ``h >= 0`` and speed ``u`` away from zero, on one side.

    Returns ``(t, kind, speed)``: ``kind = 1`` impact at ``theta = 0`` with ``speed`` the
    impact speed; ``kind = -1`` overturning (``|theta| = theta_cr``) with ``speed`` the
    velocity there; ``kind = 0`` no event ever (``t = inf``).
    """
    y = theta_cr - h  # distance to the critical angle, > 0
    d = nu * y - u  # 2 nu A
    if d > 0.0:
        w = math.sqrt(u * u + nu * nu * h * (theta_cr + y))  # energy: impact speed
        if u >= 0.0:
            n = nu * h + w + u
        else:
            n = nu * h + nu * nu * h * (theta_cr + y) / (w - u)
        return math.log1p(n / d) / nu, 1, w
    if d < 0.0:
        t = math.log1p(2.0 * nu * y / -d) / (2.0 * nu)
        return t, -1, math.sqrt((u - nu * y) * (u + nu * y))
    return math.inf, 0, 0.0


@numba.njit(nogil=True, cache=True)
def _bounce_time(w, nu, c):
    """Duration of one bounce from ``theta = 0`` with speed ``w < c``: ``(2/nu) atanh(w/c)``."""
    return math.log1p(2.0 * w / (c - w)) / nu


@numba.njit(nogil=True, cache=True)
def _series_terms(r):
    """Number of terms ``r^(2j+1)/(2j+1)`` kept in the bounce-time series (``r <= 1/2``)."""
    if r <= 0.0:
        return 1
    return max(1, int(math.ceil(math.log(_SERIES_EPS) / (2.0 * math.log(r)))) + 1)


@numba.njit(nogil=True, cache=True)
def _chatter_q(r, log_e, q, n_terms):
    """``sigma(q) = sum_j c_j (1 - q^(2j+1))`` and ``d sigma/dq``, ``c_j = r^(2j+1)/((2j+1)(1-e^(2j+1)))``.

    ``(2/nu) sigma(e^K)`` is the duration of ``K`` bounces, the first with ``w/c = r``.
    """
    s = 0.0
    ds = 0.0
    r2 = r * r
    q2 = q * q
    rp = r
    qp = 1.0  # q^(2j)
    for j in range(n_terms):
        m = 2.0 * j + 1.0
        cj = rp / (m * -math.expm1(m * log_e))
        s += cj * (1.0 - qp * q)
        ds -= cj * m * qp
        rp *= r2
        qp *= q2
    return s, ds


@numba.njit(nogil=True, cache=True)
def _chatter_k(r, log_e, k, n_terms):
    """``sigma(e^k)``, with ``1 - e^(m k)`` by ``expm1`` (precise for many bounces)."""
    s = 0.0
    r2 = r * r
    rp = r
    for j in range(n_terms):
        m = 2.0 * j + 1.0
        s += rp / m * math.expm1(m * k * log_e) / math.expm1(m * log_e)
        rp *= r2
    return s


@numba.njit(nogil=True, cache=True)
def _chatter_count(r, e, x):
    """Whole bounces that fit in scaled time ``x = nu R/2``, the first with ``w/c = r``.

    ``0 < e < 1``, ``r <= 1/2`` and the first bounce fits. Returns ``(K, sigma(e^K))``, or
    ``(-1, total)`` when the whole series fits (the block comes to rest).
    """
    log_e = math.log(e)
    n_terms = _series_terms(r)
    total, _ = _chatter_q(r, log_e, 0.0, n_terms)
    if total <= x:
        return -1.0, total
    c0 = -r / math.expm1(log_e)
    # sigma is decreasing and concave in q: from the leading-term root (left of the root)
    # Newton's first step lands right of it, and then converges monotonically.
    q = max(1.0 - x / c0, 0.0)
    for _ in range(_NEWTON_MAX):
        s, ds = _chatter_q(r, log_e, q, n_terms)
        q_new = min(max(q - (s - x) / ds, 0.0), 1.0)
        if abs(q_new - q) <= 4e-16 * q_new:
            q = q_new
            break
        q = q_new
    k = float(math.floor(math.log(q) / log_e)) if q > 0.0 else 1.0
    k = max(k, 1.0)
    for _ in range(_COUNT_FIX):
        if k > 1.0 and _chatter_k(r, log_e, k, n_terms) > x:
            k -= 1.0
        elif _chatter_k(r, log_e, k + 1.0, n_terms) <= x:
            k += 1.0
        else:
            break
    return k, _chatter_k(r, log_e, k, n_terms)


@numba.njit(nogil=True, cache=True)
def housner_flight(theta, omega, duration, nu, theta_cr, e):
    """Advance ``(theta, omega)`` by ``duration`` s of free rocking of the linearized Housner model.

    Exact (to rounding) for eqs. 2 and 6: any number of impacts, the chattering limit and
    the rest state included. Returns ``(theta, omega, overturned)``; when the block reaches
    ``|theta| = theta_cr`` inside the interval, the motion stops there and the result is
    ``(s theta_cr, velocity at that instant, True)``. A start at ``|theta| >= theta_cr``
    counts as overturned at once. A NaN state or step gives ``(nan, nan, False)`` (the
    loop is bounded).
    """
    if theta == 0.0 and omega == 0.0:
        return 0.0, 0.0, False
    side = 1.0 if (theta > 0.0 or (theta == 0.0 and omega > 0.0)) else -1.0
    h = side * theta
    u = side * omega
    if h >= theta_cr:
        return side * theta_cr, omega, True
    # Fast path: h is concave on a side (y = theta_cr - h is convex while positive), so a
    # height inside (0, theta_cr) at the end means no impact and no overturning on the way.
    h_end, u_end = _arc(h, u, duration, nu, theta_cr)
    if 0.0 < h_end < theta_cr:
        return side * h_end, side * u_end, False
    c = nu * theta_cr
    remaining = duration
    if not (remaining >= 0.0 and h >= 0.0 and abs(u) < math.inf and c > 0.0):  # NaN in, NaN out
        return math.nan, math.nan, False
    # long bounces, taken one at a time: each lasts more than (2/nu) atanh(1/2) > 1/nu and
    # leaves e times the speed, from below c down to c/2; e = 0 rests at the first landing
    # and e = 1 counts its bounces in closed form
    long_bounces = min(nu * duration, math.log(0.5) / math.log(e)) if 0.0 < e < 1.0 else 0.0
    passes = _MAX_PASSES + (int(min(long_bounces, 1e9)) if long_bounces >= 0.0 else 0)
    for _ in range(passes):
        if h == 0.0 and u < c:
            # At zero, leaving with speed u = w: whole bounces first (each lands with w, eq. 6).
            w = u
            tb = _bounce_time(w, nu, c)
            if tb <= remaining:
                if e == 0.0:  # plastic impact at the landing: rest
                    return 0.0, 0.0, False
                final = True
                if e == 1.0:
                    k = float(math.floor(remaining / tb))
                    if (k + 1.0) * tb <= remaining:
                        k += 1.0
                    elif k * tb > remaining and k > 1.0:
                        k -= 1.0
                    remaining -= k * tb
                elif w <= _SERIES_RATIO * c:
                    k, s = _chatter_count(w / c, e, 0.5 * nu * remaining)
                    if k < 0.0:
                        return 0.0, 0.0, False
                    remaining -= 2.0 * s / nu
                    w *= math.exp(k * math.log(e))
                else:  # a long bounce: one at a time (at most duration nu / 1.09 of them)
                    k = 1.0
                    final = False
                    remaining -= tb
                    w *= e
                if k % 2.0 == 1.0:
                    side = -side
                if w == 0.0:
                    return 0.0, 0.0, False
                u = w
                if final:  # the next bounce does not fit (to rounding): the last arc
                    t_last = min(max(remaining, 0.0), _bounce_time(w, nu, c))
                    h, u = _arc(0.0, w, t_last, nu, theta_cr)
                    if h <= 0.0 and u < 0.0:  # rounding: back at zero, the impact is at the end
                        return 0.0, side * e * u, False
                    return side * max(h, 0.0), side * u, False
                continue
        t, kind, speed = _event(h, u, nu, theta_cr)
        if t >= remaining:
            h_end, u_end = _arc(h, u, remaining, nu, theta_cr)
            if kind == 1 and h_end <= 0.0:  # rounding: the impact is at the very end
                return 0.0, -side * e * speed, False
            if kind == -1 and h_end >= theta_cr:
                return side * theta_cr, side * speed, True
            return side * h_end, side * u_end, False
        remaining -= t
        if kind == -1:
            return side * theta_cr, side * speed, True
        # impact (eq. 6): the block leaves zero on the other side with e times the speed
        side = -side
        h = 0.0
        u = e * speed
        if u == 0.0:
            return 0.0, 0.0, False
    return math.nan, math.nan, False


@numba.njit(nogil=True, cache=True)
def integrate_housner(impulses, dt, nu, theta_cr, e, theta0, omega0, burn_in, theta_out, omega_out):
    """Integrate one series of the linearized Housner model exactly and write the recorded part.

    As :func:`rockdec.physics.simulate.integrate`: ``impulses`` (rad/s) holds ``burn_in + n - 1``
    values, the first ``burn_in`` steps are discarded and ``n = len(theta_out)`` samples are
    written, the first being the state after the burn-in. Returns ``-1``, or the index of
    the first sample at which the block lies overturned (``0`` when it fell during the
    burn-in or started at ``|theta0| >= theta_cr``); from that sample on both outputs are NaN.
    """
    theta = theta0
    omega = omega0
    n = theta_out.shape[0]
    fallen = abs(theta0) >= theta_cr
    for i in range(burn_in):
        if fallen:
            break
        theta, omega, fallen = housner_flight(theta, omega, dt, nu, theta_cr, e)
        omega += impulses[i]  # irrelevant once fallen
    if fallen:
        theta_out[:] = np.nan
        omega_out[:] = np.nan
        return 0
    theta_out[0] = theta
    omega_out[0] = omega
    for j in range(1, n):
        theta, omega, fallen = housner_flight(theta, omega, dt, nu, theta_cr, e)
        if fallen:
            theta_out[j:] = np.nan
            omega_out[j:] = np.nan
            return j
        omega += impulses[burn_in + j - 1]
        theta_out[j] = theta
        omega_out[j] = omega
    return -1


def simulate_block_housner(seeds, n_points, *, dt, nu, theta_cr, e, sigma_p, theta0=0.0, theta_dot0=0.0, burn_in=0, pole=0.0,
                           spectrum=None):
    """Simulate one linearized-Housner series per seed (eqs. 2, 6; load as eqs. 21-24).

    Mirrors :func:`rockdec.physics.simulate.simulate_block` and draws the same impulses from the
    same seed. ``nu`` in rad/s, ``theta_cr`` in rad, ``sigma_p`` the impulse standard
    deviation in rad/s (``0``: free response from ``(theta0, theta_dot0)``), ``dt`` in s;
    ``pole``: the low-pass filtered load of :func:`rockdec.physics.loading.draw_impulses` (0: white);
    ``spectrum``: a load of that spectrum (:class:`rockdec.physics.loading.ImpulseSpectrum`) instead.

    Returns ``(theta, theta_dot, overturned_at)``: two ``(len(seeds), n_points)`` arrays,
    NaN from the sample at which a series' block lies overturned, and an int64 array with
    that sample index per seed (``-1``: it never fell; ``0``: it fell in the burn-in).
    """
    check_run(dt=dt, e=e, sigma_p=sigma_p, theta0=theta0, theta_dot0=theta_dot0, burn_in=burn_in, n_points=n_points)
    checks.positive(nu, "nu", "give the rocking frequency parameter in rad/s, > 0")
    checks.positive(theta_cr, "theta_cr", "give the critical angle in rad, > 0")
    seeds = np.atleast_1d(np.asarray(seeds, dtype=np.int64))
    n_steps = burn_in + n_points - 1
    theta = np.empty((seeds.size, n_points))
    theta_dot = np.empty((seeds.size, n_points))
    overturned_at = np.full(seeds.size, -1, dtype=np.int64)
    impulses = np.empty(n_steps)
    for row, seed in enumerate(seeds):
        draw_impulses(series_rng(seed), impulses, sigma_p, pole, spectrum)
        overturned_at[row] = integrate_housner(
            impulses, dt, nu, theta_cr, e, theta0, theta_dot0, burn_in, theta[row], theta_dot[row]
        )
    standing = np.flatnonzero(overturned_at != 0)  # NaN only from the fall on
    last = np.where(overturned_at < 0, n_points, overturned_at)[standing] - 1
    check_finite_series(
        np.stack([theta[standing, last], theta_dot[standing, last]]),
        f"the Housner simulation at dt = {dt}, nu = {nu}, sigma_p = {sigma_p}",
    )
    return theta, theta_dot, overturned_at


def choose_model(amplitude_ratio: float, tolerance: float = MODEL_TOLERANCE) -> tuple[str, str]:
    """The cheapest model valid at ``theta/theta_cr = amplitude_ratio`` (docs/method.md §2.4): ``(name, reason)``.

    ``"simplified"`` (eq. 4) while its period (eq. 5) is within ``tolerance`` (relative) of the
    linearized Housner period (eq. 3) at that amplitude, otherwise ``"housner"`` (eq. 2).
    The caller chooses which amplitude to guard; the intended one is a large but typical
    peak of the response, ``amplitude_ratio = 3 sigma_Y/theta_cr``: the stationary response
    is heavy-tailed (kurtosis 15-20), so ``3 sigma_Y`` is well inside the range the record
    visits often, while the single largest peak would make the choice depend on the record
    length. ``reason`` is one sentence with the numbers, for logs and file attributes.
    """
    ratio = float(amplitude_ratio)
    if not ratio >= 0.0:
        raise ValueError(f"amplitude_ratio must be >= 0 (got {amplitude_ratio})")
    limit = amplitude_limit(tolerance)
    if ratio >= 1.0:
        return "housner", (
            f"theta/theta_cr = {ratio:.3g} reaches the critical angle: the block can overturn, which only "
            f"the linearized Housner model (eq. 2) represents (the simplified model is valid below {limit:.3g})"
        )
    mismatch = period_mismatch(ratio)
    if mismatch < tolerance:
        return "simplified", (
            f"at theta/theta_cr = {ratio:.3g} the Housner period (eq. 3) exceeds the simplified one (eq. 5) by "
            f"{mismatch:.2%}, less than the tolerance {tolerance:.2%} (reached at theta/theta_cr = {limit:.3g})"
        )
    return "housner", (
        f"at theta/theta_cr = {ratio:.3g} the Housner period (eq. 3) exceeds the simplified one (eq. 5) by "
        f"{mismatch:.2%}, not less than the tolerance {tolerance:.2%} (reached at theta/theta_cr = {limit:.3g})"
    )

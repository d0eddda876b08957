"""Records of the randomly loaded simplified model (eqs. 4, 21-24) whose impacts are a soft
contact, written apart from :mod:`rockdec.physics.simulate`.

Between impacts ``theta'' = -g sign(theta)``; at the end of every step of ``dt`` a velocity
impulse ``sigma_p w_n``, ``w_n ~ N(0, 1)`` (the project's white load). An impact of eq. 6
multiplies the velocity ``V`` at the zero crossing by ``e`` at once; a soft contact spreads
that change over ``contact`` steps: from the crossing on, a constant deceleration
``(1 - e) V / (contact dt)`` acts against the motion beside the restoring ``g``, for
``contact dt`` seconds or until the block stops (a contact pushes, never pulls), so without
impulses inside it the velocity passes linearly from ``V`` to ``e V`` (less the restoring
term's share) over the contact. ``contact = 0`` is the ideal impact, with the rest of eq. 6
when the bounces' geometric series ends inside the step (as ``rocking_reference.py``).

Every flight is stepped event by event in closed form (piecewise-constant acceleration: the
crossing, the contact's end, the block's stop), one record at a time, compiled by numba.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

#: Speed below which a crossing ends the motion in the step (the block at rest; far below the
#: impulses' ``sigma_p``), and the most events stepped in one step before it rests.
REST_SPEED, MAX_EVENTS = 1e-12, 10_000


@njit(cache=False, nogil=True)
def _step(th, om, left, decel, side, dt, g, e, span):
    """One step of free flight (no impulse) from ``(th, om)``, with ``left`` seconds of a
    contact of deceleration ``decel`` in direction ``side`` running; returns the new state."""
    rem = dt
    for _ in range(MAX_EVENTS):
        if left > 0.0:
            u = side * om
            if u <= 0.0:  # stopped or turned by an impulse: the contact ends
                left = 0.0
                continue
            a = g + decel
            stop = u / a
            seg = min(rem, left, stop)
            th += om * seg - side * 0.5 * a * seg * seg
            om = 0.0 if seg == stop else om - side * a * seg
            left = 0.0 if seg == stop else left - seg
            rem -= seg
            if rem <= 0.0:
                return th, om, left, decel, side
            continue
        if th == 0.0 and om == 0.0:
            return 0.0, 0.0, 0.0, 0.0, side
        s = 1.0 if (th > 0.0 or (th == 0.0 and om > 0.0)) else -1.0
        h, u = s * th, s * om
        root = math.sqrt(u * u + 2.0 * g * h)
        cross = (u + root) / g if u >= 0.0 else 2.0 * h / (root - u)  # no difference of near equals
        if cross > rem:
            return s * (h + u * rem - 0.5 * g * rem * rem), s * (u - g * rem), 0.0, 0.0, side
        speed = g * cross - u
        rem -= cross
        side = -s
        if speed <= REST_SPEED:
            return 0.0, 0.0, 0.0, 0.0, side
        if span == 0.0:
            rebound = e * speed
            if e < 1.0 and 2.0 * rebound / g / (1.0 - e) <= rem:
                return 0.0, 0.0, 0.0, 0.0, side
            th, om = 0.0, side * rebound
        else:
            th, om, left, decel = 0.0, side * speed, span, (1.0 - e) * speed / span
    return 0.0, 0.0, 0.0, 0.0, side


@njit(cache=False, nogil=True)
def _run(pushes, burn_in, dt, g, e, sigma_p, span):
    n = pushes.size - burn_in + 1
    out = np.empty(n)
    th = om = left = decel = 0.0
    side = 1.0
    for k in range(pushes.size + 1):
        if k >= burn_in:
            out[k - burn_in] = th
            if k - burn_in == n - 1:
                break
        th, om, left, decel, side = _step(th, om, left, decel, side, dt, g, e, span)
        om += sigma_p * pushes[k]
    return out


def soft_record(seed: int, n: int, *, contact: float, e: float = 0.9, dt: float = 0.8043, g: float = 1.0, sigma_p: float = 1.0,
                burn_in: int = 4362) -> np.ndarray:
    """``n`` samples of ``theta`` (the first after ``burn_in`` steps from rest) of one record
    whose impacts are a contact of ``contact`` steps (0: the ideal impact, eq. 6); its impulses
    from ``numpy.random.default_rng([seed, 49])``. The defaults are the tests' white scene:
    about 75 samples per cycle at ``e = 0.9``."""
    pushes = np.random.default_rng([int(seed), 49]).standard_normal(burn_in + n - 1)
    return _run(pushes, burn_in, float(dt), float(g), float(e), float(sigma_p), float(contact) * float(dt))


def flight(theta: float, omega: float, duration: float, *, contact: float, e: float, dt: float = 0.8043, g: float = 1.0):
    """Free rocking from ``(theta, omega)`` for ``duration`` seconds, no contact running at
    the start, contacts of ``contact`` steps of ``dt``: ``(theta, omega)``."""
    th, om, *_ = _step(float(theta), float(omega), 0.0, 0.0, 1.0, float(duration), float(g), float(e), float(contact) * float(dt))
    return th, om

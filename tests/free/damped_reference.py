"""A free-rocking record with a loss in flight, integrated numerically (written apart from
:mod:`rockdec.free.flight_loss`, whose closed forms it checks): between impacts
``theta'' = -g sign(theta) - c theta'`` by :func:`scipy.integrate.solve_ivp` (an explicit
Runge-Kutta of order 8 at tight tolerances) to each zero crossing, where the speed is
multiplied by ``e`` (eq. 6)."""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp


def damped_release(e, c, *, g=1.0, theta0=0.02, dt=0.002, hold=20, noise=0.0, seed=0, min_flight_samples=3):
    """Held at ``theta0`` for ``hold`` samples, released, then flights with a loss ``c`` (1/s)
    and impacts of ``e`` (a number, or a function of the impact's number), until a flight
    lasts fewer than ``min_flight_samples`` samples; white sensor noise of ``noise`` release
    angles (``numpy.random.default_rng(seed)``). Returns the record and the impact times."""
    pieces, impacts = [], []
    t_start, side, h0, v0, k = hold * dt, 1.0, theta0, 0.0, 0

    def crossing(t, y):
        return y[0]

    crossing.terminal, crossing.direction = True, -1
    while True:
        sol = solve_ivp(lambda t, y: [y[1], -g - c * y[1]], (0.0, 100.0), [h0, v0], method="DOP853", rtol=1e-12, atol=1e-15,
                        events=crossing, dense_output=True)
        T = float(sol.t_events[0][0]) if sol.t_events[0].size else math.inf
        pieces.append((t_start, T, side, sol.sol))
        impacts.append(t_start + T)
        landing = -float(sol.y_events[0][0][1])
        ratio = e(k) if callable(e) else e
        k += 1
        t_start, side, h0, v0 = t_start + T, -side, 0.0, ratio * landing
        if T < min_flight_samples * dt or v0 <= 0.0:
            break
    n = int(math.ceil((impacts[-1] + 0.5) / dt))
    t = np.arange(n) * dt
    y = np.zeros(n)
    y[t < hold * dt] = theta0
    for start, T, s, solution in pieces:
        inside = (t >= start) & (t < start + T)
        y[inside] = s * solution(t[inside] - start)[0]
    return y + np.random.default_rng(seed).normal(0.0, noise * theta0, n), dt, np.array(impacts)

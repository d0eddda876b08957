"""A short pure-Python reference of one free-rocking interval, impact by impact.

Independent of the compiled kernel: it steps through every impact one at a time (no
closed-form count of bounces) and stops the chatter when the remaining bounces'
geometric series (eq. 6: each flight is ``e`` times the last) fits in the time left.
"""

import math


def flight_reference(theta, omega, duration, g, e, max_impacts=10_000_000):
    remaining = duration
    for _ in range(max_impacts):
        if theta == 0.0 and omega == 0.0:
            return 0.0, 0.0
        side = 1.0 if (theta > 0.0 or (theta == 0.0 and omega > 0.0)) else -1.0
        h, u = side * theta, side * omega
        # time to reach zero: positive root of h + u t - g t^2 / 2 = 0
        t_cross = (u + math.sqrt(u * u + 2.0 * g * h)) / g
        # a landing exactly at the end of the interval is an impact: left for the next
        # interval, the state (0, speed towards the other side) would cross unrestituted
        if t_cross > remaining:
            t = remaining
            return side * (h + u * t - 0.5 * g * t * t), side * (u - g * t)
        speed = g * t_cross - u  # impact speed
        remaining -= t_cross
        rebound = e * speed
        if rebound == 0.0 or (e < 1.0 and 2.0 * rebound / g / (1.0 - e) <= remaining):
            return 0.0, 0.0
        theta, omega = 0.0, -side * rebound
    raise RuntimeError("too many impacts")

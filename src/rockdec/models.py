"""Rocking models and their free-rocking periods (paper eqs. 2-5).

Units: angles in rad, time in s, ``nu`` (the rocking frequency parameter) in rad/s,
``g = nu**2 * theta_cr`` (the restoring acceleration of the simplified model, eq. 4)
in rad/s**2.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from rockdec import validate as checks


def restoring_acceleration(nu: float, theta_cr: float) -> float:
    """``g = nu^2 * theta_cr`` in rad/s^2: the constant restoring term of eq. 4 (``inf`` on overflow)."""
    try:
        return float(nu) ** 2 * float(theta_cr)
    except OverflowError:  # float ** raises where * gives inf
        return math.inf


def period_simplified(theta0, nu: float, theta_cr: float):
    """Free-rocking period of the simplified model, eq. 5: ``T = (4/nu) sqrt(2 theta0/theta_cr)``.

    Equivalently ``T = 4 sqrt(2 theta0 / g)``; ``theta0`` in rad, ``T`` in s.
    """
    return 4.0 / nu * np.sqrt(2.0 * np.asarray(theta0, dtype=float) / theta_cr)


def period_from_g(theta0, g: float):
    """Eq. 5 written with the restoring acceleration only: ``T = 4 sqrt(2 theta0 / g)``."""
    return 4.0 * np.sqrt(2.0 * np.asarray(theta0, dtype=float) / g)


def period_housner(theta0, nu: float, theta_cr: float):
    """Free-rocking period of the linearized Housner model, eq. 3.

    ``T = (4/nu) acosh(1 / (1 - theta0/theta_cr))``; infinite at ``theta0 >= theta_cr``
    (the block overturns).
    """
    ratio = np.asarray(theta0, dtype=float) / theta_cr
    with np.errstate(divide="ignore", invalid="ignore"):
        out = 4.0 / nu * np.arccosh(1.0 / (1.0 - ratio))
    return np.where(ratio >= 1.0, np.inf, out)


def period_mismatch(amplitude_ratio: float) -> float:
    """Relative excess of the Housner period (eq. 3) over the simplified one (eq. 5).

    ``T_3/T_5 - 1`` at ``theta0/theta_cr = amplitude_ratio``; about ``5 ratio/12`` for small
    ratios, infinite at ``ratio >= 1``. Dimensionless (the ratio of the periods does not
    depend on ``nu``).
    """
    ratio = float(amplitude_ratio)
    if ratio <= 0.0:
        return 0.0
    return float(period_housner(ratio, 1.0, 1.0) / period_simplified(ratio, 1.0, 1.0)) - 1.0


def amplitude_limit(tolerance: float = 0.02) -> float:
    """Amplitude ratio ``theta0/theta_cr`` at which eqs. 3 and 5 differ by ``tolerance`` (relative).

    Below it the simplified model's period is within ``tolerance`` of the Housner one. The
    mismatch grows monotonically from 0 (ratio -> 0) to infinity (ratio -> 1), so the root
    is unique; found by :func:`scipy.optimize.brentq`. ``amplitude_limit(0.02)`` is about 0.047.
    """
    if not tolerance > 0.0:
        raise ValueError(f"tolerance must be > 0 (got {tolerance})")
    return float(brentq(lambda x: period_mismatch(x) - tolerance, 1e-12, 1.0 - 1e-12, xtol=1e-15, rtol=1e-14))


def check_run(*, dt, e, sigma_p, theta0, theta_dot0, burn_in, n_points) -> None:
    """Refuse a simulation request outside the models (eqs. 4, 6; load of eqs. 21-24).

    ``dt > 0``, ``0 <= e <= 1``, ``sigma_p >= 0``, finite initial state, whole ``burn_in >= 0``
    and ``n_points >= 1``; NaN and infinities never pass (:mod:`rockdec.validate`).
    """
    checks.positive(dt, "dt", "give the time step in s, > 0")
    checks.in_range(e, "e", 0.0, 1.0, "give the coefficient of restitution in [0, 1]")
    checks.positive(sigma_p, "sigma_p", "give the impulse standard deviation in rad/s, >= 0", allow_zero=True)
    checks.finite(theta0, "theta0", "give the initial angle in rad")
    checks.finite(theta_dot0, "theta_dot0", "give the initial angular velocity in rad/s")
    checks.integer(burn_in, "burn_in", 0)
    checks.integer(n_points, "n_points", 1)


def check_finite_series(last_state: np.ndarray, what: str) -> None:
    """Refuse series that left the floating-point range (huge scales overflow).

    ``last_state`` holds the last sample of each series: a state that is NaN or infinite
    stays so (NaN and infinities propagate through the flight formulas and the impulses are
    finite), so the last samples tell whether any sample was not finite, at no cost.
    """
    if not np.isfinite(last_state).all():
        raise checks.InputError(
            f"{what} overflows the floating-point range (it is not finite); give physical scales: "
            "smaller sigma_p, dt or initial state, or a larger g"
        )

"""Rocking models and their free-rocking periods (paper eqs. 2-5).

Units: angles in rad, time in s, ``nu`` (the rocking frequency parameter) in rad/s,
``g = nu**2 * theta_cr`` (the restoring acceleration of the simplified model, eq. 4)
in rad/s**2.
"""

from __future__ import annotations

import math

import numpy as np

from rockdec import validate as checks

__all__ = [
    "MODELS", "MODEL_PEAK_SIGMAS", "MODEL_TOLERANCE", "SCALE_CONSTANT_GUESS", "amplitude_limit",
    "auto_switch_ratio", "check_finite_series", "check_run", "noise_for_amplitude", "period_from_g",
    "period_housner", "period_mismatch", "period_simplified", "restoring_acceleration", "scale_constant",
    "step_for_density",
]

MODELS = ("simplified", "housner")
"""The rocking models: simplified (eq. 4) and linearized Housner (eq. 2)."""

MODEL_TOLERANCE = 0.02
"""Largest relative difference of the periods of eqs. 3 and 5 at which ``auto`` keeps the
simplified model."""

MODEL_PEAK_SIGMAS = 3.0
"""The amplitude ``auto`` guards, in units of ``sigma_Y``: ``3 sigma_Y`` is a large but
typical peak of the heavy-tailed response (kurtosis 15-20)."""


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
    is unique; found by bisection of ``(0, 1)`` down to adjacent floats (about 60 halvings,
    without loading :mod:`scipy.optimize`, 0.3 s, on the way to a run's first
    simulation). ``amplitude_limit(0.02)`` is about 0.047.
    """
    if not tolerance > 0.0:
        raise ValueError(f"tolerance must be > 0 (got {tolerance})")
    low, high = 0.0, 1.0  # mismatch 0 below the root, above it (infinite at 1)
    while True:
        middle = 0.5 * (low + high)
        if not low < middle < high:
            return high
        if period_mismatch(middle) < tolerance:
            low = middle
        else:
            high = middle


def auto_switch_ratio() -> float:
    """``sigma_Y/theta_cr`` at which ``auto`` switches from eq. 4 to eq. 2: the amplitude
    limit of :data:`MODEL_TOLERANCE` (:func:`amplitude_limit`) over :data:`MODEL_PEAK_SIGMAS`."""
    return amplitude_limit(MODEL_TOLERANCE) / MODEL_PEAK_SIGMAS


SCALE_CONSTANT_GUESS = 290.0
"""The number ``c`` of :func:`scale_constant` near ``e = 0.95`` (white load, 75 samples per
cycle): the first guess of every step search, which then measures ``c``."""


def scale_constant(sigma_y: float, dt: float, g: float, sigma_p: float) -> float:
    """The number ``c = sigma_Y dt^2 g^3 / sigma_p^4`` of the stationary scale law.

    Under eq. 4 with white velocity impulses the only scales are ``g`` and the noise
    intensity ``S = sigma_p^2/dt``, so ``sigma_Y = c S^2/g^3`` with ``c`` a number that
    depends on ``e`` and, weakly, on the sampling (docs/method.md §3.4).
    """
    return sigma_y * dt**2 * g**3 / sigma_p**4


def step_for_density(c: float, sigma_p: float, g: float, points_per_cycle: float) -> float:
    """The step giving ``points_per_cycle`` samples per cycle at ``sigma_Y`` (eq. 5) under the
    scale law of :func:`scale_constant`: ``T(sigma_Y) = 4 sqrt(2 sigma_Y/g) = N dt`` gives
    ``dt = (sigma_p/g) sqrt(4 sqrt(2 c)/N)``."""
    return sigma_p / g * math.sqrt(4.0 * math.sqrt(2.0 * c) / points_per_cycle)


def noise_for_amplitude(c: float, sigma_y: float, g: float, points_per_cycle: float) -> float:
    """The impulse std giving ``sigma_Y`` at ``points_per_cycle`` samples per cycle: the
    scale law of :func:`scale_constant` with the step of :func:`step_for_density`, solved
    for ``sigma_p`` (``sigma_Y = sigma_p^2 N sqrt(c)/(4 sqrt(2) g)``)."""
    return math.sqrt(sigma_y * 4.0 * math.sqrt(2.0) * g / (points_per_cycle * math.sqrt(c)))


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

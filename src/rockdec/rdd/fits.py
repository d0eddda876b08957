"""How many points the estimators' fits take (eqs. 26-27, ``e_v``).

Imports nothing: the configuration (and so the Snakefile) checks a scene's sampling against
these numbers without loading numba or xarray.
"""

__all__ = ["DEFAULT_FIT_POINTS", "MIN_FIT_POINTS", "min_points_per_cycle"]

MIN_FIT_POINTS = 3
"""Fewest points of any second-order fit: three coefficients need three points (with three
the fit interpolates). Fits that would get fewer give NaN, ``"fewer than 3 points for a fit"``."""

DEFAULT_FIT_POINTS = 5
"""Points on each side of lag 0 for ``e_v``: about ``N_h/8`` at 75 points per cycle
(``N_h`` about 37), the size of the slope fits of ``e2``."""


def min_points_per_cycle(e: float, level: float) -> float:
    """Fewest samples per cycle at amplitude ``sigma_Y`` for which ``e1..e4`` can be fitted.

    The start and crossing fits of eq. 27 take ``N_h // 8`` points and need
    :data:`MIN_FIT_POINTS`, so ``N_h >= 8 * MIN_FIT_POINTS``. For the free response from
    ``a = level * sigma_Y`` the first minimum comes at ``(1 + e)/4`` of a period at
    amplitude ``a``, which is ``sqrt(level)`` times the period at ``sigma_Y`` (eq. 5):
    ``N_h = (1 + e)/4 * sqrt(level) * points_per_cycle``. At ``e = 0.95``, level 2: 35.
    """
    return 4.0 * 8 * MIN_FIT_POINTS / ((1.0 + e) * level**0.5)

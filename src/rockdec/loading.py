"""The load: discrete white noise as velocity impulses (paper §4), one random stream per seed.

Coloured load (the open question of paper §6): the impulses pass a first-order low-pass
filter, ``p_n = c p_{n-1} + sqrt(1 - c^2) w_n`` with ``w_n`` the white impulses, which keeps
their standard deviation ``sigma_p`` and puts the corner at ``f_c = -ln(c) / (2 pi dt)``;
:func:`pole_for_corner` gives ``c`` for a corner set in rocking cycles.

Every simulator (the simplified model, the Housner model, the fixed-step integrator) draws
its impulses here, so one seed means one load whatever the model.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import lfilter


def series_rng(seed: int) -> np.random.Generator:
    """The random generator of one series: NumPy ``SeedSequence(seed)``, PCG64.

    A series depends on its own seed only, whatever other seeds, chunks or cores run
    beside it.
    """
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(int(seed))))


def draw_impulses(rng: np.random.Generator, out: np.ndarray, sigma_p: float, pole: float = 0.0) -> np.ndarray:
    """Fill ``out`` with the next impulses ``p_n ~ N(0, sigma_p^2)`` (rad/s) of ``rng``.

    ``sigma_p = 0`` gives zeros (a free response) and draws nothing. Drawing a series in
    blocks continues the same stream, so white blocks concatenate to the whole series.
    ``pole`` ``c`` in ``[0, 1)``: the low-pass filtered load of the module docstring,
    started stationary (``p_0 = sigma_p w_0``); ``0`` is white noise.
    """
    if sigma_p > 0.0:
        rng.standard_normal(out=out)
        if pole > 0.0 and out.size:
            gain = np.sqrt(1.0 - pole * pole)
            out[:] = lfilter([gain], [1.0, -pole], out, zi=[(1.0 - gain) * out[0]])[0]  # p_0 = w_0
        out *= sigma_p
    else:
        out[:] = 0.0
    return out


def pole_for_corner(corner_cycles: float, points_per_cycle: float) -> float:
    """Pole ``c`` of the load filter whose corner is ``corner_cycles`` times the rocking
    frequency ``1/T(sigma_Y)`` (eq. 5), at ``points_per_cycle`` samples per cycle:
    ``c = exp(-2 pi corner_cycles / points_per_cycle)``."""
    return float(np.exp(-2.0 * np.pi * corner_cycles / points_per_cycle))

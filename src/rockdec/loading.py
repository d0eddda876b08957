"""The load: discrete white noise as velocity impulses (paper §4), one random stream per seed.

Every simulator (the simplified model, the Housner model, the fixed-step integrator) draws
its impulses here, so one seed means one load whatever the model.
"""

from __future__ import annotations

import numpy as np


def series_rng(seed: int) -> np.random.Generator:
    """The random generator of one series: NumPy ``SeedSequence(seed)``, PCG64.

    A series depends on its own seed only, whatever other seeds, chunks or cores run
    beside it.
    """
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(int(seed))))


def draw_impulses(rng: np.random.Generator, out: np.ndarray, sigma_p: float) -> np.ndarray:
    """Fill ``out`` with the next impulses ``p_n ~ N(0, sigma_p^2)`` (rad/s) of ``rng``.

    ``sigma_p = 0`` gives zeros (a free response) and draws nothing. Drawing a series in
    blocks continues the same stream, so blocks concatenate to the whole series.
    """
    if sigma_p > 0.0:
        rng.standard_normal(out=out)
        out *= sigma_p
    else:
        out[:] = 0.0
    return out

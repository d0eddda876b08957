"""The random streams of a series: its load, discrete white noise as velocity impulses (paper
§4), and the noise of the sensor that records its angle; one pair of streams per seed.

Coloured load (the open question of paper §6): the impulses pass a first-order low-pass
filter, ``p_n = c p_{n-1} + sqrt(1 - c^2) w_n`` with ``w_n`` the white impulses, which keeps
their standard deviation ``sigma_p``, gives them the autocorrelation ``c^m`` at lag ``m``
and puts the corner at ``f_c = -ln(c) / (2 pi dt)``; :meth:`rockdec.record_model.Load.pole`
gives ``c`` for a corner set in rocking frequencies.

Every simulator (the simplified model, the Housner model, the fixed-step integrator) draws
its impulses here, so one seed means one load whatever the model.
"""

from __future__ import annotations

import math

import numba
import numpy as np

SENSOR_STREAM = 1
"""Spawn key of a series' sensor-noise stream (the load's stream has none), so the sensor's
noise never shares random numbers with the load."""


def series_rng(seed: int) -> np.random.Generator:
    """The random generator of one series' load: NumPy ``SeedSequence(seed)``, PCG64.

    A series depends on its own seed only, whatever other seeds, chunks or cores run
    beside it.
    """
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(int(seed))))


def sensor_rng(seed: int) -> np.random.Generator:
    """The random generator of one series' sensor noise: ``SeedSequence(seed)`` spawned once
    (:data:`SENSOR_STREAM`), PCG64; independent of :func:`series_rng` of the same seed."""
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(int(seed), spawn_key=(SENSOR_STREAM,))))


@numba.njit(nogil=True, cache=True)
def low_pass(w, pole):
    """First-order low-pass filter in place: ``w[n] <- pole w[n-1] + sqrt(1 - pole^2) w[n]``
    for ``n >= 1`` (``w[n-1]`` already filtered), ``w[0]`` kept: unit-variance white ``w``
    becomes a stationary sequence of unit variance and autocorrelation ``pole^m``."""
    gain = math.sqrt(1.0 - pole * pole)
    for n in range(1, w.size):
        w[n] = pole * w[n - 1] + gain * w[n]
    return w


def draw_impulses(rng: np.random.Generator, out: np.ndarray, sigma_p: float, pole: float = 0.0) -> np.ndarray:
    """Fill ``out`` with the next impulses ``p_n ~ N(0, sigma_p^2)`` (rad/s) of ``rng``.

    ``sigma_p = 0`` gives zeros (a free response) and draws nothing. Drawing a series in
    blocks continues the same stream, so white blocks concatenate to the whole series.
    ``pole`` ``c`` in ``[0, 1)``: the low-pass filtered load of the module docstring
    (:func:`low_pass`), started stationary (``p_0 = sigma_p w_0``); ``0`` is white noise.
    """
    if sigma_p > 0.0:
        rng.standard_normal(out=out)
        if pole > 0.0 and out.size:
            low_pass(out, pole)
        out *= sigma_p
    else:
        out[:] = 0.0
    return out


def add_sensor_noise(theta: np.ndarray, seeds, std: float) -> np.ndarray:
    """``theta(seed, time)`` (changed in place) plus white sensor noise of standard deviation
    ``std`` (rad), each row from :func:`sensor_rng` of its seed; ``std = 0`` draws nothing."""
    if std > 0.0:
        for row, seed in zip(theta, np.atleast_1d(seeds)):
            row += std * sensor_rng(seed).standard_normal(row.size)
    return theta

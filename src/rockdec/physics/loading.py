"""The random streams of a series: its load, discrete white noise as velocity impulses (paper
§4), and the noise of the sensor that records its angle; one pair of streams per seed.

Coloured load (the open question of paper §6): the impulses pass a first-order low-pass
filter, ``p_n = c p_{n-1} + sqrt(1 - c^2) w_n`` with ``w_n`` the white impulses, which keeps
their standard deviation ``sigma_p``, gives them the autocorrelation ``c^m`` at lag ``m``
and puts the corner at ``f_c = -ln(c) / (2 pi dt)``; :meth:`rockdec.physics.record_model.Load.pole`
gives ``c`` for a corner set in rocking frequencies.

Load of a given spectrum (:class:`ImpulseSpectrum`, a table of the one-sided power spectral
density in cycles per step; only its shape matters): circulant embedding. The series of
``n`` impulses is the first ``n`` samples of a periodic one of ``M`` samples: ``M``
standard normal numbers of the series' stream, transformed, multiplied by the gain
``sqrt(S(k/M))`` of each frequency bin, transformed back. The gains are scaled so that the
mean of ``S`` over the ``M`` bins is 1, so the impulses have the standard deviation
``sigma_p`` and, at lag ``m < n``, the autocorrelation ``sum_k S(k/M) cos(2 pi k m/M) / M``,
the inverse transform of the spectrum, up to the wrap-around ``r(M - m)``.
:func:`embedding_size` makes that term smaller than :data:`WRAP_TOLERANCE`: ``M`` is the next
fast length (``scipy.fft.next_fast_len``) of ``n + L``, ``L`` the lag (at most ``n``) beyond
which the autocorrelation stays below it, so a short correlation costs little more than
``n`` numbers and a long one at most ``2n``.
``S`` between the table's rows is interpolated linearly in ``log f``; a row at ``f = 0`` sets
the constant bin and is joined to the first positive row linearly in ``f``; outside the table
``S = 0`` (the table states where the power is), and rows above the Nyquist frequency
(half a cycle per step) are not drawn. A spectrum is drawn for the whole series at once.

Every simulator (the simplified model, the Housner model, the fixed-step integrator) draws
its impulses here, so one seed means one load whatever the model.
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numba
import numpy as np

from rockdec.validate import InputError

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


class ImpulseSpectrum(NamedTuple):
    """A load spectrum as the simulators draw it: ``frequency`` in cycles per step (ascending,
    ``>= 0``) and the one-sided power spectral density ``psd`` (``>= 0``, any scale) there;
    :meth:`rockdec.physics.record_model.Load.draw_options` places a scene's table at its sampling."""

    frequency: tuple
    psd: tuple


WRAP_TOLERANCE = 1e-4
"""Largest autocorrelation the circulant embedding may wrap around (:func:`embedding_size`)."""


@functools.lru_cache(maxsize=16)
def embedding_size(spectrum: ImpulseSpectrum, n: int) -> int:
    """Length ``M`` of the periodic series whose first ``n`` samples are ``n`` impulses of
    ``spectrum``: the next fast length of ``n + L``, ``L`` the last lag up to ``n`` at which the
    autocorrelation (at ``M = 2n``) exceeds :data:`WRAP_TOLERANCE`, plus one."""
    from scipy import fft

    trial = fft.next_fast_len(2 * n, real=True)
    acf = np.abs(fft.irfft(spectral_gain(spectrum, trial) ** 2, n=trial)[: n + 1])
    lag = int(np.flatnonzero(acf > WRAP_TOLERANCE)[-1]) + 1  # acf[0] = 1
    return fft.next_fast_len(n + lag, real=True)


@functools.lru_cache(maxsize=16)
def spectral_gain(spectrum: ImpulseSpectrum, size: int) -> np.ndarray:
    """Gains ``sqrt(S(k/size))`` of the ``size // 2 + 1`` bins of a real transform of ``size``
    points (module docstring), scaled so that ``S`` averages 1 over the ``size`` bins of the circle."""
    f, s = np.asarray(spectrum.frequency, dtype=np.float64), np.asarray(spectrum.psd, dtype=np.float64)
    if not (f.size >= 2 and f.size == s.size and np.all(np.diff(f) > 0) and f[0] >= 0 and np.all(np.isfinite(s)) and s.min() >= 0
            and s.max() > 0):
        raise InputError(
            f"the load spectrum ({f.size} rows from {f[0]:.3g} to {f[-1]:.3g} cycles per step) is not a table of ascending "
            "frequencies >= 0 and PSD values >= 0, not all 0; give such a table (rockdec.physics.record_model.Load checks one)"
        )
    s = s / s.max()  # only the shape counts; no overflow in the mean below
    bins = np.arange(size // 2 + 1) / size
    power = np.zeros(bins.size)
    pos = f > 0.0
    inside = bins > 0.0
    power[inside] = np.interp(np.log(bins[inside]), np.log(f[pos]), s[pos], left=0.0, right=0.0)
    if f[0] == 0.0:
        below = bins < f[pos][0]
        power[below] = np.interp(bins[below], f[:2], s[:2])
    weights = np.full(bins.size, 2.0)
    weights[0] = 1.0
    if size % 2 == 0:
        weights[-1] = 1.0
    mean = float(np.dot(weights, power)) / size
    if not mean > 0.0:
        raise InputError(
            f"the load spectrum (rows from {f[0]:.3g} to {f[-1]:.3g} cycles per step) holds no power between 0 and the "
            "Nyquist frequency of 0.5 cycles per step of this simulation; give a table that covers the rocking band"
        )
    gain = np.sqrt(power / mean)
    gain.flags.writeable = False  # shared by every caller of the cache
    return gain


def _draw_spectrum(rng: np.random.Generator, out: np.ndarray, spectrum: ImpulseSpectrum) -> None:
    """Unit-variance impulses of ``spectrum`` into ``out`` by circulant embedding (module docstring)."""
    from scipy import fft

    size = embedding_size(spectrum, out.size)
    white = rng.standard_normal(size)
    out[:] = fft.irfft(fft.rfft(white) * spectral_gain(spectrum, size), n=size)[: out.size]


def draw_impulses(rng: np.random.Generator, out: np.ndarray, sigma_p: float, pole: float = 0.0,
                  spectrum: ImpulseSpectrum | None = None) -> np.ndarray:
    """Fill ``out`` with the next impulses ``p_n ~ N(0, sigma_p^2)`` (rad/s) of ``rng``.

    ``sigma_p = 0`` gives zeros (a free response) and draws nothing. Drawing a series in
    blocks continues the same stream, so white blocks concatenate to the whole series.
    ``pole`` ``c`` in ``[0, 1)``: the low-pass filtered load of the module docstring
    (:func:`low_pass`), started stationary (``p_0 = sigma_p w_0``); ``0`` is white noise.
    ``spectrum``: impulses of that spectrum instead (:class:`ImpulseSpectrum`, circulant
    embedding of the module docstring), ``out`` being the whole series.
    """
    if not 0.0 <= pole < 1.0:
        raise InputError(f"load pole {pole}: not in [0, 1); give the low-pass filter's pole, or draw a spectrum load with spectrum=")
    if spectrum is not None and pole > 0.0:
        raise InputError("a load is either low-pass filtered (pole) or of a given spectrum, not both; give one of them")
    if sigma_p > 0.0:
        if spectrum is not None:
            if out.size:
                _draw_spectrum(rng, out, spectrum)
        else:
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

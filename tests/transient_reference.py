"""An independent generator of rocking records under a transient base load, and their stationary twin.

Not the project's simulator: it steps the simplified rocking model
``theta'' = -g sign(theta) + a(t)`` sample by sample, ``a`` (the base's acceleration in rad/s^2 of
the block) held over each sample, on the exact parabolic flights between zero crossings, where
the angular velocity is multiplied by ``e``. The transient's base acceleration is Clough-Penzien
filtered white noise times a build-up / strong / decay envelope, then zero for the free decay
(an earthquake or a shake-table test); the stationary twin's is white noise of constant strength.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import signal

__all__ = ["FS", "G", "stationary", "transient"]

#: Sampling (Hz) and the block's ``g`` (rad/s^2): a cycle of 0.01 rad lasts 0.4 s, 80 samples.
FS, G = 200.0, 2.0

#: A rebound slower than this (rad/s) leaves the block at rest (the chatter's remaining bounces).
REST_SPEED = 1e-9


def _step(theta: float, omega: float, a: float, dt: float, g: float, e: float) -> tuple[float, float]:
    """The state after ``dt`` under the constant base acceleration ``a``."""
    left = dt
    for _ in range(100_000):
        if theta == 0.0 and omega == 0.0:
            if abs(a) <= g:
                return 0.0, 0.0
            side = math.copysign(1.0, a)
        else:
            side = math.copysign(1.0, theta) if theta != 0.0 else math.copysign(1.0, omega)
        h, u, b = side * theta, side * omega, -g + side * a  # height, speed and acceleration away from zero
        t = math.inf
        if b < 0.0:
            t = (u + math.sqrt(max(u * u - 2.0 * b * h, 0.0))) / -b
        elif u < 0.0 and u * u - 2.0 * b * h >= 0.0:
            t = (-u - math.sqrt(u * u - 2.0 * b * h)) / b if b > 0.0 else h / -u
        if t >= left:
            return side * (h + u * left + 0.5 * b * left * left), side * (u + b * left)
        left -= t
        rebound = e * (u + b * t)  # <= 0: towards the other side
        theta, omega = 0.0, (side * rebound if -rebound > REST_SPEED else 0.0)
    raise RuntimeError("the block chatters without end")


def _rock(a: np.ndarray, e: float, g: float = G, fs: float = FS, substeps: int = 0) -> np.ndarray:
    """The rocking angle at each sample under the base acceleration ``a`` (one value per
    sample): held over each sample (``substeps`` 0), or linear between samples, read at the
    midpoints of ``substeps`` equal steps of each sample."""
    out = np.empty(a.size)
    theta = omega = 0.0
    dt = 1.0 / fs
    if substeps:
        mid = (np.arange(substeps) + 0.5) / substeps
        for i, ai in enumerate(a):
            out[i] = theta
            for ak in ai + mid * ((a[i + 1] if i + 1 < a.size else ai) - ai):
                theta, omega = _step(theta, omega, float(ak), dt / substeps, g, e)
        return out
    for i, ai in enumerate(a):
        out[i] = theta
        theta, omega = _step(theta, omega, float(ai), dt, g, e)
    return out


def _clough_penzien(n: int, rng: np.random.Generator, fs: float, f_g: float = 5.0, zeta_g: float = 0.6, f_f: float = 0.5,
                    zeta_f: float = 0.6) -> np.ndarray:
    """Clough-Penzien filtered white noise, unit std: the Kanai-Tajimi ground filter (frequency
    ``f_g`` Hz, damping ``zeta_g``) and a second-order high-pass (``f_f``, ``zeta_f``) that takes
    out the ground's slowest motion."""
    w, wf = 2.0 * math.pi * f_g, 2.0 * math.pi * f_f
    b, a = signal.bilinear([2.0 * zeta_g * w, w * w], [1.0, 2.0 * zeta_g * w, w * w], fs)
    x = signal.lfilter(b, a, rng.standard_normal(n))
    b, a = signal.bilinear([1.0, 0.0, 0.0], [1.0, 2.0 * zeta_f * wf, wf * wf], fs)
    x = signal.lfilter(b, a, x)
    return x / x.std()


def _noisy(theta: np.ndarray, noise: float, rng: np.random.Generator) -> np.ndarray:
    """``theta`` with sensor noise of ``noise`` times its std."""
    return theta + noise * theta.std() * rng.standard_normal(theta.size) if noise else theta


def transient(e: float, seed: int, *, strong: float = 20.0, free: float = 20.0, peak: float = 0.8, noise: float = 0.01,
              fs: float = FS) -> np.ndarray:
    """A record of an earthquake or shake-table test: ``strong`` s of shaking (a 20 % build-up
    as ``t^2``, a strong phase, a decay over the last 30 %) of Clough-Penzien noise peaking at
    ``peak`` times ``g`` in std, then ``free`` s of free decay from the block's last state; sensor
    noise ``noise`` times the record's std."""
    return transient_with_base(e, seed, strong=strong, free=free, peak=peak, noise=noise, fs=fs)[0]


def transient_with_base(e: float, seed: int, *, strong: float = 20.0, free: float = 20.0, peak: float = 0.8, noise: float = 0.01,
                        fs: float = FS, residual: float = 0.0, substeps: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """The record of :func:`transient` and the base acceleration that made it (rad/s^2, the
    simplified rocking equation's load; the block lifts above ``G``). ``residual``: the base
    keeps moving in the free part, white noise uniform in ``+-residual G`` (drawn from its own
    stream, so the shaking and the sensor noise stay those of ``residual = 0``). ``substeps``:
    as :func:`_rock` (0: the base held over each sample)."""
    rng = np.random.default_rng(seed)
    n_shake, n_free = int(strong * fs), int(free * fs)
    t = np.arange(n_shake) / n_shake
    envelope = np.where(t < 0.2, (t / 0.2) ** 2, np.where(t < 0.7, 1.0, np.exp(-8.0 * (t - 0.7))))
    tail = residual * G * np.random.default_rng([seed, 1]).uniform(-1.0, 1.0, n_free) if residual else np.zeros(n_free)
    a = np.concatenate([peak * G * envelope * _clough_penzien(n_shake, rng, fs), tail])
    return _noisy(_rock(a, e, G, fs, substeps), noise, rng), a


def stationary(e: float, seed: int, *, seconds: float = 100.0, strength: float = 3.0, noise: float = 0.01,
               fs: float = FS) -> np.ndarray:
    """A stationary twin: white base noise of ``strength`` times ``g`` in std for ``seconds`` s
    (its first 10 s, the block's start from rest, dropped); sensor noise as :func:`transient`."""
    rng = np.random.default_rng(seed)
    skip = int(10.0 * fs)
    a = strength * G * rng.standard_normal(int(seconds * fs) + skip)
    return _noisy(_rock(a, e, G, fs)[skip:], noise, rng)

"""Earthquake-like base motions and the simplified block's response to them: the shake-table
tests of the demonstration campaign.

The ground acceleration is white noise shaped by the Kanai-Tajimi ground filter (frequency
``f_g``, damping ``zeta_g``) and a second-order high-pass that takes out its slowest motion
(the Clough-Penzien correction), synthesised in the frequency domain, then multiplied by a
build-up / strong / decay envelope over the shaking; the rest of the record is the free
decay, the base at rest. The block answers as the simplified model (eq. 4) with the base
acceleration as its load, each sample's acceleration given as a velocity impulse
(:func:`rockdec.physics.simulate.integrate`, eqs. 21-24). Entry point: :func:`shake_test`.
"""

from __future__ import annotations

import numpy as np

from rockdec import validate as checks
from rockdec.physics.loading import add_sensor_noise, series_rng
from rockdec.physics.models import check_finite_series, check_run
from rockdec.physics.simulate import integrate

__all__ = ["envelope", "ground_gain", "ground_motion", "shake_test"]

#: The ground filter (Hz and damping) and its high-pass (Hz and damping): a firm soil's.
GROUND = {"f_g": 5.0, "zeta_g": 0.6, "f_f": 0.5, "zeta_f": 0.6}

#: Shares of the shaking taken by the build-up and by the strong motion; the decay's rate.
BUILD_UP, STRONG, DECAY_RATE = 0.2, 0.5, 8.0


def ground_gain(f, f_g: float, zeta_g: float, f_f: float, zeta_f: float) -> np.ndarray:
    """Amplitude of the Clough-Penzien filter at the frequencies ``f`` (Hz): the Kanai-Tajimi
    ground filter times the high-pass.

    Examples
    --------
    >>> ground_gain([0.0, 5.0], 5.0, 0.6, 0.5, 0.6).round(3).tolist()
    [0.0, 1.305]
    """
    r = np.asarray(f, dtype=float) / f_g
    kanai = (1.0 + (2.0 * zeta_g * r) ** 2) / ((1.0 - r * r) ** 2 + (2.0 * zeta_g * r) ** 2)
    s = np.asarray(f, dtype=float) / f_f
    high = s**4 / ((1.0 - s * s) ** 2 + (2.0 * zeta_f * s) ** 2)
    return np.sqrt(kanai * high)


def envelope(n: int) -> np.ndarray:
    """The shaking's envelope over ``n`` samples: a quadratic build-up over :data:`BUILD_UP` of
    them, the strong motion over :data:`STRONG`, then an exponential decay.

    Examples
    --------
    >>> envelope(10).round(2).tolist()
    [0.0, 0.25, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 0.45, 0.2]
    """
    t = np.arange(n) / n
    strong_end = BUILD_UP + STRONG
    return np.where(t < BUILD_UP, (t / BUILD_UP) ** 2, np.where(t < strong_end, 1.0, np.exp(-DECAY_RATE * (t - strong_end))))


def ground_motion(n_points: int, dt: float, seed: int, *, peak: float, g: float = 1.0, shaking: float = 0.5) -> np.ndarray:
    """A base acceleration of ``n_points`` samples every ``dt`` s (rad/s^2, the simplified
    model's load): filtered noise (:func:`ground_gain`, :data:`GROUND`) of standard deviation
    ``peak * g`` in its strong motion, under :func:`envelope` over the first ``shaking`` of the
    record, zero after it.

    Examples
    --------
    >>> a = ground_motion(8_000, 0.005, 1, peak=1.5)
    >>> round(float(a[800:2800].std()), 1), float(abs(a[4000:]).max())
    (1.5, 0.0)
    """
    n_shake = int(round(shaking * n_points))
    if not 0 < n_shake <= n_points:
        raise checks.InputError(f"a shaking of {shaking:g} of {n_points} samples holds no sample; give 0 < shaking <= 1.")
    white = series_rng(seed).standard_normal(n_shake)
    f = np.fft.rfftfreq(n_shake, dt)
    shaped = np.fft.irfft(np.fft.rfft(white) * ground_gain(f, **GROUND), n_shake)
    shaped *= peak * g / shaped.std()
    return np.concatenate([shaped * envelope(n_shake), np.zeros(n_points - n_shake)])


def shake_test(e: float, n_points: int, dt: float, seed: int, *, peak: float, g: float = 1.0, noise: float = 0.0,
               shaking: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    """A shake-table test of the simplified block (eq. 4, restitution ``e``, restoring
    acceleration ``g`` in rad/s^2) at rest under :func:`ground_motion`: ``(theta, base)``, the
    angle in rad with white sensor noise of ``noise`` times its largest value, and the base.

    Examples
    --------
    >>> theta, base = shake_test(0.9, 8_000, 0.005, 2, peak=1.5)
    >>> bool(abs(theta[:4000]).max() > 1e-3), float(abs(theta[-100:]).max()) < 1e-9
    (True, True)
    """
    check_run(dt=dt, e=e, sigma_p=0.0, theta0=0.0, theta_dot0=0.0, burn_in=0, n_points=n_points)
    checks.positive(g, "g", "give the restoring acceleration nu^2 theta_cr in rad/s^2, > 0")
    checks.positive(peak, "peak", "give the shaking's strength in uplift levels, > 0")
    base = ground_motion(n_points, dt, seed, peak=peak, g=g, shaking=shaking)
    theta, omega = np.zeros((1, n_points)), np.zeros((1, n_points))
    integrate(-base[:-1] * dt, dt, g, e, 0.0, 0.0, 0, theta[0], omega[0])
    check_finite_series(np.stack([theta[:, -1], omega[:, -1]]), f"the shake-table test at dt = {dt}, g = {g}, peak = {peak}")
    add_sensor_noise(theta, [seed], noise * float(np.abs(theta).max()))
    return theta[0], base

"""Loss in flight (``theta'' = -g sign(theta) - c theta'``): the closed-form arcs of
:mod:`rockdec.free.flight_loss` against a numerical integration, and the free-rocking
analysis on records of an independent generator (tests/free/damped_reference.py): the
score test's false alarms on ideal records, and ``e`` and ``c`` held by their intervals when
the block loses speed in flight."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from damped_reference import damped_release
from rockdec.free import arcs, flight_loss
from rockdec.free.analysis import analyse_free_rocking


def integrate(g, c, h0, v0, T):
    """``h'' = -g - c h'`` from ``(h0, v0)`` to time ``T``, dense."""
    return solve_ivp(lambda t, y: [y[1], -g - c * y[1]], (0.0, T), [h0, v0], method="DOP853", rtol=1e-13, atol=1e-16,
                     dense_output=True).sol


@pytest.mark.parametrize("c", [-0.3, 1e-7, 0.004, 0.0101, 0.7, 3.0])
def test_flight_and_fall_follow_the_equation_of_motion(c):
    """A flight that leaves at the closed form's speed comes back to zero at ``T`` landing at
    its other speed, at every height; the fall from the closed form's height lands at ``T0``."""
    g, T, T0 = 1.3, 0.9, 0.6
    leave, land = flight_loss.speeds(T, g, c)
    sol = integrate(g, c, 0.0, float(leave), T)
    tau = np.linspace(0.0, T, 11)
    np.testing.assert_allclose(flight_loss.flight_height(tau, T, g, c), sol(tau)[0], atol=1e-12 * g * T**2)
    assert -sol(T)[1] == pytest.approx(float(land), rel=1e-10)
    height = float(flight_loss.fall_height(T0, T0, g, c))
    fall = integrate(g, c, height, 0.0, T0)
    s = np.linspace(0.0, T0, 7)
    np.testing.assert_allclose(flight_loss.fall_height(s, T0, g, c), fall(T0 - s)[0], atol=1e-12 * g * T0**2)


def test_no_loss_is_the_parabola_and_the_series_meets_the_exponentials():
    g, T = 2.0, 0.5
    tau = np.linspace(0.0, T, 9)
    np.testing.assert_allclose(flight_loss.flight_height(tau, T, g, 0.0), 0.5 * g * tau * (T - tau), rtol=1e-14, atol=1e-16)
    assert [float(v) for v in flight_loss.speeds(T, g, 0.0)] == pytest.approx([g * T / 2] * 2, rel=1e-15)
    edge = flight_loss.SERIES_BELOW / T
    below, above = (flight_loss.flight_height(tau, T, g, edge * f) for f in (1 - 1e-9, 1 + 1e-9))
    np.testing.assert_allclose(below, above, rtol=1e-11, atol=1e-16)


@pytest.mark.slow
def test_ideal_blocks_rarely_get_a_loss_in_flight():
    """Forty ideal releases (c = 0, 0.5 % sensor noise): the score test fires by chance on
    about 2.5 % (LOSS_Z, one-sided); 5 or more of 40 has a chance of 0.7 % at that rate."""
    chosen = held = 0
    for seed in range(40):
        y, dt, _ = damped_release(0.9, 0.0, noise=0.005, seed=seed)
        fit = analyse_free_rocking(y, dt)
        chosen += fit.loss_in_flight
        held += fit.e_interval[0] <= 0.9 <= fit.e_interval[1]
    assert chosen <= 4 and held >= 35, (chosen, held)


@pytest.mark.slow
def test_a_loss_in_flight_is_found_and_e_is_the_impacts_share():
    """Ten releases with c = 0.15 /s and e = 0.9 at impact (0.5 % noise): the loss is found,
    and e and c are each held by their intervals (the one-e fit misses e confidently on
    every one of them)."""
    chosen = e_held = c_held = 0
    for seed in range(10):
        y, dt, _ = damped_release(0.9, 0.15, noise=0.005, seed=seed)
        fit = analyse_free_rocking(y, dt)
        chosen += fit.loss_in_flight
        e_held += fit.e_interval[0] <= 0.9 <= fit.e_interval[1]
        c_held += fit.flight_loss_interval[0] <= 0.15 <= fit.flight_loss_interval[1]
    assert chosen >= 9 and e_held >= 8 and c_held >= 8, (chosen, e_held, c_held)
    assert any("loses speed in flight" in note for note in fit.notes)


@pytest.mark.slow
def test_a_loss_in_flight_leaves_the_time_and_angle_scales_invariant():
    y, dt, _ = damped_release(0.9, 0.15, noise=0.005, seed=3)
    a = analyse_free_rocking(y, dt)
    b = analyse_free_rocking(7.0 * y, dt / 3.0)
    assert a.loss_in_flight and b.loss_in_flight
    assert b.e == pytest.approx(a.e, rel=1e-6) and b.flight_loss == pytest.approx(3.0 * a.flight_loss, rel=1e-5)
    assert math.isfinite(a.flight_loss_interval[0])


def test_a_release_whose_score_is_unread_starts_its_fit_at_no_loss():
    """A release whose score test could not read ``c`` (NaN: its loss column is explained by
    the arcs alone) is fitted from ``c = 0``, as it would be with that guess, instead of
    stopping the analysis with non-finite residuals."""
    tt = np.linspace(0.0, 1.5, 61)
    yy = np.where(tt < 0.5, 0.25 - tt**2, -(tt - 0.5) * (1.5 - tt))
    first = arcs.fit_sequence(tt, yy, side=1, times0=[0.0, 0.5, 1.5], q0=2.0, model="simplified", theta_cr=None)
    unread, zero = flight_loss.fit_sequence(tt, yy, first, c0=math.nan), flight_loss.fit_sequence(tt, yy, first, c0=0.0)
    assert unread.g == zero.g and unread.c == zero.c and np.array_equal(unread.times, zero.times)


@pytest.mark.parametrize("c", [50.0, 800.0, 1e4])
def test_a_fall_with_a_large_loss_stays_finite_and_below_the_lossless_fall(c):
    """``c T0`` past ~700 overflowed ``expm1`` (inf times 0: NaN) and stopped the fit of a
    release whose score guessed such a loss (met in the shake study). The fall is finite,
    rises from 0, and a loss only lowers it."""
    s = np.linspace(0.0, 2.0, 9)
    h = flight_loss.fall_height(s, 2.0, 2.0, c)
    assert np.all(np.isfinite(h)) and h[0] == 0.0 and np.all(np.diff(h) > 0)
    assert np.all(h <= flight_loss.fall_height(s, 2.0, 2.0, 0.0) + 1e-15)

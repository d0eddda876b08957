"""The exact simulator against closed forms, its reference, and its invariants (docs/method.md §3)."""

import math

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from rockdec.physics import simulate
from long_series import long_series
from rocking_reference import flight_reference

G = 1.0


def analytic_free_response(t, a, g, e):
    """Free rocking from (a, 0) at t = 0 (eqs. 4, 6): parabolas, speed times e at each impact.

    First crossing at t1 = sqrt(2a/g) with speed g t1; flight k >= 1 starts at T_k with
    speed e^k g t1, lasts 2 e^k t1, on side (-1)^k; rest from t1 (1 + e)/(1 - e).
    """
    t = np.asarray(t, dtype=float)
    t1 = math.sqrt(2 * a / g)
    out = np.where(t <= t1, a - 0.5 * g * t**2, 0.0)
    start, k = t1, 1
    while e > 0 and e**k * t1 > 1e-300 and start < t.max():
        speed, length = e**k * g * t1, 2 * e**k * t1
        inside = (t > start) & (t <= start + length)
        s = t[inside] - start
        out[inside] = (-1) ** k * (speed * s - 0.5 * g * s**2)
        start, k = start + length, k + 1
    return out


def free_run(a, e, dt, n):
    theta, theta_dot = simulate.simulate_block([0], n, dt=dt, g=G, e=e, sigma_p=0.0, theta0=a)
    return theta[0], theta_dot[0]


@pytest.mark.parametrize("e", [0.3, 0.5, 0.8, 0.95, 0.99])
def test_free_response_matches_parabolas(e):
    a = 0.7
    t1 = math.sqrt(2 * a / G)
    dt = t1 / 37.3
    n = int(6 * t1 / dt)
    theta, _ = free_run(a, e, dt, n)
    expected = analytic_free_response(np.arange(n) * dt, a, G, e)
    np.testing.assert_allclose(theta, expected, rtol=0, atol=1e-12 * a)


@pytest.mark.parametrize("e", [0.5, 0.95])
def test_first_minimum_is_minus_e_squared_a_at_one_plus_e_t1(e):
    a = 1.3
    t1 = math.sqrt(2 * a / G)
    t2 = (1 + e) * t1
    # one step that ends exactly at t2: minimum value, zero velocity
    theta, omega = simulate.flight(a, 0.0, t2, G, e)
    assert theta == pytest.approx(-(e**2) * a, rel=1e-12)
    assert abs(omega) < 1e-12 * G * t1


@pytest.mark.parametrize("e", [0.1, 0.5, 0.9, 0.999])
def test_rest_reached_at_geometric_series_sum(e):
    a = 0.4
    t1 = math.sqrt(2 * a / G)
    t_rest = t1 * (1 + e) / (1 - e)
    # just before rest it still moves; just after (one step holding thousands of impacts) it rests
    before = simulate.flight(a, 0.0, t_rest * (1 - 1e-9), G, e)
    after = simulate.flight(a, 0.0, t_rest * (1 + 1e-9), G, e)
    assert before != (0.0, 0.0)
    assert after == (0.0, 0.0)


def test_landing_exactly_at_the_end_of_a_step_is_restituted():
    # impact at t = 0 with speed 0.5 -> 0.25 up, back at zero at t = 2 * 0.25 / g = 0.5 = dt:
    # that landing is an impact too (otherwise the next step would cross unrestituted)
    theta, omega = simulate.flight(-1e-300, 0.5, 0.5, G, 0.5)
    assert theta == 0.0 and omega == pytest.approx(-0.125, rel=1e-12)


def test_many_impacts_in_one_step_do_not_hang():
    # e close to 1 and a tiny rebound speed: ~1e10 bounces inside one step
    theta, omega = simulate.flight(0.0, 1e-10, 1.0, G, 1.0 - 1e-9)
    assert np.isfinite(theta) and np.isfinite(omega)
    assert abs(theta) <= 0.5 * 1e-20 / G * 1.0001  # bounce height (v^2 / 2g) bounds it
    theta, omega = simulate.flight(0.0, 1e-10, 1.0, G, 1.0)
    assert abs(omega) == pytest.approx(1e-10, rel=1e-6)  # e = 1 keeps the speed


def test_e_equal_one_conserves_energy():
    a = 0.5
    t1 = math.sqrt(2 * a / G)
    theta, theta_dot = free_run(a, 1.0, t1 / 20.3, 4000)
    energy = 0.5 * theta_dot**2 + G * np.abs(theta)
    np.testing.assert_allclose(energy, G * a, rtol=1e-10)


def test_e_zero_rests_at_first_impact():
    a = 0.5
    t1 = math.sqrt(2 * a / G)
    dt = t1 / 10.5
    theta, theta_dot = free_run(a, 0.0, dt, 40)
    first_after = int(math.ceil(t1 / dt))
    assert np.all(theta[first_after:] == 0.0) and np.all(theta_dot[first_after:] == 0.0)
    assert np.all(theta[:first_after] > 0)


@pytest.mark.parametrize("e", [1e-12, 1.0 - 1e-12])
def test_extreme_restitution_behaves(e):
    a = 0.5
    t1 = math.sqrt(2 * a / G)
    theta, theta_dot = free_run(a, e, t1 / 10.5, 400)
    assert np.all(np.isfinite(theta))
    if e < 0.5:  # first rebound 1e-12 of the speed: at rest within the step of the impact
        assert np.all(theta[11:] == 0.0)
    else:  # essentially lossless: the energy stays at its start value to ~1e-9
        energy = 0.5 * theta_dot**2 + G * np.abs(theta)
        np.testing.assert_allclose(energy, G * a, rtol=1e-8)


@settings(max_examples=400, deadline=None)
@given(
    theta=st.floats(-1.0, 1.0),
    omega=st.floats(-1.0, 1.0),
    duration=st.floats(1e-6, 3.0),
    e=st.one_of(st.floats(0.0, 0.99), st.just(1.0)),
)
@example(theta=-2.772155391678588e-203, omega=0.5, duration=0.5, e=0.5)  # lands exactly at the end
def test_compiled_step_equals_reference_step(theta, omega, duration, e):
    # the reference walks impact by impact: keep the count of bounces it must walk small
    if e > 0.99 and abs(omega) + math.sqrt(2 * G * abs(theta)) < 1e-3:
        return
    got = simulate.flight(theta, omega, duration, G, e)
    want = flight_reference(theta, omega, duration, G, e)
    # rounding differs (closed-form bounce count vs one impact at a time); scale of the motion:
    scale = abs(theta) + abs(omega) * duration + G * duration**2 + 1e-300
    assert got[0] == pytest.approx(want[0], rel=1e-9, abs=1e-9 * scale)
    assert got[1] == pytest.approx(want[1], rel=1e-9, abs=1e-9 * (abs(omega) + G * duration))


def test_scale_invariance_sigma_p_times_k_scales_response_by_k_squared():
    # At fixed g, sigma_p -> k sigma_p with dt -> k dt keeps dt g / sigma_p; theta -> k^2 theta.
    dt, sigma_p, e = 0.01, 0.003, 0.95
    base, _ = simulate.simulate_block([5, 6], 3000, dt=dt, g=G, e=e, sigma_p=sigma_p, burn_in=500)
    for k in (4.0, 2.0**-10):  # powers of two scale every operation exactly: bit for bit
        scaled, _ = simulate.simulate_block([5, 6], 3000, dt=k * dt, g=G, e=e, sigma_p=k * sigma_p, burn_in=500)
        np.testing.assert_array_equal(scaled, k**2 * base)
    # Any other k: equal to rounding over a short stretch only. The forced rocker is chaotic:
    # rounding differences of 1e-16 grow to 1e-12 of the amplitude within about 60 steps.
    k = 3.0
    scaled, _ = simulate.simulate_block([5, 6], 40, dt=k * dt, g=G, e=e, sigma_p=k * sigma_p)
    short, _ = simulate.simulate_block([5, 6], 40, dt=dt, g=G, e=e, sigma_p=sigma_p)
    np.testing.assert_allclose(scaled, k**2 * short, rtol=0, atol=1e-12 * np.abs(k**2 * short).max())


def test_seed_alone_equals_seed_inside_a_chunked_run():
    kwargs = dict(dt=0.01, g=G, e=0.95, sigma_p=0.003, burn_in=200)
    alone = simulate.simulation_dataset([3, 7], 1500, chunk_seeds=1, **kwargs).theta.values
    many = simulate.simulation_dataset(np.arange(10), 1500, chunk_seeds=3, **kwargs)
    np.testing.assert_array_equal(alone, many.theta.sel(seed=[3, 7]).values)


def test_default_burn_in_gives_a_stationary_record():
    """Started at rest, the ensemble variance grows; after the default burn-in it is flat.

    Over 2000 seeds, the mean square of the first 500 and the last 1000 samples of the recorded series
    agree within their standard errors (3 sigma), while without burn-in the first third is
    far below the last.
    """
    e, ppc = 0.95, 75.0
    cal = simulate.calibrate_dt(e=e, g=G, sigma_p=0.003, points_per_cycle=ppc, pilot_seeds=64, pilot_points=20_000)

    def first_vs_last(burn_in):
        theta, _ = simulate.simulate_block(np.arange(2000), 3000, dt=cal["dt"], g=G, e=e, sigma_p=0.003, burn_in=burn_in)
        first, last = (np.mean(theta[:, s] ** 2, axis=1) for s in (slice(0, 500), slice(2000, 3000)))
        diff = first - last
        return diff.mean(), diff.std(ddof=1) / math.sqrt(diff.size), last.mean()

    mean_diff, se, level = first_vs_last(simulate.default_burn_in(e, ppc))
    assert abs(mean_diff) < 3 * se
    mean_diff0, se0, level0 = first_vs_last(0)
    assert mean_diff0 < -5 * se0  # the test can tell: no burn-in is visibly non-stationary


def test_calibration_hits_points_per_cycle_and_refuses_e_one():
    cal = simulate.calibrate_dt(e=0.95, g=G, sigma_p=0.003, points_per_cycle=75.0)
    assert cal["points_per_cycle"] == pytest.approx(75.0, rel=0.05)  # pilot sigma_Y is good to ~2 %
    with pytest.raises(ValueError, match="no energy"):
        simulate.calibrate_dt(e=1.0, g=G, sigma_p=0.003)


@pytest.mark.parametrize("chunk", [1, 999, 10_007, 50_000])
def test_long_series_in_time_chunks_equals_the_whole_series(chunk):
    kwargs = dict(dt=0.0034, g=G, e=0.95, sigma_p=0.003, burn_in=500)
    whole = simulate.simulate_block([4], 10_007, **kwargs)[0][0]
    blocks = list(long_series(4, 10_007, chunk, **kwargs))
    assert all(b[0].size <= chunk for b in blocks)
    np.testing.assert_array_equal(np.concatenate([b[0] for b in blocks]), whole)


@pytest.mark.parametrize("gap", [False, True])
def test_pilot_statistics_are_the_nan_means_of_the_squares_bit_for_bit(gap):
    """sigma_y and sigma_ydot: the root of np.nanmean of the squares (a NaN sample left out),
    to the last bit, whichever way the mean is formed."""
    theta = np.random.default_rng(3).standard_normal((7, 5001)) * 1e-3
    if gap:
        theta[2, 100:140] = np.nan
    dt = 0.0034
    stats = simulate.pilot_statistics(theta, dt, 1.0)
    assert stats["sigma_y"] == float(np.sqrt(np.nanmean(theta**2)))
    assert stats["sigma_ydot"] == float(np.sqrt(np.nanmean((np.diff(theta, axis=-1) / dt) ** 2)))
    assert math.isfinite(stats["sigma_y"]) and math.isfinite(stats["sigma_ydot"])


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_pilot_statistics_are_the_plain_expressions_bit_for_bit(dtype):
    """sqrt(mean(theta**2)) and sqrt(mean((diff(theta)/dt)**2)), NaN left out, whether the
    arithmetic runs in a scratch array (C-ordered float64) or as written (float32, other orders)."""
    rng = np.random.default_rng(7)
    theta = (0.002 * rng.standard_normal((6, 5001))).astype(dtype)
    for case in (theta, np.asfortranarray(theta), np.where(np.arange(5001) == 17, np.nan, theta).astype(dtype)):
        stats = simulate.pilot_statistics(case, 0.0034, 1.0)
        squares, slopes = case**2, (np.diff(case, axis=-1) / 0.0034) ** 2
        expected = [np.sqrt(np.nanmean(x) if np.isnan(x).any() else np.mean(x)) for x in (squares, slopes)]
        assert [stats["sigma_y"], stats["sigma_ydot"]] == [float(x) for x in expected]

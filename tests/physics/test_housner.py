"""The linearized Housner simulator (paper eqs. 2, 3, 6) against closed forms, the simplified
model in its small-amplitude limit, an impact-by-impact reference, and its invariants."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

from rockdec.physics import housner, loading, models, simulate

NU, THETA_CR = 3.0, 0.15
C = NU * THETA_CR  # speed that just reaches theta_cr from theta = 0
G = models.restoring_acceleration(NU, THETA_CR)  # eq. 4 limit: g = nu^2 theta_cr


def flight(theta, omega, duration, e):
    return housner.housner_flight(theta, omega, duration, NU, THETA_CR, e)


def energy(theta, omega):
    """Conserved between impacts: ``omega^2/2 - nu^2 (theta^2/2 - theta_cr |theta|)``."""
    return 0.5 * omega**2 - NU**2 * (0.5 * theta**2 - THETA_CR * np.abs(theta))


def first_crossing(ratio):
    """Eq. 2 from rest at theta0 = ratio theta_cr reaches zero at acosh(1/(1 - ratio))/nu."""
    return math.acosh(1.0 / (1.0 - ratio)) / NU


def bounce(speed):
    """A flight from theta = 0 with ``speed < C`` returns after ``(2/nu) atanh(speed/C)``."""
    return 2.0 * math.atanh(speed / C) / NU


# ---------------------------------------------------------------- an independent reference


def reference_flight(theta, omega, duration, e, max_impacts=100_000):
    """Impact by impact, each crossing found by brentq on the cosh/sinh arc (no closed-form
    root, no bounce count). Stops the chatter when the explicitly summed bounce times fit.
    Only for states that do not overturn."""
    remaining = duration
    for _ in range(max_impacts):
        if theta == 0.0 and omega == 0.0:
            return 0.0, 0.0
        side = 1.0 if (theta > 0.0 or (theta == 0.0 and omega > 0.0)) else -1.0
        h, u = side * theta, side * omega

        def height(t, h=h, u=u):  # eq. 2 on one side, cosh - 1 written 2 sinh^2 (t = 0 gives h)
            return h * math.cosh(NU * t) + u / NU * math.sinh(NU * t) - 2 * THETA_CR * math.sinh(NU * t / 2) ** 2

        hi = 1.0 / NU
        while height(hi) > 0.0:
            hi *= 2.0
        if h > 0.0:  # bracket within a factor of two (the root may be many decades below 1/nu)
            while height(0.5 * hi) < 0.0:
                hi *= 0.5
            lo = 0.5 * hi
        else:  # leaving zero: t = 0 is the lower root, the bounce ends near bounce(u)
            lo = 1e-3 * bounce(u)
        t_cross = brentq(height, lo, hi, xtol=1e-300, rtol=1e-15, maxiter=1000)
        if t_cross >= remaining:
            t = remaining
            arc_u = u * math.cosh(NU * t) - NU * (THETA_CR - h) * math.sinh(NU * t)
            return side * height(t), side * arc_u
        remaining -= t_cross
        speed = e * math.sqrt(u * u + NU**2 * h * (2.0 * THETA_CR - h))  # energy, then eq. 6
        if speed == 0.0:
            return 0.0, 0.0
        if e < 1.0:
            k = np.arange(int(math.log(1e-300 / speed) / math.log(e)) + 2 if e > 0 else 1)
            if np.sum(2.0 * np.arctanh(speed * e**k / C) / NU) <= remaining:
                return 0.0, 0.0
        theta, omega = 0.0, -side * speed
    raise RuntimeError("too many impacts")


# ---------------------------------------------------------------- free response, eqs. 2, 3, 6


@pytest.mark.parametrize("e", [0.0, 0.5, 0.95, 1.0])
def test_free_response_is_eq2_before_the_first_impact(e):
    ratio = 0.3
    theta0 = ratio * THETA_CR
    t1 = first_crossing(ratio)
    for t in np.linspace(0.0, t1, 41)[1:-1]:
        theta, omega, fallen = flight(theta0, 0.0, t, e)
        assert not fallen
        assert theta == pytest.approx(THETA_CR - (THETA_CR - theta0) * math.cosh(NU * t), rel=0, abs=1e-12 * theta0)
        assert omega == pytest.approx(-(THETA_CR - theta0) * NU * math.sinh(NU * t), rel=1e-12)


def test_first_crossing_time_and_restitution_at_the_impact():
    ratio, e = 0.3, 0.8
    theta0 = ratio * THETA_CR
    t1 = first_crossing(ratio)
    eps = 1e-9 * t1
    before = flight(theta0, 0.0, t1 - eps, e)
    after = flight(theta0, 0.0, t1 + eps, e)
    assert before[0] > 0.0 > after[0]  # the sign changes between t1 - eps and t1 + eps
    assert abs(before[0]) < 1e-8 * theta0 and abs(after[0]) < 1e-8 * theta0
    assert after[1] / before[1] == pytest.approx(e, rel=1e-7)  # eq. 6
    # the energy is e^2 times smaller after the impact (it is omega^2/2 at theta = 0)
    assert energy(*after[:2]) / energy(*before[:2]) == pytest.approx(e**2, rel=1e-7)
    assert energy(*before[:2]) == pytest.approx(energy(theta0, 0.0), rel=1e-12)


@pytest.mark.parametrize("ratio", [0.01, 0.3, 0.9])
def test_period_for_e_one_is_eq3(ratio):
    theta0 = ratio * THETA_CR
    period = float(models.period_housner(theta0, NU, THETA_CR))
    assert period == pytest.approx(4.0 * first_crossing(ratio), rel=1e-14)  # four quarter periods
    half = flight(theta0, 0.0, 0.5 * period, 1.0)
    full = flight(theta0, 0.0, period, 1.0)
    assert half[0] == pytest.approx(-theta0, rel=1e-10)
    assert full[0] == pytest.approx(theta0, rel=1e-10)
    assert abs(full[1]) < 1e-10 * C and not full[2]


def impact_times(ratio, e, t_max):
    """Impacts of the free response from rest at ratio theta_cr: t1 (eq. 2), then bounces of
    (2/nu) atanh(e^k W/C) (W the first impact speed); ends at the rest time when e < 1."""
    w = C * math.sqrt(ratio * (2 - ratio))
    n = int(t_max / bounce(e * w)) + 2 if e == 1.0 else int(math.log(1e-300 / w) / math.log(e)) + 2
    speeds = w * e ** np.arange(1, n + 1)
    return first_crossing(ratio) + np.concatenate([[0.0], np.cumsum(2.0 * np.arctanh(speeds / C) / NU)])


@pytest.mark.parametrize("e", [0.6, 0.95, 1.0])
def test_energy_constant_in_flight_and_times_e2_per_impact(e):
    ratio = 0.4
    theta0 = ratio * THETA_CR
    dt = first_crossing(ratio) / 37.3
    n = 600
    theta, theta_dot, fallen_at = housner.simulate_block_housner(
        [0], n, dt=dt, nu=NU, theta_cr=THETA_CR, e=e, sigma_p=0.0, theta0=theta0
    )
    assert fallen_at[0] == -1
    t = np.arange(n) * dt
    crossings = impact_times(ratio, e, t[-1])
    impacts = np.searchsorted(crossings, t)  # impacts before each sample
    expected = np.where(impacts < crossings.size, energy(theta0, 0.0) * e ** (2.0 * impacts), 0.0)
    np.testing.assert_allclose(energy(theta[0], theta_dot[0]), expected, rtol=1e-9, atol=1e-14 * expected[0])
    if t[-1] > crossings[-1]:  # the geometric-like series of bounces has ended: rest
        assert theta[0, -1] == 0.0 and theta_dot[0, -1] == 0.0


# ---------------------------------------------------------------- the eq. 4 limit


def test_small_amplitudes_follow_the_simplified_model_to_order_theta_over_theta_cr():
    """Bound: eq. 2 minus the parabola of eq. 4 is ``theta0 (cosh - 1) - theta_cr (cosh - 1 -
    (nu t)^2/2)``; with ``(nu t)^2 <= 2x`` (``x = theta0/theta_cr``) up to the first impact
    this is at most ``x theta0 (1 + O(x))``. Afterwards the periods differ by ``5x/12``
    (eqs. 3, 5), a phase drift, so over three cycles the difference stays below
    ``10 x theta0`` (three periods' drift times the largest speed); it is ``O(x)`` relative.
    """
    e = 0.9
    errors = {}
    for x in (1e-4, 1e-3):
        theta0 = x * THETA_CR
        t1 = first_crossing(x)
        dt = t1 / 18.7
        n = int(12 * t1 / dt)  # three cycles
        housner_theta, _, _ = housner.simulate_block_housner(
            [0], n, dt=dt, nu=NU, theta_cr=THETA_CR, e=e, sigma_p=0.0, theta0=theta0
        )
        simple_theta, _ = simulate.simulate_block([0], n, dt=dt, g=G, e=e, sigma_p=0.0, theta0=theta0)
        diff = np.abs(housner_theta[0] - simple_theta[0])
        first_quarter = np.arange(n) * dt < t1 * (1 - 1e-6)
        assert diff[first_quarter].max() <= 1.01 * x * theta0
        assert diff.max() <= 10 * x * theta0
        errors[x] = diff.max()
        # a single flight of the simplified kernel agrees to the same order
        one = flight(theta0, 0.0, 2.5 * t1, e)
        two = simulate.flight(theta0, 0.0, 2.5 * t1, G, e)
        assert one[0] == pytest.approx(two[0], rel=0, abs=10 * x * theta0)
    # first order in x: ten times the amplitude ratio, ten times the relative difference
    assert errors[1e-3] / (1e-3 * 1e-3) == pytest.approx(errors[1e-4] / (1e-4 * 1e-4), rel=0.05)


def random_parameters(ratio):
    """Step and impulse size giving sigma_Y ~ ratio theta_cr at ~75 points per cycle (e = 0.95).

    From the scale invariance of the simplified model, sigma_Y = c S^2/g^3 with
    S = sigma_p^2/dt and c ~ 290 (see :func:`rockdec.physics.simulate.calibrate_dt`).
    """
    c, n = 290.0, 75.0
    k = math.sqrt(4.0 * math.sqrt(2.0 * c) / n)
    sigma_p = k * math.sqrt(ratio * THETA_CR * G / c)
    return {"dt": sigma_p / G * k, "sigma_p": sigma_p, "e": 0.95}


def test_random_response_at_small_amplitude_matches_the_simplified_model():
    """Same impulses (seeds 0-99), both kernels started from one stationary state of the
    simplified model (8000 steps of burn-in, sigma_Y ~ 1e-3 or 1e-2 theta_cr), then compared
    over the next 20 steps. The difference, relative to the amplitude ``A`` of the stretch,
    is ``O(A/theta_cr)``: its ratio to ``A/theta_cr`` has a median of order one at both
    levels. (Chaos amplifies any difference, strongest near rest: started from rest, where
    chattering decides rest or motion within a step, even a 1e-12 change of g shows after a
    few dozen steps, so the stationary start and the short stretch are needed.)"""
    burn_in, n = 8000, 20
    for ratio in (1e-3, 1e-2):
        p = random_parameters(ratio)
        scaled = []
        for seed in range(100):
            impulses = loading.series_rng(seed).standard_normal(burn_in + n) * p["sigma_p"]
            start, start_dot = np.empty(burn_in + 1), np.empty(burn_in + 1)
            simulate.integrate(impulses, p["dt"], G, p["e"], 0.0, 0.0, 0, start, start_dot)
            a, a_dot, b, b_dot = (np.empty(n) for _ in range(4))
            simulate.integrate(impulses[burn_in:], p["dt"], G, p["e"], start[-1], start_dot[-1], 0, b, b_dot)
            fell = housner.integrate_housner(
                impulses[burn_in:], p["dt"], NU, THETA_CR, p["e"], start[-1], start_dot[-1], 0, a, a_dot
            )
            assert fell == -1 and a[0] == b[0]
            amplitude = np.abs(b).max()
            scaled.append(np.abs(a - b).max() / amplitude / (amplitude / THETA_CR))
        assert 0.1 < np.median(scaled) < 3.0


def test_random_response_statistics_at_small_amplitude():
    """Stationary sigma_Y of the two models within 15 % over 64 x 15000 samples. (The response
    has kurtosis near 15-20 and is chaotic, so this many samples pin sigma_Y only to about
    4 % each; the tolerance is about three standard errors of the difference.)"""
    p = random_parameters(1e-3)
    seeds = np.arange(64)
    a, _, fallen = housner.simulate_block_housner(seeds, 15_000, nu=NU, theta_cr=THETA_CR, burn_in=6000, **p)
    b, _ = simulate.simulate_block(seeds, 15_000, g=G, burn_in=6000, **p)
    assert np.all(fallen == -1)
    assert np.std(b) / THETA_CR == pytest.approx(1e-3, rel=0.3)
    assert np.std(a) / np.std(b) == pytest.approx(1.0, abs=0.15)


def test_same_seed_same_series_bit_for_bit():
    p = random_parameters(1e-2)
    one = housner.simulate_block_housner([5, 9], 3000, nu=NU, theta_cr=THETA_CR, burn_in=100, **p)
    alone = housner.simulate_block_housner([9], 3000, nu=NU, theta_cr=THETA_CR, burn_in=100, **p)
    np.testing.assert_array_equal(one[0][1], alone[0][0])
    np.testing.assert_array_equal(one[1][1], alone[1][0])


# ---------------------------------------------------------------- overturning


def test_overturning_from_zero_at_the_right_sample_and_not_just_below():
    # from theta = 0 with speed w > C, eq. 2 reaches theta_cr at atanh(C/w)/nu
    w = 1.01 * C
    t_fall = math.atanh(C / w) / NU
    dt = t_fall / 23.4
    theta, theta_dot, fallen_at = housner.simulate_block_housner(
        [0], 100, dt=dt, nu=NU, theta_cr=THETA_CR, e=0.9, sigma_p=0.0, theta_dot0=w
    )
    k = math.ceil(t_fall / dt)
    assert fallen_at[0] == k
    assert np.all(np.isnan(theta[0, k:])) and np.all(np.isnan(theta_dot[0, k:]))
    assert np.all((theta[0, :k] >= 0) & (theta[0, :k] < THETA_CR))
    theta_end, omega_end, fallen = flight(0.0, w, 2 * t_fall, 0.9)
    assert fallen and theta_end == THETA_CR
    assert omega_end == pytest.approx(math.sqrt(w**2 - C**2), rel=1e-9)  # energy at theta_cr
    # just below the critical speed it comes back (and, with e < 1, never falls)
    theta, _, fallen_at = housner.simulate_block_housner(
        [0], 2000, dt=dt, nu=NU, theta_cr=THETA_CR, e=0.9, sigma_p=0.0, theta_dot0=-0.999 * C
    )
    assert fallen_at[0] == -1 and np.all(np.abs(theta) < THETA_CR)
    assert theta[0, -1] == 0.0  # chattered to rest


@pytest.mark.parametrize("excess", [1e-6, -1e-6])
def test_overturning_separatrix_from_a_tilted_start(excess):
    # from height h moving away with u, the block falls iff u > nu (theta_cr - h)
    h = 0.6 * THETA_CR
    u = NU * (THETA_CR - h) * (1 + excess)
    *_, fallen = flight(-h, -u, 50.0 / NU, 0.95)
    assert fallen == (excess > 0)


def test_overturned_start_and_burn_in():
    out = housner.simulate_block_housner(
        [0], 10, dt=0.01, nu=NU, theta_cr=THETA_CR, e=0.9, sigma_p=0.0, theta0=THETA_CR
    )
    assert out[2][0] == 0 and np.all(np.isnan(out[0]))
    out = housner.simulate_block_housner(
        [0], 10, dt=0.01, nu=NU, theta_cr=THETA_CR, e=0.9, sigma_p=0.0, theta_dot0=2 * C, burn_in=100
    )
    assert out[2][0] == 0 and np.all(np.isnan(out[1]))


# ---------------------------------------------------------------- limits: e = 0, e = 1, chatter


def test_e_zero_rests_at_the_first_impact():
    ratio = 0.3
    t1 = first_crossing(ratio)
    dt = t1 / 10.5
    theta, theta_dot, _ = housner.simulate_block_housner(
        [0], 40, dt=dt, nu=NU, theta_cr=THETA_CR, e=0.0, sigma_p=0.0, theta0=ratio * THETA_CR
    )
    k = math.ceil(t1 / dt)
    assert np.all(theta[0, :k] > 0) and np.all(theta[0, k:] == 0.0) and np.all(theta_dot[0, k:] == 0.0)
    # leaving zero: one bounce, then rest
    w = 0.3 * C
    assert flight(0.0, -w, 0.999 * bounce(w), 0.0)[0] < 0.0
    assert flight(0.0, -w, 1.001 * bounce(w), 0.0) == (0.0, 0.0, False)


def test_e_one_keeps_the_energy_over_many_cycles_and_long_steps():
    theta0 = 0.5 * THETA_CR
    dt = first_crossing(0.5) / 20.3
    theta, theta_dot, fallen_at = housner.simulate_block_housner(
        [0], 4000, dt=dt, nu=NU, theta_cr=THETA_CR, e=1.0, sigma_p=0.0, theta0=theta0
    )
    assert fallen_at[0] == -1
    np.testing.assert_allclose(energy(theta[0], theta_dot[0]), energy(theta0, 0.0), rtol=1e-10)
    # one step holding ~1e9 equal bounces: counted by one division, energy kept
    w = 1e-9 * C
    theta, omega, _ = flight(0.0, w, 1.0, 1.0)
    assert energy(theta, omega) == pytest.approx(0.5 * w**2, rel=1e-6)


@pytest.mark.parametrize("e", [0.1, 0.5, 0.9, 0.999])
def test_chatter_rests_at_the_sum_of_the_bounce_times(e):
    ratio = 0.3
    theta0 = ratio * THETA_CR
    w = C * math.sqrt(ratio * (2 - ratio))  # first impact speed, from the energy
    k = np.arange(int(math.log(1e-300 / w) / math.log(e)) + 2)
    t_rest = first_crossing(ratio) + np.sum(2.0 * np.arctanh(w * e ** (k + 1) / C) / NU)
    before = flight(theta0, 0.0, t_rest * (1 - 1e-9), e)
    after = flight(theta0, 0.0, t_rest * (1 + 1e-9), e)
    assert before[:2] != (0.0, 0.0)
    assert after == (0.0, 0.0, False)


@pytest.mark.parametrize("e", [1.0 - 1e-9, 1.0 - 1e-12, 0.999999])
def test_many_impacts_in_one_step_terminate(e):
    w = 1e-7 * C  # bounces of ~1e-7 / nu s: ~1e7 of them in the step
    theta, omega, fallen = flight(0.0, w, 1.0, e)
    assert np.isfinite(theta) and np.isfinite(omega) and not fallen
    assert energy(theta, omega) <= 0.5 * w**2 * (1 + 1e-9)  # never gains energy


# ---------------------------------------------------------------- against the reference


@settings(max_examples=300, deadline=None)
@given(
    ratio=st.floats(-0.95, 0.95, allow_subnormal=False),
    omega=st.floats(-1.0, 1.0),
    duration=st.floats(1e-6, 3.0),
    e=st.one_of(st.floats(0.0, 0.9), st.just(1.0)),
)
def test_compiled_flight_equals_the_reference(ratio, omega, duration, e):
    theta = ratio * THETA_CR
    omega *= C
    if 2 * energy(theta, omega) > 0.95 * C**2:  # keep away from overturning
        return
    if e == 1.0 and abs(omega) < 1e-3 * C and abs(ratio) < 1e-6:  # too many bounces to walk
        return
    if 0.0 < abs(omega) < 1e-12 * C and abs(ratio) < 1e-12:  # flights under 1e-12 s: the reference's root finder cannot bracket them
        return
    got = flight(theta, omega, duration, e)
    want = reference_flight(theta, omega, duration, e)
    assert not got[2]
    scale = abs(theta) + abs(omega) * duration + G * duration**2 + 1e-300
    assert got[0] == pytest.approx(want[0], rel=1e-9, abs=1e-9 * scale)
    assert got[1] == pytest.approx(want[1], rel=1e-9, abs=1e-9 * (abs(omega) + G * duration))


def test_two_steps_equal_one():
    rng = np.random.default_rng(0)
    for _ in range(300):
        theta = rng.uniform(-0.8, 0.8) * THETA_CR
        omega = rng.uniform(-0.5, 0.5) * C
        e = rng.choice([0.0, 0.5, 0.95, 1.0])
        d1, d2 = rng.uniform(0, 2.0 / NU, 2)
        whole = flight(theta, omega, d1 + d2, e)
        split = flight(*flight(theta, omega, d1, e)[:2], d2, e)
        assert whole[0] == pytest.approx(split[0], abs=1e-9 * THETA_CR)
        assert whole[1] == pytest.approx(split[1], abs=1e-9 * C)


# ---------------------------------------------------------------- model choice


@pytest.mark.parametrize("tolerance", [1e-6, 0.02, 0.05, 0.5, 10.0])
def test_the_amplitude_limit_is_the_root_of_the_period_mismatch_to_adjacent_floats(tolerance):
    limit = models.amplitude_limit(tolerance)
    assert models.period_mismatch(np.nextafter(limit, 0.0)) < tolerance <= models.period_mismatch(limit)
    if 0.01 < tolerance < 1.0:  # a mismatch well above its rounding, and a root inside brentq's bracket
        assert limit == pytest.approx(brentq(lambda x: models.period_mismatch(x) - tolerance, 1e-9, 1.0 - 1e-12, xtol=1e-15),
                                      rel=1e-13)


def test_choose_model_and_amplitude_limit():
    limit = models.amplitude_limit(0.02)
    t3 = models.period_housner(limit, 1.0, 1.0)
    t5 = models.period_simplified(limit, 1.0, 1.0)
    assert t3 / t5 - 1 == pytest.approx(0.02, rel=1e-9)
    assert limit == pytest.approx(0.02 * 12 / 5, rel=0.05)  # T3/T5 ~ 1 + 5x/12
    assert housner.choose_model(0.01)[0] == "simplified"
    assert housner.choose_model(0.2)[0] == "housner"
    assert housner.choose_model(0.99 * limit)[0] == "simplified"
    assert housner.choose_model(1.01 * limit)[0] == "housner"
    assert housner.choose_model(1.5)[0] == "housner"
    name, reason = housner.choose_model(0.2, tolerance=0.2)
    assert name == "simplified" and "9.6" in reason
    with pytest.raises(ValueError):
        models.amplitude_limit(0.0)


def test_parameters_are_checked():
    with pytest.raises(ValueError, match="restitution"):
        housner.simulate_block_housner([0], 10, dt=0.01, nu=NU, theta_cr=THETA_CR, e=1.5, sigma_p=0.0)
    with pytest.raises(ValueError, match="> 0"):
        housner.simulate_block_housner([0], 10, dt=0.0, nu=NU, theta_cr=THETA_CR, e=0.5, sigma_p=0.0)


def test_scene_records_which_model_ran_and_why():
    from rockdec.pipeline import config
    from rockdec.physics import run

    pilot = {"pilot_seeds": 32, "pilot_points": 20_000}  # a smaller step search: the choice and the attributes are read, not the step
    small = config.validate_scene({"model": "auto"})
    contract = run.from_scene(small, pilot=pilot)
    assert contract.model == "simplified" and contract.model_reason.startswith("auto:")
    forced = config.validate_scene({"model": "housner"})
    housner_run = run.from_scene(forced, pilot=pilot)
    assert housner_run.model == "housner" and housner_run.model_reason == "requested"
    ds = housner_run.dataset([3, 4, 5], 6000)
    assert ds.attrs["model"] == "housner"
    # the attributes are the contract: the run they describe regenerates any seed alone
    assert run.Run.from_attrs(ds.attrs) == housner_run
    alone = run.Run.from_attrs(ds.attrs).dataset([4], 6000, chunk_seeds=1).theta.values[0]
    np.testing.assert_array_equal(alone, ds.theta.sel(seed=4).values)  # seed-stable for Housner too

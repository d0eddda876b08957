"""The fixed-step simulator with impacts on the grid: first-order convergence, its restitution bias.

Theory of the bias (module docstring of :mod:`rockdec.physics.fixed_step`): a crossing a time
``tau`` before the end of its step is seen at the step's end, after ``tau`` of gravity of
the wrong sign. Speed ``V`` at the crossing becomes ``V + g tau`` and the body ends ``V tau +
g tau^2/2`` beyond zero, so after ``omega *= e`` the energy ratio of the impact is
``e^2 + 2 (1 + e^2) g tau / V + O(tau^2)``. With ``tau`` uniform over the step and
``V = g T / 4`` (``T = N dt`` the period at that amplitude, eq. 5), the effective
restitution is ``e_eff^2 = e^2 + 4 (1 + e^2) / N`` on average over where the crossing
falls: above ``e``, by a first-order amount with a large constant.
"""

import math

import numpy as np
import pytest

from rockdec.physics import simulate

G = 1.0


def fixed_free(a, e, dt, n):
    theta, omega = simulate.simulate_block([0], n, dt=dt, g=G, e=e, sigma_p=0.0, theta0=a, grid_impacts=True)
    return theta[0], omega[0]


def effective_restitution(a, e, points_per_cycle, phases=64):
    """sqrt(energy after / before) of the first impact, for crossings spread over a step."""
    t1 = math.sqrt(2 * a / G)
    out = []
    for shift in np.linspace(0.0, 4.0, phases, endpoint=False):
        dt = 4 * t1 / (points_per_cycle + shift)  # crossing t1 / dt sweeps a whole step
        theta, omega = fixed_free(a, e, dt, int(1.5 * t1 / dt) + 2)
        energy = 0.5 * omega**2 + G * np.abs(theta)
        k = int(np.argmax(theta < 0))
        out.append(math.sqrt(energy[k] / energy[0]))
    return np.array(out)


def test_free_response_converges_at_first_order():
    a, e = 0.7, 0.8
    t1 = math.sqrt(2 * a / G)
    steps, errors = [], []
    for n_half in (20, 40, 80, 160, 320, 640):
        dt = t1 / (n_half + 0.37)  # crossings off the grid
        n = int(4 * t1 / dt)
        exact, _ = simulate.simulate_block([0], n, dt=dt, g=G, e=e, sigma_p=0.0, theta0=a)
        theta, _ = fixed_free(a, e, dt, n)
        steps.append(dt)
        errors.append(np.abs(theta - exact[0]).max())
    order = np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert 0.9 < order < 1.1
    assert errors[-1] < 0.02 * a


def test_energy_changes_only_at_grid_impacts():
    a, e = 0.7, 0.9
    dt = math.sqrt(2 * a / G) / 23.7
    theta, omega = fixed_free(a, e, dt, 400)
    energy = 0.5 * omega**2 + G * np.abs(theta)
    impact = np.sign(theta[1:]) != np.sign(theta[:-1])
    assert impact.sum() >= 3
    np.testing.assert_allclose(np.diff(energy)[~impact], 0.0, atol=1e-13 * G * a)


@pytest.mark.parametrize("points_per_cycle", [38, 150])
def test_grid_impacts_raise_the_effective_restitution_by_four_one_plus_e2_over_n(points_per_cycle):
    e = 0.95
    e_eff = effective_restitution(0.7, e, points_per_cycle)
    excess = np.mean(e_eff**2) - e**2
    assert excess == pytest.approx(4 * (1 + e**2) / points_per_cycle, rel=0.08)
    assert e_eff.min() >= e - 1e-12  # never below e: the overshoot only adds energy


def test_coarse_step_bias_at_the_paper_sampling():
    # 75 points per cycle (the paper's sampling at sigma_Y): the grid impact loses almost nothing
    e_eff = effective_restitution(0.7, 0.95, 75)
    assert e_eff.mean() > 0.99
    # and the bias shrinks about linearly with the step
    fine = effective_restitution(0.7, 0.95, 1000).mean() - 0.95
    coarse = effective_restitution(0.7, 0.95, 150).mean() - 0.95
    assert coarse / fine == pytest.approx(1000 / 150, rel=0.25)


@pytest.mark.parametrize("e", [0.9, 0.95])
def test_free_response_never_rests_but_locks_on_a_grid_limit_cycle(e):
    # energy balance e_eff = 1 at N* = 4 (1 + e^2)/(1 - e^2) points per cycle, whatever the step
    dt = 0.01
    theta, _ = fixed_free(0.7, e, dt, 200_000)
    tail = theta[-50_000:]
    crossings = np.flatnonzero(np.sign(tail[1:]) != np.sign(tail[:-1]))
    points_per_cycle = 2 * np.mean(np.diff(crossings))
    assert points_per_cycle == pytest.approx(4 * (1 + e**2) / (1 - e**2), rel=0.05)
    assert np.isfinite(theta).all()


def test_plastic_impact_chatters_within_a_step_scale():
    a = 0.7
    dt = math.sqrt(2 * a / G) / 7.3
    theta, omega = fixed_free(a, 0.0, dt, 400)
    after = int(np.argmax(theta < 0)) + 1
    assert np.abs(theta[after:]).max() < 5 * G * dt**2
    assert np.isfinite(omega).all()


def test_same_impulses_as_the_exact_simulator_before_the_first_impact():
    a = 0.7
    fixed, _ = simulate.simulate_block([3, 4], 200, dt=0.01, g=G, e=0.9, sigma_p=0.003, theta0=a, grid_impacts=True)
    exact, _ = simulate.simulate_block([3, 4], 200, dt=0.01, g=G, e=0.9, sigma_p=0.003, theta0=a)
    for f, x in zip(fixed, exact):
        before = int(np.argmax(x < 0))  # both integrate the same parabolas and impulses until then
        assert before > 50
        np.testing.assert_allclose(f[:before], x[:before], rtol=0, atol=1e-12)


def test_same_seed_gives_the_same_series_bit_for_bit():
    kw = dict(dt=0.0034, g=G, e=0.95, sigma_p=0.003, burn_in=300)
    first, first_dot = simulate.simulate_block([7, 8, 9], 2000, **kw, grid_impacts=True)
    again, again_dot = simulate.simulate_block([7, 8, 9], 2000, **kw, grid_impacts=True)
    alone, _ = simulate.simulate_block([8], 2000, **kw, grid_impacts=True)
    assert np.array_equal(first, again) and np.array_equal(first_dot, again_dot)
    assert np.array_equal(alone[0], first[1])
    lazy = simulate.simulation_dataset([7, 8, 9], 2000, chunk_seeds=2, model="fixed_step", **kw)
    assert lazy["theta"].chunks is not None and lazy.attrs["model"] == "fixed_step"
    assert np.array_equal(lazy["theta"].values, first) and np.array_equal(lazy["theta_dot"].values, first_dot)

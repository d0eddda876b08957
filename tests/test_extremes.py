"""Numerical extremes (docs/method.md §3, §4): scale, precision, restitution at its limits, sampling floor.

Nothing hangs and nothing returns a silent wrong number: a correct value or NaN with a reason.
"""

import math

import numpy as np
import pytest
import xarray as xr

from rockdec.pipeline import config, replicates
from rockdec.rdd import estimators, fits
from rockdec.physics import simulate
from reference_estimators import local_measures

DT, G, SIGMA_P = 0.003432651166459561, 1.0, 0.003
STATS = {"sigma_y": 0.001992454115749987, "sigma_ydot": 0.03410016419092972, "g": G}


@pytest.fixture(scope="module")
def record():
    """60 stationary series of the paper scene (e = 0.95, 75 points per cycle)."""
    theta, _ = simulate.simulate_block(np.arange(60), 6000, dt=DT, g=G, e=0.95, sigma_p=SIGMA_P, burn_in=8087)
    return xr.DataArray(theta, dims=("seed", "time"), coords={"seed": np.arange(60)}, attrs={"dt": DT})


def estimates_of(theta, stats):
    scene = config.validate_scene({})
    group = np.zeros(theta.sizes["seed"], dtype=int)
    cube = replicates.scene_signatures(theta, scene["signatures"], **stats, group=group, replicate_of_group=[0])
    return replicates.replicate_estimates(cube, fit_points=5)


@pytest.mark.hostile("numbers", "answered")
@pytest.mark.parametrize("scale", [2.0**40, 2.0**-40])
def test_power_of_two_scaling_leaves_estimates_bit_identical(record, scale):
    base = estimates_of(record, STATS)
    scaled_stats = {**STATS, "sigma_y": STATS["sigma_y"] * scale, "sigma_ydot": STATS["sigma_ydot"] * scale, "g": G * scale}
    scaled = estimates_of(record * scale, scaled_stats)
    np.testing.assert_array_equal(scaled["count"].values, base["count"].values)
    # every ratio of eqs. 26-27 is exact under a power of two; e_g regresses log|r|, where the
    # scale adds 40 ln 2 to every point and rounds the sums differently (1e-15)
    local = [name for name in base["estimator"].values if name != "e_g"]
    np.testing.assert_array_equal(scaled["e_hat"].sel(estimator=local).values, base["e_hat"].sel(estimator=local).values)
    np.testing.assert_allclose(scaled["e_hat"].sel(estimator="e_g").values, base["e_hat"].sel(estimator="e_g").values, rtol=1e-13)


@pytest.mark.hostile("numbers", "answered")
@pytest.mark.parametrize("scale", [1e12, 1e-12])
def test_decimal_scaling_changes_estimates_only_by_rounding(record, scale):
    base = estimates_of(record, STATS)
    scaled_stats = {**STATS, "sigma_y": STATS["sigma_y"] * scale, "sigma_ydot": STATS["sigma_ydot"] * scale, "g": G * scale}
    scaled = estimates_of(record * scale, scaled_stats)
    # a trigger sitting on a window edge to 1e-16 could flip; the estimates move by rounding only
    np.testing.assert_allclose(scaled["e_hat0"].values, base["e_hat0"].values, rtol=1e-9)


@pytest.mark.hostile("numbers", "answered")
def test_float32_record_gives_the_float64_estimates_to_float32_precision(record):
    base = estimates_of(record, STATS)
    single = estimates_of(record.astype(np.float32), STATS)
    assert single["e_hat0"].dtype == np.float64
    # float32 rounding (6e-8 relative) can move a few triggers across a window edge
    np.testing.assert_allclose(single["e_hat0"].values, base["e_hat0"].values, atol=2e-3)


@pytest.mark.hostile("numbers", "answered")
@pytest.mark.parametrize("e", [0.0, 1e-12, 0.5, 0.999999, 1.0])
def test_restitution_limits_simulate_at_a_given_step(e):
    theta, theta_dot = simulate.simulate_block(np.arange(3), 20_000, dt=DT, g=G, e=e, sigma_p=SIGMA_P)
    assert np.all(np.isfinite(theta)) and np.all(np.isfinite(theta_dot))
    if e < 1e-6:  # plastic: every landing stops the block, so it sits at zero between kicks often
        assert np.mean(theta == 0.0) > 0.01
    if e >= 0.999999:  # (nearly) lossless: the random walk in energy keeps growing
        assert np.mean(theta[:, -5000:] ** 2) > 10 * np.mean(theta[:, :5000] ** 2)


@pytest.mark.hostile("sizes", "refused")
def test_calibration_refuses_e_one_and_a_burn_in_too_long_to_run():
    with pytest.raises(ValueError, match="no energy"):
        simulate.calibrate_dt(e=1.0, g=G, sigma_p=SIGMA_P)
    with pytest.raises(ValueError, match="give `burn_in`"):
        simulate.default_burn_in(0.999999, 75.0)


@pytest.mark.hostile("numbers", "answered")
def test_e_half_is_estimated_by_the_impact_slope():
    """At e = 0.5 the response rests often, but D_v still sees the velocity ratio of eq. 6."""
    cal = simulate.calibrate_dt(e=0.5, g=G, sigma_p=SIGMA_P, pilot_seeds=64, pilot_points=20_000)
    theta, _ = simulate.simulate_block(np.arange(100), 6000, dt=cal["dt"], g=G, e=0.5, sigma_p=SIGMA_P, burn_in=cal["burn_in"])
    da = xr.DataArray(theta, dims=("seed", "time"), coords={"seed": np.arange(100)}, attrs={"dt": cal["dt"]})
    est = estimates_of(da, {"sigma_y": cal["sigma_y"], "sigma_ydot": cal["sigma_ydot"], "g": G})
    assert abs(float(est["e_hat0"].sel(estimator="e_v", replicate=0)) - 0.5) < 0.03


def analytic_free_response(points_per_cycle, e=0.95, level=2.0, n_periods=2.5):
    """Ideal free response from a = level (sigma_Y = 1, g = 1) sampled at points_per_cycle at sigma_Y."""
    dt = 4 * math.sqrt(2.0) / points_per_cycle  # eq. 5 at amplitude 1
    n = int(n_periods * 4 * math.sqrt(2 * level) / dt)
    r = np.empty(n + 1)
    for k in range(n + 1):
        r[k] = simulate.flight(level, 0.0, k * dt, G, e)[0]
    return r, dt


@pytest.mark.hostile("numbers", "warned")
def test_local_fits_have_a_sampling_floor():
    """Below min_points_per_cycle the paper's N_h/8-point fits would have fewer than 3 points.

    The estimators then fit 3 points anyway while the half cycle holds them, and return NaN
    with a reason once it does not (5 points per cycle); at and above the floor they are exact
    on the ideal response, up to 5000 points per cycle.
    """
    floor = fits.min_points_per_cycle(0.95, 2.0)
    for ppc in (math.ceil(floor), 75, 5000):
        r, dt = analytic_free_response(ppc)
        for name, est in local_measures(r, dt).items():
            assert est.value == pytest.approx(0.95, abs=1e-9), (ppc, name, est)
    r, dt = analytic_free_response(5)
    measures = local_measures(r, dt)
    assert all(np.isnan(m.value) and "fewer than 3 points" in m.reason for m in measures.values())
    with pytest.raises(config.ConfigError, match="points_per_cycle"):
        config.validate_scene({"excitation": {"points_per_cycle": 5}})

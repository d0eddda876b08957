"""Properties of the estimators of e (paper eqs. 25-27) and of the zero-window extrapolation.

The reference is the analytic free rocking response of the simplified model (docs/method.md §5,
eqs. 4-6): parabolas of curvature ``g``, the velocity multiplied by ``e`` at every zero
crossing, rest once the geometric series of flight times has run out.
"""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from rockdec.rdd import signatures
from rockdec.physics import simulate
from rockdec.rdd.estimators import (
    LOCAL_ESTIMATORS,
    Estimate,
    _lobes,
    estimate_all,
    estimate_cube,
    extrapolate,
    extrapolate_to_zero,
    half_cycle,
)
from rockdec.rdd.registry import ESTIMATORS
from reference_estimators import (
    e_first_peak,
    e_global,
    e_impact_slope,
    local_measures,
    reference_estimate_all,
    reference_half_cycle,
    reference_lobes,
)

G = 2.0  # rad/s^2: with A = 1 rad the first crossing is at t1 = 1 s
A = 1.0
POINTS_PER_CYCLE = 75
E_VALUES = (0.3, 0.5, 0.8, 0.95, 0.99)


def t1_of(a=A, g=G):
    return np.sqrt(2.0 * a / g)


def dt_of(points_per_cycle=POINTS_PER_CYCLE, a=A, g=G):
    """Step giving ``points_per_cycle`` samples per period ``T = 4 sqrt(2a/g)`` (eq. 5)."""
    return 4.0 * t1_of(a, g) / points_per_cycle


def crossing_times(e, t_end, a=A, g=G):
    """Zero crossings ``tau_j`` (``j >= 1``) of the free response from ``(a, 0)``, preceded by
    ``tau_0 = -t1``: flight ``j`` starts at ``tau_j`` with speed ``e^j g t1`` and lasts
    ``2 e^j t1``. Stops past ``t_end`` or when the flights left are below rounding."""
    t1 = t1_of(a, g)
    taus, j = [-t1], 0
    while taus[-1] <= t_end and e**j > 1e-17:
        taus.append(taus[-1] + 2.0 * e**j * t1)
        j += 1
    return np.array(taus)


def free_rocking(e, t, a=A, g=G):
    """Closed-form free response from ``(a, 0)`` at times ``t >= 0`` (eqs. 4, 6).

    Flight ``j`` (sign ``(-1)^j``) is ``(-1)^j [u_j s - g s^2/2]`` with ``s = t - tau_j`` and
    ``u_j = e^j g t1``; flight 0 written this way is ``a - g t^2/2``. After the last flight
    (the series has summed) the block rests at zero.
    """
    t = np.asarray(t, dtype=float)
    taus = crossing_times(e, t.max(), a, g)
    j = np.searchsorted(taus, t, side="right") - 1
    s = t - taus[np.minimum(j, taus.size - 1)]
    u = e ** j.astype(float) * g * t1_of(a, g)
    flight = (-1.0) ** j * (u * s - 0.5 * g * s**2)
    return np.where(j < taus.size - 1, flight, 0.0)


def sampled_free_response(e, periods=2.5, points_per_cycle=POINTS_PER_CYCLE):
    dt = dt_of(points_per_cycle)
    n = int(round(periods * points_per_cycle)) + 1
    return free_rocking(e, dt * np.arange(n)), dt


def through_impact(e, tau, v=G * t1_of(), g=G):
    """Two-sided response through an impact at ``tau = 0``: rising from below with speed
    ``v`` (gravity ``+g`` while negative), leaving with ``e v`` (gravity ``-g``)."""
    return np.where(tau < 0, v * tau + 0.5 * g * tau**2, e * v * tau - 0.5 * g * tau**2)


# --- exactness on the ideal response -------------------------------------------------


@pytest.mark.parametrize("e", E_VALUES)
def test_local_measures_recover_e_on_ideal_response(e):
    r, dt = sampled_free_response(e)
    est = local_measures(r, dt)
    for name in ("e1", "e2", "e3", "e4"):
        assert est[name].reason == ""
        assert est[name].value == pytest.approx(e, abs=1e-9), name


@pytest.mark.parametrize("e", E_VALUES)
def test_half_cycle_features_match_closed_form(e):
    r, dt = sampled_free_response(e)
    h = half_cycle(r, dt)
    t1 = t1_of()
    expected = dict(c1=A, t1=t1, v1=-G * t1, v2=-e * G * t1, t2=(1 + e) * t1, c2=-(e**2) * A)
    for name, value in expected.items():
        assert getattr(h, name) == pytest.approx(value, abs=1e-9), name


@pytest.mark.parametrize("e", E_VALUES)
def test_paper_printed_e4_is_reciprocal_of_e(e):
    """Eq. 27 as printed, ``t1/(t2 - t1)``: with ``t2 - t1 = e t1`` (the impact leaves speed
    ``e g t1``, which gravity stops in ``e t1``) it equals ``1/e``; ``(t2 - t1)/t1 = e``."""
    r, dt = sampled_free_response(e)
    h = half_cycle(r, dt)
    assert h.t1 / (h.t2 - h.t1) == pytest.approx(1.0 / e, rel=1e-9)
    assert local_measures(r, dt)["e4"].value == pytest.approx(e, abs=1e-9)


@pytest.mark.parametrize("e", E_VALUES)
def test_impact_slope_ratio_recovers_e(e):
    dt = dt_of()
    tau = dt * np.arange(-10, 11)
    assert 10 * dt < 2 * e * t1_of()  # the lags stay inside one flight on each side
    est = e_impact_slope(through_impact(e, tau), dt, fit_points=5)
    assert est.reason == ""
    assert est.value == pytest.approx(e, abs=1e-9)


def sampling_error(e, i, dt, a=A, g=G):
    """Relative bound on the sampled ``i``-th extreme: the sample nearest the vertex is at
    most ``dt/2`` away, so ``|r_i|`` is low by at most ``(g/2)(dt/2)^2 = g dt^2/8`` out of
    ``a e^(2i)``; ``r_0`` sits on the vertex (tau = 0), no error."""
    return 0.0 if i == 0 else g * dt**2 / (8.0 * a * e ** (2 * i))


@pytest.mark.parametrize("e", E_VALUES)
def test_first_peak_within_sampling_bound(e):
    """``e_0 = sqrt(|r_1|/r_0)`` with ``r_0 = a`` exact and ``a e^2 (1 - eps) <= |r_1| <= a e^2``
    (``eps`` = :func:`sampling_error`), so ``0 <= e - e_0 <= e (1 - sqrt(1 - eps))``."""
    r, dt = sampled_free_response(e)
    bound = e * (1.0 - np.sqrt(1.0 - sampling_error(e, 1, dt)))
    error = e - e_first_peak(r).value
    assert -1e-12 <= error <= bound + 1e-12
    assert bound < 5e-3


@pytest.mark.parametrize("e", E_VALUES)
def test_global_decrement_within_sampling_bound(e):
    """Extremes ``0..K``, with ``K`` the last half cycle of half-width ``e^K t1 >= 2 dt``
    (so its vertex has samples on both sides) within 2.5 periods; the record ends just
    before crossing ``K+1``. Each ``y_i = 2 ln|r_i|`` is low by at most
    ``-2 ln(1 - eps_i)`` (:func:`sampling_error`); the least-squares slope is
    ``sum w_i y_i`` with ``w_i = (i - mean)/sum (i - mean)^2``, so it is off by at most
    ``B = sum |w_i| (-2 ln(1 - eps_i))``, and ``e_g = e exp(error/4)`` is within
    ``e (exp(B/4) - 1)`` of ``e``."""
    dt, t1 = dt_of(), t1_of()
    taus = crossing_times(e, 10.0 * t1)
    last = max(k for k in range(1, taus.size - 1) if e**k * t1 >= 2 * dt and taus[k + 1] <= 10 * t1)
    n = int(np.ceil(taus[last + 1] / dt))  # samples 0..n-1 end before crossing last+1
    r = free_rocking(e, dt * np.arange(n))
    i = np.arange(last + 1)
    w = (i - i.mean()) / np.sum((i - i.mean()) ** 2)
    slope_bound = sum(abs(w[k]) * -2.0 * np.log1p(-sampling_error(e, k, dt)) for k in i)
    bound = e * np.expm1(slope_bound / 4.0)
    assert abs(e_global(r).value - e) <= bound + 1e-12
    assert bound < 2e-2


# --- noise ---------------------------------------------------------------------------


@pytest.mark.parametrize("e", (0.5, 0.8, 0.95))
def test_local_measure_error_shrinks_with_noise(e):
    r, dt = sampled_free_response(e)
    rms = {}
    for noise in (1e-2, 1e-3):
        errors = []
        for seed in range(20):
            rng = np.random.default_rng([seed, int(e * 100)])
            est = local_measures(r + noise * rng.standard_normal(r.size), dt)
            errors.append([est[name].value - e for name in ("e1", "e2", "e3", "e4")])
        rms[noise] = np.sqrt(np.mean(np.square(errors), axis=0))
    assert np.all(np.isfinite(rms[1e-2]))
    assert np.all(rms[1e-3] < rms[1e-2] / 3)


# --- degenerate input ----------------------------------------------------------------


def test_nan_signature_gives_nan_with_reason():
    r = np.full(50, np.nan)
    out = estimate_all(r, np.full(21, np.nan), dt_of())
    assert set(out) == set(ESTIMATORS)
    for est in out.values():
        assert np.isnan(est.value) and est.reason == "NaN in signature"


def test_no_zero_crossing_gives_nan_with_reason():
    r = np.exp(-np.linspace(0.0, 3.0, 80))
    out = estimate_all(r, None, dt_of())
    for name in ("e_g", "e_0", "e1", "e2", "e3", "e4"):
        assert np.isnan(out[name].value) and out[name].reason == "no zero crossing"
    assert out["e_v"].reason == "no D_v signature"


def test_record_ending_before_first_minimum_gives_nan_with_reason():
    r, dt = sampled_free_response(0.9)
    short = r[: int(1.5 * t1_of() / dt)]  # past the crossing, before the minimum
    for name, est in estimate_all(short, None, dt).items():
        assert np.isnan(est.value)
        if name != "e_v":
            assert est.reason == "first minimum beyond the lag range"


def test_too_few_points_for_a_fit_gives_nan_with_reason():
    e, points_per_cycle = 0.5, 10  # second half cycle spans 2.5 dt: at most 2 samples after t1
    r, dt = sampled_free_response(e, points_per_cycle=points_per_cycle)
    for est in local_measures(r, dt).values():
        assert np.isnan(est.value) and est.reason == "fewer than 3 points for a fit"
    assert np.isfinite(e_first_peak(r).value)


def test_short_or_nan_dv_signature_gives_nan_with_reason():
    dt = dt_of()
    tau = dt * np.arange(-2, 3)
    assert "lags on a side" in e_impact_slope(through_impact(0.9, tau), dt, 5).reason
    assert e_impact_slope(np.full(21, np.nan), dt, 5).reason == "NaN in signature"
    with pytest.raises(ValueError, match="fit_points=2"):
        e_impact_slope(np.zeros(21), dt, 2)


def test_estimators_never_raise_and_reason_explains_every_nan():
    rng = np.random.default_rng(1)
    dt = dt_of()
    cases = [rng.standard_normal(40) for _ in range(200)]
    cases += [np.abs(rng.standard_normal(40)) + 0.1, np.zeros(40), np.array([1.0]), np.array([])]
    cases += [np.r_[1.0, rng.standard_normal(39)] for _ in range(200)]
    for r in cases:
        for est in estimate_all(r, rng.standard_normal(21), dt).values():
            assert isinstance(est, Estimate)
            assert (est.reason == "") == bool(np.isfinite(est.value))


# --- zero-window extrapolation -------------------------------------------------------

WINDOWS = np.linspace(0.125, 1.0, 8)


@pytest.mark.parametrize("weights", [None, np.arange(10.0, 18.0)])
def test_extrapolation_recovers_exact_line(weights):
    fit = extrapolate_to_zero(WINDOWS, 0.9626 - 0.0375 * WINDOWS, weights)
    assert fit.reason == ""
    assert fit.value == pytest.approx(0.9626, abs=1e-12)
    assert fit.slope == pytest.approx(-0.0375, abs=1e-12)
    assert fit.stderr == pytest.approx(0.0, abs=1e-12)


def test_extrapolation_stderr_matches_empirical_spread():
    """``y_i = 0.95 - 0.05 x_i + noise`` with ``Var = s^2/x_i`` (weights = x), 4000 draws.
    The RMS of the reported stderr estimates the true sd with relative sd about
    ``sqrt(2/6)/sqrt(4000)/2 = 0.5 %`` (6 residual degrees of freedom), the empirical sd of
    the intercepts about ``1/sqrt(2*4000) = 1.1 %``; 5 % is more than 4 sigma of both."""
    rng = np.random.default_rng(2024)
    draws = [
        extrapolate_to_zero(
            WINDOWS, 0.95 - 0.05 * WINDOWS + 0.01 * rng.standard_normal(8) / np.sqrt(WINDOWS)
        )
        for _ in range(4000)
    ]
    values = np.array([d.value for d in draws])
    stderr = np.array([d.stderr for d in draws])
    assert np.sqrt(np.mean(stderr**2)) == pytest.approx(values.std(ddof=1), rel=0.05)
    assert abs(values.mean() - 0.95) < 4 * values.std(ddof=1) / np.sqrt(values.size)


def test_zero_weight_point_has_no_influence():
    rng = np.random.default_rng(3)
    y = 0.95 - 0.05 * WINDOWS + 0.01 * rng.standard_normal(8)
    counts = np.arange(20.0, 28.0)
    without = extrapolate_to_zero(np.delete(WINDOWS, 3), np.delete(y, 3), np.delete(counts, 3))
    y[3], counts[3] = 100.0, 0.0  # an outlier of weight zero
    with_outlier = extrapolate_to_zero(WINDOWS, y, counts)
    assert with_outlier[:3] == pytest.approx(without[:3], rel=1e-12)


def test_extrapolation_default_weights_are_window_sizes_and_scale_free():
    rng = np.random.default_rng(4)
    y = 0.95 - 0.05 * WINDOWS + 0.01 * rng.standard_normal(8)
    default = extrapolate_to_zero(WINDOWS, y)
    assert extrapolate_to_zero(WINDOWS, y, WINDOWS) == default
    scaled = extrapolate_to_zero(WINDOWS, y, 7.0 * WINDOWS)
    assert scaled[:3] == pytest.approx(default[:3], rel=1e-12)
    by_counts = extrapolate_to_zero(WINDOWS, y, np.ones(8))
    assert by_counts.value != pytest.approx(default.value, rel=1e-6)


def test_extrapolation_drops_nan_and_needs_two_points():
    y = 0.95 - 0.05 * WINDOWS
    y[2] = np.nan
    assert extrapolate_to_zero(WINDOWS, y).value == pytest.approx(0.95, abs=1e-12)
    two = extrapolate_to_zero(WINDOWS[:2], y[:2])
    assert two.value == pytest.approx(0.95, abs=1e-12) and np.isnan(two.stderr)
    one = extrapolate_to_zero(WINDOWS[:3], y[:3] * [1.0, np.nan, np.nan])
    assert np.isnan(one.value) and one.reason == "fewer than 2 usable points"


# --- labelled wrappers ---------------------------------------------------------------


def signature_cube():
    """Free responses over ``(e_true, window)`` with a little noise, and ``D_v`` over ``e_true``."""
    rng = np.random.default_rng(5)
    e_true = np.array([0.5, 0.8, 0.95])
    window = np.array([0.25, 0.5, 0.75, 1.0])
    dt = dt_of()
    lag_pos = dt * np.arange(188)
    lag = dt * np.arange(-10, 11)
    r = np.stack([free_rocking(e, lag_pos) for e in e_true])[:, None, :]
    r = r + 1e-3 * window[None, :, None] * rng.standard_normal((3, 4, 188))
    d = np.stack([through_impact(e, lag) for e in e_true])
    free = xr.DataArray(
        r, dims=("e_true", "window", "lag_pos"), coords={"e_true": e_true, "window": window}
    )
    dv = xr.DataArray(d, dims=("e_true", "lag"), coords={"e_true": e_true})
    return free, dv, dt


@pytest.mark.parametrize("use_dask", [False, True])
def test_estimate_cube_equals_reference(use_dask):
    free, dv, dt = signature_cube()
    if use_dask:
        free, dv = free.chunk({"e_true": 1}), dv.chunk({"e_true": 1})
    out = estimate_cube(free, dv, dt, fit_points=5)
    assert (out["e_hat"].chunks is not None) == use_dask  # dask input stays lazy
    assert out["e_hat"].dims == ("estimator", "e_true", "window")
    assert list(out["estimator"].values) == list(ESTIMATORS)
    assert out["e_hat"].attrs["units"] == "1" and out["e_hat"].attrs["long_name"]
    e_hat = out["e_hat"].compute()
    for i in range(3):
        for j in range(4):
            expected = reference_estimate_all(free.values[i, j], dv.values[i], dt, 5)
            got = e_hat.isel(e_true=i, window=j)
            np.testing.assert_allclose(got.values, [v.value for v in expected.values()], rtol=1e-12, atol=0)


def test_estimate_cube_without_dv_signature_gives_nan_e_v():
    free, _, dt = signature_cube()
    out = estimate_cube(free, None, dt)
    assert out["e_hat"].sel(estimator="e_v").isnull().all()
    assert out["e_hat"].sel(estimator="e4").notnull().all()


@pytest.mark.parametrize("use_dask", [False, True])
def test_extrapolate_equals_kernel(use_dask):
    free, dv, dt = signature_cube()
    e_hat = estimate_cube(free, dv, dt)["e_hat"]
    counts = xr.DataArray([50.0, 110.0, 140.0, 200.0], dims="window")
    if use_dask:
        e_hat = e_hat.chunk({"e_true": 1})
    for weights in (None, counts):
        out = extrapolate(e_hat, weights).compute()
        assert set(out) == {"e_hat0", "e_hat0_stderr", "slope"}
        assert out["e_hat0"].attrs["units"] == "1"
        w = e_hat["window"].values if weights is None else counts.values
        for name in ESTIMATORS:
            for i in range(3):
                expected = extrapolate_to_zero(
                    e_hat["window"].values, e_hat.sel(estimator=name).isel(e_true=i).values, w
                )
                got = out.sel(estimator=name).isel(e_true=i)
                np.testing.assert_array_equal(
                    [got["e_hat0"], got["e_hat0_stderr"], got["slope"]], expected[:3]
                )


# --- the batch kernel against the per-signature reference -----------------------------
#
# ``reference_estimate_all`` (tests/reference_estimators.py) is the per-signature NumPy implementation
# (np.linalg.solve per fit, NumPy runs for the lobes); the kernels must give its values to
# 1e-12 (relative on real signatures), the same NaN and the same reasons.


def assert_same_estimates(got, expected, rtol=1e-12, atol=0.0):
    """Two lists of ``{name: Estimate}``: same reasons (so the same NaN), values to ``rtol``/``atol``."""
    assert [[e.reason for e in row.values()] for row in got] == [[e.reason for e in row.values()] for row in expected]
    values = np.array([[e.value for e in row.values()] for row in got])
    reference = np.array([[e.value for e in row.values()] for row in expected])
    np.testing.assert_array_equal(np.isnan(values), np.isnan(reference))
    np.testing.assert_allclose(values, reference, rtol=rtol, atol=atol)
    return reference


@pytest.fixture(scope="module")
def simulated_signatures():
    """Per-series and pooled signatures of 6 simulated series at 75 and at 9 samples per cycle
    (the coarse step leaves the half-cycle fits too few points), each free response also cut
    to a half and a third of its lags (minima beyond the range), each ``D_v`` also cut to 3
    lags a side (too few for the fits): ``[(r, d, dt)]``."""
    cases = []
    for dt in (0.00343, 0.0286):
        theta, _ = simulate.simulate_block(np.arange(6), 3000, dt=dt, g=1.0, e=0.95, sigma_p=0.003, burn_in=2000)
        stats = simulate.pilot_statistics(theta, dt, 1.0)
        theta = xr.DataArray(theta, dims=("seed", "time"), attrs={"dt": dt})
        kw = dict(sigma_y=stats["sigma_y"], sigma_ydot=stats["sigma_ydot"], windows=np.arange(1, 11) / 10, g=1.0)
        for group in (None, xr.DataArray([0, 0, 0, 1, 1, 1], dims="seed")):
            cube = signatures.signature_cube(theta, group=group, **kw)
            r = cube["free_response"].values.reshape(-1, cube.sizes["lag_pos"])
            d = cube["signature"].sel(trigger="v").values.reshape(-1, cube.sizes["lag"])
            lag0 = d.shape[1] // 2
            for i in range(r.shape[0]):
                for n_lag in (r.shape[1], r.shape[1] // 2, r.shape[1] // 3):
                    cases.append((r[i, :n_lag], d[i], dt))
                cases.append((r[i], d[i, lag0 - 3 : lag0 + 4], dt))
    return cases


def test_kernel_equals_reference_on_simulated_signatures(simulated_signatures):
    got = [estimate_all(r, d, dt) for r, d, dt in simulated_signatures]
    expected = [reference_estimate_all(r, d, dt) for r, d, dt in simulated_signatures]
    reference = assert_same_estimates(got, expected)
    reasons = {e.reason for row in expected for e in row.values()}
    assert {"fewer than 3 points for a fit", "first minimum beyond the lag range", "no zero crossing"} <= reasons
    assert {"NaN in signature", "fewer than fit_points=5 lags on a side"} <= reasons
    assert np.isfinite(reference).sum() > 2000  # most signatures give values


def test_estimate_cube_equals_reference_on_simulated_cube():
    dt = 0.00343
    theta, _ = simulate.simulate_block(np.arange(4), 3000, dt=dt, g=1.0, e=0.95, sigma_p=0.003, burn_in=2000)
    stats = simulate.pilot_statistics(theta, dt, 1.0)
    theta = xr.DataArray(theta, dims=("seed", "time"), attrs={"dt": dt})
    cube = signatures.signature_cube(theta, sigma_y=stats["sigma_y"], sigma_ydot=stats["sigma_ydot"], windows=np.arange(1, 9) / 8, g=1.0)
    free, dv = cube["free_response"], cube["signature"].sel(trigger="v", drop=True)
    loaded = estimate_cube(free, dv, dt)["e_hat"]
    chunked = estimate_cube(free.chunk({"seed": 3, "window": 5}), dv.chunk({"seed": 1}), dt)["e_hat"]
    assert chunked.chunks is not None
    xr.testing.assert_identical(chunked.compute(), loaded)  # the same kernel on every block
    without_dv = estimate_cube(free.chunk({"seed": 2}), None, dt)["e_hat"].compute()
    xr.testing.assert_identical(without_dv.drop_sel(estimator="e_v"), loaded.drop_sel(estimator="e_v"))
    assert without_dv.sel(estimator="e_v").isnull().all()
    expected = [
        reference_estimate_all(free.values[i, j], dv.values[i, j], dt) for i in range(free.sizes["seed"]) for j in range(free.sizes["window"])
    ]
    values = loaded.transpose("seed", "window", "estimator").values.reshape(-1, len(ESTIMATORS))
    reference = np.array([[e.value for e in row.values()] for row in expected])
    np.testing.assert_array_equal(np.isnan(values), np.isnan(reference))
    np.testing.assert_allclose(values, reference, rtol=1e-12, atol=0)


def test_single_estimator_functions_equal_reference(simulated_signatures):
    """The public one-estimator functions run the same kernels as the batch."""
    for r, d, dt in simulated_signatures[::7]:
        expected = reference_estimate_all(r, d, dt)
        lobes = _lobes(r)
        for name, func in (("e_g", e_global), ("e_0", e_first_peak)):
            assert func(r).reason == func(r, lobes).reason == expected[name].reason
            np.testing.assert_allclose(func(r).value, expected[name].value, rtol=1e-12, atol=0)
        local = local_measures(r, dt, lobes)
        assert_same_estimates([local], [{name: expected[name] for name in LOCAL_ESTIMATORS}])
        assert_same_estimates([{"e_v": e_impact_slope(d, dt)}], [{"e_v": expected["e_v"]}])
        h, h_ref = half_cycle(r, dt), reference_half_cycle(r, dt, reference_lobes(r))
        assert h.reason == h_ref.reason
        np.testing.assert_allclose(h[:6], h_ref[:6], rtol=1e-12, atol=0)


def test_kernel_equals_reference_on_arbitrary_input():
    """Noise, random walks and crafted corners reach every way a fit fails. Values here can
    be near zero after cancellation (e2 = v2/v1 of two noise slopes), so the tolerance is
    1e-12 absolute or relative, whichever is larger."""
    rng = np.random.default_rng(11)
    cases = []
    for k in range(3000):
        r = rng.standard_normal(rng.integers(1, 80))
        if k % 2:
            r[0] = abs(r[0]) + 0.5
        if k % 3 == 0:
            r = 0.1 * np.cumsum(r) + np.cos(np.arange(r.size) * rng.uniform(0.05, 0.5))
            r[0] = 1.0
        if k % 7 == 0:
            r[rng.integers(r.size)] = 0.0  # a zero inside a run or between runs
        d = rng.standard_normal(2 * rng.integers(0, 12) + 1)
        if k % 11 == 0:
            d[d.size // 2 - 3 : d.size // 2] = 1.0  # flat before the impact
        cases.append((r, d))
    cases += [
        (np.array([]), np.zeros(4)),  # empty, even D_v
        (np.zeros((3, 3)), np.zeros((3, 3))),  # not one-dimensional
        (np.r_[1e-300, -1e300, 1.0, 1.0, 0.5], np.r_[1e300, -1e300, 1.0, 1e300, 1e-300, 1e300, -1e300]),  # overflow
        (np.r_[1.0, 0.0, 0.0, -1.0, 0.0, 1.0, 0.0], None),
    ]
    got = [estimate_all(r, d, 0.05, 3) for r, d in cases]
    expected = [reference_estimate_all(r, d, 0.05, 3) for r, d in cases]
    assert_same_estimates(got, expected, rtol=1e-12, atol=1e-12)
    reasons = {e.reason for row in expected for e in row.values()}
    assert {
        "empty signature",
        "r[0] not positive",
        "before-crossing fit has no real root",
        "minimum fit has no minimum",
        "fitted crossing t1 not between 0 and t2",
        "not finite: the signature values overflow the arithmetic",
        "D_v signature length not odd: no lag 0",
        "zero slope before the impact",
        "no D_v signature",
    } <= reasons


@pytest.mark.parametrize("use_dask", [False, True])
def test_estimate_cube_recovers_e_on_ideal_responses(use_dask):
    """Closed-form responses (eqs. 4, 6) through the batch kernel: e1..e4 and e_v exact to rounding."""
    dt = dt_of()
    lag_pos, lag = dt * np.arange(188), dt * np.arange(-10, 11)
    e_true = np.array(E_VALUES)
    free = xr.DataArray(np.stack([free_rocking(e, lag_pos) for e in e_true]), dims=("e_true", "lag_pos"), coords={"e_true": e_true})
    dv = xr.DataArray(np.stack([through_impact(e, lag) for e in e_true]), dims=("e_true", "lag"), coords={"e_true": e_true})
    if use_dask:
        free, dv = free.chunk({"e_true": 2}), dv.chunk({"e_true": 3})
    e_hat = estimate_cube(free, dv, dt)["e_hat"].compute()
    exact = e_hat.sel(estimator=[*LOCAL_ESTIMATORS, "e_v"])
    np.testing.assert_allclose(exact.values, np.broadcast_to(e_true, exact.shape), rtol=0, atol=1e-9)


def test_kernels_check_their_inputs():
    r, dt = sampled_free_response(0.9)
    with pytest.raises(ValueError, match="dt"):
        estimate_all(r, None, 0.0)
    with pytest.raises(ValueError, match="fit_points=2"):
        estimate_all(r, np.zeros(21), dt, 2)
    assert estimate_all(r, None, dt, 2)["e_v"].reason == "no D_v signature"  # fit_points unused
    free = xr.DataArray(r[None], dims=("seed", "lag_pos"))
    with pytest.raises(ValueError, match="dt"):
        estimate_cube(free, None, -1.0)
    with pytest.raises(ValueError, match="fit_points=2"):
        estimate_cube(free, xr.DataArray(np.zeros((1, 21)), dims=("seed", "lag")), dt, 2)


# --- batched extrapolation against an independent weighted least squares -------------


def lstsq_extrapolation(x, y, w):
    """Weighted least squares by ``lstsq`` on ``sqrt(w)``-scaled rows, the covariance
    ``s^2 (X^T W X)^-1`` for the standard error: independent of the normal-equation sums of
    :func:`extrapolate_to_zero`, with the same point and NaN rules."""
    use = np.isfinite(x) & np.isfinite(y) & np.isfinite(w) & (w > 0)
    x, y, w = x[use], y[use], w[use]
    if x.size < 2 or np.all(x == x[0]):
        return np.nan, np.nan, np.nan
    design = np.stack([np.ones_like(x), x], axis=1)
    root = np.sqrt(w)
    (value, slope), *_ = np.linalg.lstsq(design * root[:, None], y * root, rcond=None)
    if x.size == 2:
        return value, np.nan, slope
    s2 = np.sum(w * (y - value - slope * x) ** 2) / (x.size - 2)
    cov = s2 * np.linalg.inv(design.T @ (w[:, None] * design))
    return value, np.sqrt(cov[0, 0]), slope


@pytest.mark.parametrize("use_dask", [False, True])
def test_extrapolate_equals_independent_least_squares(use_dask):
    rng = np.random.default_rng(6)
    n_rows = 300
    y = 0.95 - 0.05 * WINDOWS + 0.01 * rng.standard_normal((n_rows, WINDOWS.size))
    y[rng.random(y.shape) < 0.3] = np.nan  # rows with 0 .. 8 usable points
    y[:20, 2:] = np.nan  # two points: no stderr
    counts = rng.integers(0, 5, size=(n_rows, WINDOWS.size)).astype(float)  # some weights zero
    counts[20:30] = np.where(np.arange(WINDOWS.size) == 4, 1.0, 0.0)  # a single usable point
    e_hat = xr.DataArray(y, dims=("row", "window"), coords={"window": WINDOWS})
    w = xr.DataArray(counts, dims=("row", "window"))
    if use_dask:
        e_hat, w = e_hat.chunk({"row": 70}), w.chunk({"row": 110})
    for weights in (None, w):
        out = extrapolate(e_hat, weights).compute()
        expected = np.array(
            [lstsq_extrapolation(WINDOWS, y[i], WINDOWS if weights is None else counts[i]) for i in range(n_rows)]
        )
        got = np.stack([out["e_hat0"].values, out["e_hat0_stderr"].values, out["slope"].values], axis=1)
        np.testing.assert_array_equal(np.isnan(got), np.isnan(expected))
        np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-12)
        assert np.isnan(expected[:, 0]).sum() > 5 and np.isnan(expected[:, 1]).sum() > 15  # every NaN rule met


def test_extrapolation_refuses_negative_weights_and_flags_one_window():
    with pytest.raises(ValueError, match="non-negative"):
        extrapolate_to_zero(WINDOWS, WINDOWS, -WINDOWS)
    same = extrapolate_to_zero(np.full(4, 0.5), np.arange(4.0))
    assert np.isnan(same.value) and same.reason == "all points at one window size"

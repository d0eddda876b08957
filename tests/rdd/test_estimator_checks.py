"""Common checks run over every registered estimator (:mod:`rockdec.rdd.registry`).

Whatever an estimator computes, it must: recover ``e`` from the ideal responses of the
simplified model (eqs. 4, 6, in closed form), be invariant to the scales of angle and time,
answer a NaN window with NaN and a reason, and give the same value through the labelled
cube (:func:`rockdec.rdd.estimators.estimate_cube`) as on one record
(:func:`rockdec.rdd.estimators.estimate_all`), and through the workflow's cube path as through
the analysis of a measured record (:func:`rockdec.rdd.measured.analyse`): one analysis core
(:func:`rockdec.rdd.estimators.window_estimates`, :func:`rockdec.rdd.estimators.zero_window`). A
new estimator passes these before anything else.
"""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from conftest import calibrated_step
from test_estimators import A, G, free_rocking, t1_of, through_impact

from rockdec.rdd import estimators, measured, registry, signatures
from rockdec.pipeline import replicates
from rockdec.physics import simulate
from rockdec.rdd.estimators import DEFAULT_FIT_POINTS, estimate_all, estimate_cube

NAMES = registry.ESTIMATORS
POINTS_PER_CYCLE = 2000
"""Fine sampling: the sampled extremes of ``e_g`` and ``e_0`` then miss the true ones by
``g dt^2/8`` (tests/rdd/test_estimators.py), below the tolerance."""
TOLERANCE = 1e-4


def ideal_signatures(e: float, points_per_cycle: int = POINTS_PER_CYCLE, angle: float = 1.0, time: float = 1.0):
    """The ideal free response from ``(a, 0)`` over 1.6 periods and the ideal ``D_v`` through
    an impact at lag 0 (closed forms, eqs. 4, 6), with angles scaled by ``angle`` and times by
    ``time`` (``g`` becomes ``angle g / time^2``). Returns ``(r, d, dt)``."""
    dt = 4.0 * t1_of() / points_per_cycle
    lag_pos = dt * np.arange(int(1.6 * points_per_cycle))
    lag = dt * np.arange(-40, 41)
    return angle * free_rocking(e, lag_pos, a=A, g=G), angle * through_impact(e, lag), time * dt


def test_registry_names_are_unique_and_declare_a_known_trigger():
    assert len(set(NAMES)) == len(NAMES)
    assert {s.trigger for s in registry.REGISTRY} <= {"a", "v"}
    assert registry.DEFAULT_ESTIMATOR in registry.CANDIDATES
    assert sorted(s.rank for s in registry.REGISTRY) == list(range(1, len(NAMES) + 1))


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("e", (0.8, 0.95))
def test_recovers_e_from_the_ideal_response(name, e):
    r, d, dt = ideal_signatures(e)
    est = estimate_all(r, d, dt)[name]
    assert est.reason == ""
    assert est.value == pytest.approx(e, abs=TOLERANCE)


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("angle, time", [(1e-3, 1.0), (1.0, 37.0), (250.0, 1e-2)])
def test_invariant_to_angle_and_time_scales(name, angle, time):
    r, d, dt = ideal_signatures(0.9, points_per_cycle=75)
    reference = estimate_all(r, d, dt)[name].value
    scaled = estimate_all(*ideal_signatures(0.9, points_per_cycle=75, angle=angle, time=time))[name].value
    assert np.isfinite(reference)
    assert scaled == pytest.approx(reference, rel=1e-9)


@pytest.mark.parametrize("name", NAMES)
def test_nan_window_gives_nan_with_a_reason(name):
    r, d, dt = ideal_signatures(0.9, points_per_cycle=75)
    if registry.trigger(name) == "a":
        r = r.copy()
        r[len(r) // 3] = np.nan
    else:
        d = d.copy()
        d[len(d) // 2 - 2] = np.nan
    est = estimate_all(r, d, dt)[name]
    assert np.isnan(est.value)
    assert est.reason == "NaN in signature"


@pytest.mark.parametrize("use_dask", [False, True])
def test_cube_path_equals_single_record_path(use_dask):
    """Every estimator, every window of a small labelled cube, against one record at a time."""
    rng = np.random.default_rng(5)
    rows = [ideal_signatures(e, points_per_cycle=75) for e in (0.6, 0.8, 0.9, 0.95)]
    dt = rows[0][2]
    free = np.stack([r + 0.01 * rng.standard_normal(r.size) for r, _, _ in rows])
    dv = np.stack([d + 0.01 * rng.standard_normal(d.size) for _, d, _ in rows])
    free_da = xr.DataArray(free, dims=("window", "lag_pos"))
    dv_da = xr.DataArray(dv, dims=("window", "lag"))
    if use_dask:
        free_da, dv_da = free_da.chunk({"window": 3}), dv_da.chunk({"window": 2})
    cube = estimate_cube(free_da, dv_da, dt)["e_hat"].compute()
    assert list(cube["estimator"].values) == list(NAMES)
    for w in range(free.shape[0]):
        single = estimate_all(free[w], dv[w], dt, DEFAULT_FIT_POINTS)
        for name in NAMES:
            np.testing.assert_array_equal(cube.sel(estimator=name).values[w], single[name].value)


def test_docs_list_every_registered_estimator():
    """The method (docs/method.md and its pages, §5 the estimators) names each estimator and the
    recipe for a new one exists."""
    from pathlib import Path

    docs = Path(__file__).resolve().parents[2] / "docs"
    method = "\n".join(p.read_text() for p in [docs / "method.md", *sorted((docs / "explanation" / "method").glob("*.md"))])
    for spec in registry.REGISTRY:
        assert f"`{spec.name}`" in method, spec.name
    assert "registry" in (docs / "development" / "adding-an-estimator.md").read_text()


def sums_of(r, d, count=1.0):
    """Signature sums and counts ``(trigger, window, lag)`` whose signatures are the two-sided
    ``D_a`` with even part ``r`` (``r`` mirrored) and ``D_v`` ``d``, each from ``count``
    triggers (``r`` and ``d`` one row per window, ``d`` of ``2 len(r) - 1`` lags)."""
    two_sided = np.concatenate([r[..., :0:-1], r], axis=-1)
    sums = count * np.stack([two_sided, d])
    return sums, np.full(sums.shape[:-1], count)


@pytest.mark.parametrize("e", (0.8, 0.95))
def test_core_recovers_e_and_g_from_ideal_sums_at_any_count(e):
    """The analysis core on sums of ideal signatures (eqs. 4, 6): every estimator within
    :data:`TOLERANCE` of ``e``, ``g`` = ``G`` (``2 c1/t1^2`` of the free flight), and the
    same values whatever the number of triggers pooled (only ``sum/count`` matters)."""
    r, _, dt = ideal_signatures(e)
    n_lag = r.size - 1
    d = through_impact(e, dt * np.arange(-n_lag, n_lag + 1))
    rows = np.stack([r, r]), np.stack([d, d])  # two windows
    values = estimators.window_estimates(*sums_of(*rows), dt)
    assert values.shape == (len(estimators.COLUMNS), 2)
    np.testing.assert_allclose(values[: len(NAMES)], e, atol=TOLERANCE)
    np.testing.assert_allclose(values[estimators.COLUMNS.index(estimators.G_NAME)], G, rtol=1e-9)
    np.testing.assert_allclose(estimators.window_estimates(*sums_of(*rows, count=37.0), dt), values, rtol=1e-12)


def test_count_weights_are_the_counts_of_each_estimators_trigger():
    """``weights="count"`` weights each estimator by its own trigger's counts
    (:func:`rockdec.rdd.registry.trigger`); ``"window"`` by the window sizes (paper §5)."""
    rng = np.random.default_rng(3)
    windows = np.arange(1, 7) / 6
    values = 0.9 + 0.01 * rng.standard_normal((len(estimators.COLUMNS), windows.size))
    counts = np.stack([np.arange(10, 70, 10), np.array([90, 5, 40, 2, 60, 30])])
    for weights in ("window", "count"):
        value, stderr, slope = estimators.zero_window(windows, values, counts, weights)
        for k, name in enumerate(NAMES):
            w = windows if weights == "window" else counts[signatures.TRIGGERS.index(registry.trigger(name))]
            expected = estimators.extrapolate_to_zero(windows, values[k], w)
            np.testing.assert_array_equal([value[k], stderr[k], slope[k]], expected[:3])
    with pytest.raises(ValueError, match="unknown extrapolation weights"):
        estimators.zero_window(windows, values, counts, "triggers")


@pytest.fixture(scope="module")
def one_record():
    cal = calibrated_step(0.9, G, 0.003)
    theta, _ = simulate.simulate_block([3], 30_000, dt=cal["dt"], g=G, e=0.9, sigma_p=0.003, burn_in=cal["burn_in"])
    return theta[0], cal["dt"]


@pytest.mark.parametrize("use_dask", [False, True])
@pytest.mark.parametrize("weights", ["window", "count"])
def test_cube_path_equals_the_analysis_of_a_measured_record(one_record, use_dask, weights):
    """The workflow's path (a signature cube, :func:`rockdec.pipeline.replicates.replicate_curves`,
    :func:`rockdec.pipeline.replicates.extrapolated`) on a record, at the trigger levels and lag range
    :func:`rockdec.rdd.measured.analyse` chose for it, gives its window curves, ``g`` and
    zero-window values to 1e-12."""
    theta, dt = one_record
    analysis = measured.analyse([theta], dt, {"weights": weights})
    y = theta - theta.mean()
    sigma_ydot = float(np.sqrt(np.mean((np.diff(y) / dt) ** 2)))
    series = xr.DataArray(y[None], dims=("seed", "time"), attrs={"dt": dt})
    cube = signatures.signature_cube(series, sigma_y=analysis.sigma_y, sigma_ydot=sigma_ydot, n_lag=analysis.n_lag)
    if use_dask:
        cube = cube.chunk({"seed": 1})
    cube = cube.assign_coords(replicate=("seed", [0]))
    window = estimators.window_cube(cube, DEFAULT_FIT_POINTS)
    assert (window["e_hat"].chunks is not None) == use_dask  # lazy stays lazy
    np.testing.assert_allclose(window["g_hat"].isel(seed=0).values, analysis.per_window["g"], rtol=1e-12)
    est = replicates.extrapolated(replicates.replicate_curves(cube, fit_points=DEFAULT_FIT_POINTS), weights).compute()
    for name in NAMES:
        np.testing.assert_allclose(est["e_hat"].sel(estimator=name, replicate=0).values, analysis.per_window[name], rtol=1e-12)
        np.testing.assert_allclose(est["e_hat0"].sel(estimator=name, replicate=0).values, analysis.raw[name], rtol=1e-12)
    np.testing.assert_array_equal(est["count"].sel(replicate=0).values, np.stack([analysis.count["a"], analysis.count["v"]]))


def test_window_cube_refuses_a_bad_step_or_fit_before_computing(one_record):
    theta, dt = one_record
    series = xr.DataArray(theta[None, :6000], dims=("seed", "time"), attrs={"dt": dt}).chunk({"seed": 1})
    cube = signatures.signature_cube(series, sigma_y=float(theta.std()), sigma_ydot=1.0, n_lag=40)
    with pytest.raises(ValueError, match="dt"):
        estimators.window_cube(cube.assign_attrs(dt=-1.0))
    with pytest.raises(ValueError, match="fit_points=2"):
        estimators.window_cube(cube, 2)

"""Replicates, readings and tables: grouping rules, t-tests, and the paper scene at reduced size."""

import math

import dask
import numpy as np
import pytest
import xarray as xr

from rockdec import config, replicates, simulate, tables


def test_grouping_of_each_reading():
    seeds = np.arange(3 * 250).reshape(3, 250)
    used, group, rep = replicates.grouping(seeds, "pooled")
    assert used.size == 750 and np.array_equal(group, np.repeat([0, 1, 2], 250)) and np.array_equal(rep, [0, 1, 2])
    used, group, rep = replicates.grouping(seeds, "per_series")
    assert used.size == 300 and np.array_equal(used[:100], np.arange(100)) and np.array_equal(used[100:200], np.arange(250, 350))
    assert np.array_equal(group, np.arange(300)) and np.array_equal(np.bincount(rep), [100, 100, 100])
    used, group, rep = replicates.grouping(seeds, "groups_of_10")
    assert used.size == 3 * 250 and np.array_equal(np.bincount(group), np.full(75, 10)) and np.array_equal(np.bincount(rep), [25] * 3)
    with pytest.raises(ValueError, match="unknown reading"):
        replicates.grouping(seeds, "mystery")
    with pytest.raises(ValueError, match="at least 10"):
        replicates.grouping(seeds[:, :5], "groups_of_10")


def test_bias_row_matches_the_t_statistic_formula():
    values = np.array([0.951, 0.957, 0.949, 0.962, 0.955, np.nan])
    row = tables.bias_row(values, 0.95)
    finite = values[:-1]
    t = (finite.mean() - 0.95) / (finite.std(ddof=1) / math.sqrt(finite.size))
    assert row["n"] == 5 and row["t"] == pytest.approx(t, rel=1e-12)
    assert row["bias"] == pytest.approx(finite.mean() - 0.95)
    assert 0 < row["p_value"] < 1
    assert np.isnan(tables.bias_row(np.array([0.9]), 0.95)["t"])  # one replicate: no test


def test_paper_columns_only_for_the_paper_target():
    e_hat0 = xr.DataArray(np.full((2, 3), 0.9), dims=("estimator", "replicate"), coords={"estimator": ["e1", "e_v"]})
    table = tables.summary_table(e_hat0, 0.95)
    assert table.set_index("estimator").loc["e1", "paper_mean"] == 0.9628
    assert np.isnan(table.set_index("estimator").loc["e_v", "paper_mean"])
    assert np.isnan(tables.summary_table(e_hat0, 0.8)["paper_mean"]).all()
    assert "| e1" in tables.to_markdown(table)


@pytest.fixture(scope="module")
def reduced_paper():
    """The paper scene at reduced size: 8 replicates of 150 pooled series (paper: 20 x ~1000)."""
    cfg = config.load()
    scene = config.scene(cfg, "paper")
    scene["records"].update(replicates=8, series_per_replicate=150, chunk_seeds=150)
    params = simulate.scene_parameters(scene)
    attrs = {**params, "n_points": scene["records"]["n_points"], "theta0": 0.0, "theta_dot0": 0.0}
    with dask.config.set(scheduler="threads", num_workers=2):
        cube = replicates.reading_cube(attrs, scene, "pooled").compute()
    return replicates.replicate_estimates(cube, **replicates.estimate_options(scene))


def test_reduced_paper_scene_lands_near_the_papers_means(reduced_paper):
    """e_0, e1, e3, e4 at zero window against the paper (§5, eq. 28).

    Tolerance: 4 standard errors of the difference, our replicate mean (8 replicates of 150
    series, so each replicate scatters about sqrt(1000/150) ~ 2.6 times the paper's) and the
    paper's mean (its std / sqrt(20)); never more than 0.03.
    """
    table = tables.summary_table(reduced_paper["e_hat0"], 0.95).set_index("estimator")
    for name in ("e_0", "e1", "e3", "e4"):
        row = table.loc[name]
        paper_se = (row.paper_std if np.isfinite(row.paper_std) else 0.005) / math.sqrt(20)
        tolerance = min(4 * math.hypot(row["std"] / math.sqrt(row["n"]), paper_se), 0.03)
        assert abs(row["mean"] - row.paper_mean) < tolerance, (name, row["mean"], row.paper_mean, tolerance)


def test_impact_slope_estimator_is_unbiased_on_the_reduced_scene(reduced_paper):
    """e_v (the paper's §6 proposal): no bias detectable at 3 standard errors."""
    row = tables.bias_row(reduced_paper["e_hat0"].sel(estimator="e_v").values, 0.95)
    assert abs(row["bias"]) < 3 * row["std"] / math.sqrt(row["n"]) + 1e-3


def test_alternative_weights_sit_beside_the_table():
    e_hat0 = xr.DataArray([[0.95, 0.96], [0.90, 0.92]], dims=("estimator", "replicate"), coords={"estimator": ["e1", "e4"]})
    table = tables.with_alternative(tables.summary_table(e_hat0, 0.95), e_hat0 + 0.01, "count_weights", 0.95)
    np.testing.assert_allclose(table["mean_count_weights"], table["mean"] + 0.01)
    np.testing.assert_allclose(table["std_count_weights"], table["std"])

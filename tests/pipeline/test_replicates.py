"""Replicates, readings and tables: grouping rules, t-tests, and the paper scene at reduced size."""

import math

import numpy as np
import pandas as pd
import pytest
import xarray as xr

from rockdec.pipeline import config, layout, replicates, series
from rockdec.physics import run
from rockdec.report import tables


def test_groups_of_each_reading():
    seeds = np.arange(3 * 250).reshape(3, 250)
    group, rep = replicates.reading_groups(seeds, "pooled")
    assert np.array_equal(group, np.repeat([0, 1, 2], 250)) and np.array_equal(rep, [0, 1, 2])
    group, rep = replicates.reading_groups(seeds, "per_series")
    used = seeds.ravel()[group >= 0]
    assert used.size == 300 and np.array_equal(used[:100], np.arange(100)) and np.array_equal(used[100:200], np.arange(250, 350))
    assert np.array_equal(group[group >= 0], np.arange(300)) and np.array_equal(np.bincount(rep), [100, 100, 100])
    group, rep = replicates.reading_groups(seeds, "groups_of_10")
    assert np.array_equal(np.bincount(group), np.full(75, 10)) and np.array_equal(np.bincount(rep), [25] * 3)
    with pytest.raises(ValueError, match="unknown reading"):
        replicates.reading_groups(seeds, "mystery")
    with pytest.raises(ValueError, match="at least 10"):
        replicates.reading_groups(seeds[:, :5], "groups_of_10")


def test_the_units_of_one_pass_rebuild_every_reading_exactly():
    """Each reading's groups are unions of units, and no unit mixes two groups of a reading."""
    seeds = np.arange(3 * 137).reshape(3, 137)  # not a multiple of 10: groups_of_10 leaves 7 a replicate out
    unit, groups = replicates.pass_units(seeds, replicates.READINGS)
    for reading in replicates.READINGS:
        group, rep = replicates.reading_groups(seeds, reading)
        group_of_unit, rep_of_group = groups[reading]
        assert np.array_equal(rep_of_group, rep)
        rebuilt = np.where(unit >= 0, group_of_unit[np.maximum(unit, 0)], -1)
        assert np.array_equal(rebuilt, group), reading
    # a series some reading keeps alone is a unit of its own; the others pool by tens
    assert np.bincount(unit[unit >= 0]).max() == 10 and (unit >= 0).sum() == 3 * 137
    assert unit.max() + 1 == 3 * (100 + 3 + 1)  # 100 alone, 3 tens, and the 7 left over


@pytest.fixture(scope="module")
def tiny():
    """The tiny scene at 2 replicates of 20 series, and its run."""
    scene = config.scene(config.load(), "tiny")
    scene["records"].update(replicates=2, series_per_replicate=20, chunk_seeds=8, n_points=4000)
    scene["excitation"].update(dt=0.0034, burn_in=2000)
    return scene, run.from_scene(scene)


def test_one_pass_gives_each_reading_as_its_own_pass_does(tiny):
    """All readings from one pass equal one pass per reading (the former rule `readings`):
    counts exactly, signature sums and extrapolated estimates to 1e-12."""
    scene, contract = tiny
    rec, sig = scene["records"], scene["signatures"]
    one_pass = replicates.scene_cubes(contract, rec, sig, replicates.READINGS, threads=2)
    for reading in replicates.READINGS:
        group, rep = replicates.reading_groups(run_seeds := layout.scene_seeds(rec), reading)
        used = run_seeds.ravel()[group >= 0]
        theta = series.as_recorded(contract.dataset(used, rec["n_points"], chunk_seeds=rec["chunk_seeds"])["theta"])
        alone = replicates.scene_signatures(
            theta, sig, sigma_y=contract.sigma_y, sigma_ydot=contract.sigma_ydot, g=contract.g,
            group=group[group >= 0], replicate_of_group=rep,
        ).compute()
        got = one_pass[reading]
        assert np.array_equal(got["count"].values, alone["count"].values), reading
        np.testing.assert_allclose(got["signature_sum"].values, alone["signature_sum"].values, rtol=1e-12, atol=1e-15)
        est_got = replicates.replicate_estimates(got, fit_points=5)["e_hat0"].values
        est_alone = replicates.replicate_estimates(alone, fit_points=5)["e_hat0"].values
        np.testing.assert_allclose(est_got, est_alone, rtol=1e-12, atol=1e-12, err_msg=reading)
        assert np.isfinite(est_got).sum() > 0


def test_readings_table_lists_every_reading_with_the_true_e(tiny):
    scene, contract = tiny
    cubes = replicates.scene_cubes(contract, scene["records"], scene["signatures"], replicates.READINGS)
    curves = replicates.reading_curves(cubes, fit_points=5)
    assert curves.attrs["e_target"] == scene["system"]["e"]
    combined, table = replicates.readings_estimates(curves, "window")
    assert list(combined["reading"].values) == list(replicates.READINGS)
    assert list(pd.unique(table["reading"])) == list(replicates.READINGS)
    own, _ = replicates.scene_estimates(cubes["pooled"], scene["estimates"])
    np.testing.assert_array_equal(combined["e_hat0"].sel(reading="pooled").values, own["e_hat0"].values)
    assert own.attrs["e_target"] == scene["system"]["e"]



def test_readings_kept_as_sums_only_give_the_same_sums_and_window_curves(tiny):
    """``sums_only`` leaves out a reading's signature and free response, and nothing its
    window curves read: the curves are the finished cubes' bit for bit."""
    scene, contract = tiny
    rec, sig = scene["records"], scene["signatures"]
    finished = replicates.scene_cubes(contract, rec, sig, replicates.READINGS)
    sums = replicates.scene_cubes(contract, rec, sig, replicates.READINGS, sums_only=replicates.READINGS[1:])
    assert {"signature", "free_response"} <= set(sums["pooled"].data_vars)
    for reading in replicates.READINGS[1:]:
        assert set(sums[reading].data_vars) == {"signature_sum", "count", "skipped"}
        for name in ("signature_sum", "count", "skipped"):
            assert np.array_equal(sums[reading][name].values, finished[reading][name].values), (reading, name)
    got, want = replicates.reading_curves(sums, fit_points=5), replicates.reading_curves(finished, fit_points=5)
    assert np.array_equal(got["e_hat"].values, want["e_hat"].values, equal_nan=True)
    assert np.array_equal(got["count"].values, want["count"].values)

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
    assert "| `e1`" in tables.to_markdown(table)


@pytest.fixture(scope="module")
def reduced_paper():
    """The paper scene at reduced size: 8 replicates of 150 pooled series (paper: 20 x ~1000)."""
    cfg = config.load()
    scene = config.scene(cfg, "paper")
    scene["records"].update(replicates=8, series_per_replicate=150, chunk_seeds=150)
    contract = run.from_scene(scene)
    cube = replicates.scene_cubes(contract, scene["records"], scene["signatures"], ["pooled"], threads=2)["pooled"]
    return replicates.replicate_estimates(cube, fit_points=scene["estimates"]["fit_points"], weights=scene["estimates"]["weights"])


@pytest.mark.slow
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


@pytest.mark.slow
def test_impact_slope_estimator_is_unbiased_on_the_reduced_scene(reduced_paper):
    """e_v (the paper's §6 proposal): no bias detectable at 3 standard errors."""
    row = tables.bias_row(reduced_paper["e_hat0"].sel(estimator="e_v").values, 0.95)
    assert abs(row["bias"]) < 3 * row["std"] / math.sqrt(row["n"]) + 1e-3


def test_alternative_weights_sit_beside_the_table():
    e_hat0 = xr.DataArray([[0.95, 0.96], [0.90, 0.92]], dims=("estimator", "replicate"), coords={"estimator": ["e1", "e4"]})
    table = tables.with_alternative(tables.summary_table(e_hat0, 0.95), e_hat0 + 0.01, "count_weights", 0.95)
    np.testing.assert_allclose(table["mean_count_weights"], table["mean"] + 0.01)
    np.testing.assert_allclose(table["std_count_weights"], table["std"])


def test_a_scene_split_into_jobs_gathers_to_the_whole_scene(tiny):
    """Jobs of `replicates_per_job` replicates (a cluster's DAG) give the one-job numbers: the
    same seeds, chunks aligned with the jobs, so the sums are equal bit for bit."""
    scene, contract = tiny
    rec = {**scene["records"], "replicates": 3, "series_per_replicate": 16, "chunk_seeds": 8, "replicates_per_job": 2}
    sig, readings = scene["signatures"], list(replicates.READINGS)
    whole = replicates.scene_cubes(contract, {**rec, "replicates_per_job": None}, sig, readings)
    parts = [layout.part_records(rec, part) for part in layout.signature_parts(rec)]
    assert [(p["replicates"], first) for p, first in parts] == [(2, 0), (1, 2)]
    cubes = [replicates.scene_cubes(contract, p, sig, readings, first_replicate=first) for p, first in parts]
    cube, curves = replicates.gathered([c["pooled"] for c in cubes], [replicates.reading_curves(c, 5) for c in cubes])
    for name in ("signature_sum", "count", "skipped", "replicate", "group"):
        assert np.array_equal(cube[name].values, whole["pooled"][name].values, equal_nan=True), name
    np.testing.assert_array_equal(curves["e_hat"].values, replicates.reading_curves(whole, 5)["e_hat"].values)
    with pytest.raises(ValueError, match="outside"):
        layout.part_records(rec, 2)

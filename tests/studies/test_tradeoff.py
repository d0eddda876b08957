"""The speed/accuracy study: configurations, statistics, the cheapest passing choice, one tiny run."""

import numpy as np
import pandas as pd
import pytest

from rockdec.pipeline import config
from rockdec.report import figures, tables
from rockdec import io
from rockdec.studies import figures as study_figures
from rockdec.studies import tradeoff


@pytest.fixture
def scene():
    return config.scene(config.load(), "tradeoff")


def test_points_per_cycle_keeps_the_record_duration(scene):
    base = tradeoff.base_settings(scene)
    assert base == {"simulator": "exact", "points_per_cycle": 75.0, "n_points": 6000, "series_per_replicate": 200,
                    "n_windows": 10, "level": 2.0, "n_periods": 2.5}
    fine = tradeoff.variant_scene(scene, tradeoff.knob_settings(base, "points_per_cycle", 300))
    assert fine["records"]["n_points"] == 24000 and fine["estimates"]["fit_points"] == scene["estimates"]["fit_points"]
    coarse = tradeoff.variant_scene(scene, tradeoff.knob_settings(base, "points_per_cycle", 5))
    assert coarse["records"]["n_points"] == 400
    five = tradeoff.variant_scene(scene, tradeoff.knob_settings(base, "n_windows", 5))
    assert five["signatures"]["windows"] == [0.2, 0.4, 0.6, 0.8, 1.0]
    fixed = tradeoff.knob_settings(base, "fixed_step_points_per_cycle", 300)
    assert fixed["simulator"] == "fixed_step" and fixed["points_per_cycle"] == 300.0
    assert scene["excitation"]["points_per_cycle"] == 75  # the base scene is left alone
    with pytest.raises(ValueError, match="unknown knob"):
        tradeoff.knob_settings(base, "colour", 1)
    with pytest.raises(ValueError, match="simplified model"):
        tradeoff.run_study({**scene, "model": "housner"})


def test_every_knob_lists_the_base_value_once(scene):
    configs = tradeoff.configurations(scene)
    base = tradeoff.base_settings(scene)
    on_base = [knob for knob, _, s in configs if s == base]
    assert on_base == [k for k in tradeoff.KNOBS if k != "fixed_step_points_per_cycle"]
    assert len(configs) == sum(len(v) for v in tradeoff.KNOBS.values())


def _synthetic_table():
    rows = [
        # knob, value, cost, estimator, bias, std, n
        ("n_points", "1500", 1.0, "e4", 0.004, 0.010, 20),   # ci95 0.0236
        ("n_points", "3000", 2.0, "e4", 0.002, 0.003, 20),   # ci95 0.0079
        ("n_points", "6000", 4.0, "e4", 0.001, 0.001, 20),   # ci95 0.00296 (base)
        ("level", "2", 4.0, "e4", 0.001, 0.001, 20),         # the base again, under another knob
        ("level", "2.5", 3.0, "e4", 0.0, 0.002, 19),         # ci95 0.0039 but one replicate failed
        ("n_points", "1500", 1.0, "e_v", 0.030, 0.010, 20),  # ci95 0.0496
        ("n_points", "3000", 2.0, "e_v", 0.020, 0.001, 20),  # ci95 0.02196, rmse ~0.02002
        ("n_points", "6000", 4.0, "e_v", 0.015, 0.001, 20),
        ("level", "2", 4.0, "e_v", 0.015, 0.001, 20),
        ("level", "2.5", 3.0, "e_v", 0.2, 0.1, 20),
    ]
    table = pd.DataFrame(rows, columns=["knob", "value", "cpu_s", "estimator", "bias", "std", "n"])
    table["kind"] = "exact"
    table["replicates"] = 20
    table["base"] = table["value"].isin(["6000", "2"])
    table["cpu_s_per_replicate"] = table["cpu_s"] / 20
    table["rmse"] = np.sqrt(table["bias"] ** 2 + table["std"] ** 2 * 19 / 20)
    table["ci95"] = table["bias"].abs() + 1.96 * table["std"]
    return table


def test_recommend_picks_the_cheapest_passing_configuration():
    rec = tradeoff.recommend(_synthetic_table(), [0.005, 0.01, 0.025, 0.05]).set_index(["tolerance", "estimator"])
    # by hand: the cheapest row with |bias| + 1.96 std within the tolerance and no failed replicate
    assert rec.loc[(0.005, "e4"), "knob"] == "base" and rec.loc[(0.005, "e4"), "cpu_s"] == 4.0
    assert (rec.loc[(0.01, "e4"), "knob"], rec.loc[(0.01, "e4"), "value"]) == ("n_points", "3000")
    assert rec.loc[(0.025, "e4"), "value"] == "1500"
    assert rec.loc[(0.01, "e_v"), "knob"] == "none" and np.isnan(rec.loc[(0.01, "e_v"), "cpu_s"])
    assert rec.loc[(0.025, "e_v"), "value"] == "3000"
    assert rec.loc[(0.05, "e_v"), "value"] == "1500"
    by_rmse = tradeoff.recommend(_synthetic_table(), 0.02, criterion="rmse").set_index("estimator")
    assert by_rmse.loc["e_v", "knob"] == "base"  # rmse 0.02002 at 3000 misses 0.02; the base passes
    assert by_rmse.loc["e4", "value"] == "1500"
    with pytest.raises(ValueError, match="criterion"):
        tradeoff.recommend(_synthetic_table(), 0.01, criterion="mae")


def test_pareto_front_keeps_only_undominated_points():
    cost = [1.0, 2.0, 2.0, 3.0, 4.0, np.nan, 5.0]
    error = [0.5, 0.3, 0.2, 0.25, 0.1, 0.01, np.nan]
    assert tradeoff.pareto_front(cost, error).tolist() == [0, 2, 4]


@pytest.mark.filterwarnings("ignore::rockdec.rdd.signatures.NoTriggerWarning")
def test_tiny_study_end_to_end(scene, tmp_path):
    scene["records"].update(replicates=2, series_per_replicate=3, n_points=2500, chunk_seeds=2)
    knobs = {"level": (1.5, 2.0), "simulator": ("exact", "fixed_step")}
    ds = tradeoff.run_study(scene, knobs, threads=2, pilot={"pilot_seeds": 8, "pilot_points": 5000})
    assert ds.sizes == {"config": 4, "estimator": 7, "replicate": 2}
    assert ds["base"].values.tolist() == [0, 1, 1, 0]
    assert (ds["cpu_s"] > 0).all() and ds["cpu_s"][1] == ds["cpu_s"][2]  # the base runs once
    # the fixed-step record is analysed with its own (larger) sigma_Y
    assert float(ds["sigma_y"][3]) > float(ds["sigma_y"][0])
    table = tradeoff.study_table(ds)
    io.write_netcdf(ds, tmp_path / "tradeoff.nc")
    with io.open_dataset(tmp_path / "tradeoff.nc") as back:
        pd.testing.assert_frame_equal(tradeoff.study_table(back.load()), table)
    for col in ("knob", "value", "kind", "cpu_s", "estimator", "bias", "std", "rmse", "n", "ci95"):
        assert col in table.columns
    assert "t" not in table.columns and "p_value" not in table.columns  # the study's columns as before
    assert len(table) == 4 * 7
    ok = table[table["n"] > 1]
    assert len(ok) > 0
    np.testing.assert_allclose(ok["rmse"] ** 2, ok["bias"] ** 2 + ok["std"] ** 2 * (ok["n"] - 1) / ok["n"], rtol=1e-12)
    recommendations = {criterion: tradeoff.recommend(table, criterion=criterion) for criterion in tradeoff.CRITERIA}
    markdown = tables.tradeoff_markdown(table, recommendations)
    assert markdown.count("## Cheapest configuration") == 2 and "Target e = 0.95" in markdown
    fig = study_figures.pareto_figure(table)
    assert len([ax for ax in fig.axes if ax.get_visible()]) == 4

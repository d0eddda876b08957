"""The campaign sheet (rockdec.pipeline.campaign.read_sheet): every kind of bad row refused in
one sentence that names its row and its column, before any job; what a good sheet completes;
the plan reads the calibration the estimate then asks for; the summary's table. Without
Snakemake (the campaign through the workflow: test_campaign_workflow.py)."""

from __future__ import annotations

import json
import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
import xarray as xr

import rockdec
from rockdec.pipeline import campaign
from rockdec.pipeline.campaign import SheetError

DT = 0.01


def write_csv(path: Path, n: int = 1200, dt: float = DT, time: bool = True) -> Path:
    theta = 0.01 * np.sin(np.arange(n) * 0.3)
    if time:
        path.write_text("time,theta\n" + "".join(f"{i * dt:.6f},{v:.6g}\n" for i, v in enumerate(theta)))
    else:
        path.write_text("theta\n" + "".join(f"{v:.6g}\n" for v in theta))
    return path


@pytest.fixture
def folder(tmp_path):
    write_csv(tmp_path / "r1.csv")
    write_csv(tmp_path / "r2.csv")
    write_csv(tmp_path / "slow.csv", dt=2 * DT)
    write_csv(tmp_path / "bare.csv", time=False)
    np.save(tmp_path / "r3.npy", 0.01 * np.sin(np.arange(1200) * 0.3))
    return tmp_path


def sheet(folder: Path, *lines: str) -> Path:
    path = folder / "records.tsv"
    path.write_text("\n".join(lines) + "\n")
    return path


BAD = {
    # kind: (sheet lines, row, column, words of the sentence)
    "missing file": (["record\tpath", "a\tr1.csv", "b\tnone.csv"], 2, "path", "does not exist"),
    "duplicate id": (["record\tpath", "a\tr1.csv", "a\tr2.csv"], 2, "record", "row 1 too"),
    "unknown unit": (["record\tpath\tunits", "a\tr1.csv\tfurlong"], 1, "units", "give one of rad"),
    "negative dt": (["record\tpath\tdt", "a\tr3.npy\t-0.01"], 1, "dt", "'-0.01' is not allowed"),
    "dt and fs both": (["record\tpath\tdt\tfs", "a\tr3.npy\t0.01\t100"], 1, "fs", "both dt and fs"),
    "unknown load": (["record\tpath\tload", "a\tr1.csv\tpink"], 1, "load", "'pink' is not allowed"),
    "block steps differ": (["record\tpath\tblock", "a\tr1.csv\tA", "b\tslow.csv\tA"], 2, "dt", "same block 'A'"),
    "dt against the file": (["record\tpath\tdt", "a\tr1.csv\t0.02"], 1, "dt", "disagrees with the file's time axis"),
    "no step at all": (["record\tpath", "a\tr3.npy"], 1, "dt", "has no time axis"),
    "not a number": (["record\tpath\tg", "a\tr1.csv\tnine"], 1, "g", "'nine' is not a number"),
    "nan": (["record\tpath\ttheta_cr\tmodel", "a\tr1.csv\tnan\thousner"], 1, "theta_cr", "not a finite number"),
    "housner without theta_cr": (["record\tpath\tmodel", "a\tr1.csv\thousner"], 1, "theta_cr", "needs the block's critical angle"),
    "theta_cr without housner": (["record\tpath\ttheta_cr", "a\tr1.csv\t0.2"], 1, "theta_cr", "set model to housner"),
    "unknown sensor noise": (["record\tpath\tsensor_noise", "a\tr1.csv\tloud"], 1, "sensor_noise", "'loud' is not allowed"),
    "unknown test": (["record\tpath\ttest", "a\tr1.csv\tquake"], 1, "test", "give one of random, free, shake"),
    "unknown filter": (["record\tpath\tsensor_filter", "a\tr1.csv\tbessel:4:10:causal"], 1, "sensor_filter", "'bessel:4:10:causal' is not allowed"),
    "filter phase": (["record\tpath\tload\tsensor_noise\tsensor_filter", "a\tr1.csv\twhite\t0\trc:5:sideways"], 1, "sensor_filter",
                     "the phase 'sideways' is not known"),
    "filter without its load": (["record\tpath\tsensor_filter", "a\tr1.csv\trc:5:causal"], 1, "sensor_filter", "declare `load` and `sensor_noise` beside it"),
    "filters differ in a block": (["record\tpath\tblock\tsensor_filter", "a\tr1.csv\tA\tnone", "b\tr2.csv\tA\tauto"], 2,
                                  "sensor_filter", "pooled under one"),
    "free test with a filter": (["record\tpath\ttest\tsensor_filter", "a\tr1.csv\tfree\tnone"], 1, "sensor_filter", "needs no record model"),
    "free test sharing lengths": (["record\tpath\ttest\tshare_lengths", "a\tr1.csv\tfree\tyes"], 1, "share_lengths", "takes no calibration"),
    "share_lengths not yes or no": (["record\tpath\tshare_lengths", "a\tr1.csv\ttrue"], 1, "share_lengths", "give one of yes, no"),
    "sharing differs in a block": (["record\tpath\tblock\tshare_lengths", "a\tr1.csv\tA\tyes", "b\tr2.csv\tA\tno"], 2,
                                   "share_lengths", "pooled under one share_lengths"),
    "shake without a base": (["record\tpath\ttest", "a\tr1.csv\tshake"], 1, "base", "needs its base acceleration's file"),
    "a base on a random row": (["record\tpath\tbase", "a\tr1.csv\tr2.csv"], 1, "base", "only a shake-table test"),
    "a base that does not exist": (["record\tpath\ttest\tbase", "a\tr1.csv\tshake\tnone.csv"], 1, "base", "does not exist"),
    "a base without units": (["record\tpath\ttest\tbase", "a\tr1.csv\tshake\tr2.csv"], 1, "base_units", "states no units"),
    "a base sampled otherwise": (["record\tpath\ttest\tbase\tbase_units\tg", "a\tr1.csv\tshake\tslow.csv\trad/s2\t1"], 1, "base",
                                 "resample the base"),
    "a base in m/s2 without theta_cr": (["record\tpath\ttest\tbase\tbase_units", "a\tr1.csv\tshake\tr2.csv\tm/s2"], 1, "theta_cr",
                                        "needs the block's critical angle"),
    "a base in rad/s2 without g": (["record\tpath\ttest\tbase\tbase_units", "a\tr1.csv\tshake\tr2.csv\trad/s2"], 1, "g",
                                   "needs the block's g"),
    "a shake test with a load": (["record\tpath\ttest\tbase\tbase_units\tg\tload", "a\tr1.csv\tshake\tr2.csv\trad/s2\t1\twhite"], 1,
                                 "load", "needs no record model"),
    "a shake recipe on a random row": (["record\ttrue_e\tdt\tsimulate", "a\t0.9\t0.005\tseed=1 n_points=8000 shake=2"], 1, "test",
                                       "set test to shake"),
    "a simulated shake row without shake": (["record\ttrue_e\tdt\tsimulate\ttest", "a\t0.9\t0.005\tseed=1 n_points=8000\tshake"], 1,
                                            "simulate", "needs shake=PEAK"),
    "a shake recipe with a tilt": (["record\ttrue_e\tdt\tsimulate\ttest", "a\t0.9\t0.005\tseed=1 shake=2 theta0=1\tshake"], 1,
                                   "simulate", "leave theta0 and corner out"),
    "bad id": (["record\tpath", "1a\tr1.csv"], 1, "record", "'1a' is not allowed"),
    "block options differ": (["record\tpath\tblock\tload", "a\tr1.csv\tA\twhite", "b\tr2.csv\tA\tauto"], 2, "load", "pooled under one load"),
    "simulated without true e": (["record\tdt\tsimulate", "a\t0.8\tseed=1"], 1, "true_e", "needs its true_e"),
    "no path": (["record\tblock", "a\tA"], 1, "path", "empty; give the record's file"),
    "a folder": (["record\tpath", "a\t."], 1, "path", "is a folder"),
    "empty id": (["record\tpath", "\tr1.csv"], 1, "record", "empty; every row needs a record id"),
    "too many cells": (["record\tpath", "a\tr1.csv\textra"], 1, None, "3 cells for 2 columns"),
}


@pytest.mark.parametrize("kind", BAD)
def test_a_bad_row_is_refused_in_one_sentence_naming_its_row_and_column(folder, kind):
    lines, row, column, words = BAD[kind]
    with pytest.raises(SheetError) as err:
        campaign.read_sheet(sheet(folder, *lines))
    message = str(err.value)
    assert f"row {row}" in message and words in message, message
    assert column is None or f"column '{column}'" in message, message
    assert message.count(". ") == 0 and message.endswith("."), message  # one sentence


@pytest.mark.parametrize(
    "lines, words",
    [
        ([], "is empty"),
        (["# only a comment"], "is empty"),
        (["record\tpath"], "no record"),
        (["path", "r1.csv"], "column 'record'"),
        (["record\tpath\tcolour", "a\tr1.csv\tred"], "column 'colour': no such column"),
        (["record\tpath\tpath", "a\tr1.csv\tr1.csv"], "names this column twice"),
    ],
    ids=["empty sheet", "comments only", "header only", "no record column", "unknown column", "column twice"],
)
def test_a_sheet_without_rows_or_with_a_bad_header_is_refused(folder, lines, words):
    with pytest.raises(SheetError, match=words):
        campaign.read_sheet(sheet(folder, *lines))


def test_a_missing_sheet_names_the_config_field(tmp_path):
    with pytest.raises(SheetError, match="campaign.sheet"):
        campaign.read_sheet(tmp_path / "none.tsv")


def test_a_good_sheet_is_completed_paths_resolved_and_steps_read_off_the_files(folder):
    rows = campaign.read_sheet(sheet(
        folder,
        "# a comment",
        "record\tpath\tblock\tdt\tunits",
        "a\tr1.csv\tA\t\t",
        f"b\t{folder / 'r2.csv'}\tA\t{DT}\t",
        "c\tr3.npy\t\t0.01\tdeg",
        "",
    ))
    assert [r["record"] for r in rows] == ["a", "b", "c"]
    assert [r["block"] for r in rows] == ["A", "A", "c"]  # a record's own block by default
    assert [r["path"] for r in rows] == [str(folder / name) for name in ("r1.csv", "r2.csv", "r3.npy")]
    assert [r["dt"] for r in rows] == pytest.approx([DT, DT, 0.01])
    assert rows[0]["load"] == "auto" and rows[0]["sensor_noise"] == "auto" and rows[0]["test"] == "random"
    assert list(campaign.units(rows)) == ["record_a", "record_b", "record_c", "block_A"]


def test_a_netcdf_records_step_and_units_are_read_from_its_header(tmp_path):
    theta = xr.DataArray(np.zeros(1200), dims="time", coords={"time": ("time", np.arange(1200) * 5.0, {"units": "ms"})},
                         attrs={"units": "degree"})
    xr.Dataset({"theta": theta}).to_netcdf(tmp_path / "r.nc")
    assert campaign.file_step(tmp_path / "r.nc") == (pytest.approx(0.005), "degree")
    rows = campaign.read_sheet(sheet(tmp_path, "record\tpath\tunits", "a\tr.nc\tdeg"))
    assert rows[0]["dt"] == pytest.approx(0.005)
    with pytest.raises(SheetError, match="column 'units'.*differs from the file's own units 'degree'"):
        campaign.read_sheet(sheet(tmp_path, "record\tpath\tunits", "a\tr.nc\trad"))


def test_angles_in_degrees_are_read_in_rad(folder):
    rows = campaign.read_sheet(sheet(folder, "record\tpath\tdt\tunits", "a\tr3.npy\t0.01\tdeg", "b\tr3.npy\t0.01\trad"))
    deg, rad = (campaign.read([row])[0].theta for row in rows)
    np.testing.assert_allclose(deg, rad * math.pi / 180)


def test_a_spectrum_files_path_is_taken_relative_to_the_sheet(folder):
    (folder / "psd.csv").write_text("frequency_rocking,psd\n0.1,1\n1,1\n10,0.01\n")
    rows = campaign.read_sheet(sheet(folder, "record\tpath\tload", "a\tr1.csv\tspectrum:psd.csv"))
    assert rows[0]["load"] == f"spectrum:{folder / 'psd.csv'}"


def test_the_declared_options_are_what_the_estimate_takes():
    from rockdec.physics.record_model import Load

    from rockdec.physics.record_model import SensorFilter

    got = campaign.declared({"load": "lowpass:3", "sensor_noise": "2%", "sensor_filter": "rc:5:causal"})
    assert got["load"] == Load("lowpass", 3.0) and got["sensor"].std == pytest.approx(0.02) and got["sensor"].units == "sigma_y"
    assert got["sensor_filter"] == SensorFilter("rc", 1, 5.0, False)
    assert campaign.declared({"load": "auto", "sensor_noise": "auto", "sensor_filter": "auto"}) == {"load": None, "sensor": None, "sensor_filter": "auto"}


def test_a_free_rocking_row_says_the_analysis_is_not_available_where_rockdec_has_none(folder):
    rows = campaign.read_sheet(sheet(folder, "record\tpath\ttest", "a\tr1.csv\tfree"))
    doc, result = campaign.estimate_unit(rows, campaign.options(rows[0]), folder, SimpleNamespace())
    assert doc["e"] is None and doc["reason"] == campaign.FREE_UNAVAILABLE and result is None
    assert campaign.plan(rows, campaign.options(rows[0])) == {"calibrations": {}, "error": None}


def test_a_free_rocking_rows_json_is_what_rockdec_estimate_test_free_prints(tmp_path, monkeypatch, capsys):
    from rockdec import cli

    rockdec.simulate(0.9, 3000, seed=0, sigma_p=0.0, theta0=0.01).to_netcdf(tmp_path / "free.nc")
    rows = campaign.read_sheet(sheet(tmp_path, "record\tpath\ttest", "f\tfree.nc\tfree"))
    doc, result = campaign.estimate_unit(rows, campaign.options(rows[0]), tmp_path, rockdec)
    assert doc["test"] == "free" and doc["e"] == pytest.approx(0.9, abs=1e-3) and result.to_dict() == doc
    monkeypatch.chdir(tmp_path)
    assert cli.main(["estimate", "--test", "free", str(tmp_path / "free.nc"), "--json"]) in (0, None)
    assert json.loads(capsys.readouterr().out) == doc


@pytest.mark.slow
def test_a_shake_table_rows_json_is_what_rockdec_estimate_test_shake_prints(tmp_path, monkeypatch, capsys):
    """A simulated shake-table row (its base stored beside its angle, in rad/s^2 at g = 1) and a
    block of two: the campaign's document is ``rockdec estimate --test shake --json``'s."""
    from rockdec import cli

    rows = campaign.read_sheet(sheet(tmp_path, "record\tblock\ttrue_e\tdt\tsimulate\ttest",
                                     "s1\tE\t0.95\t0.005\tseed=3 n_points=6000 shake=3 noise=0.01\tshake",
                                     "s2\tE\t0.95\t0.005\tseed=4 n_points=6000 shake=3 noise=0.01\tshake"), simulated=tmp_path)
    assert [(r["base"], r["base_units"], r["g"]) for r in rows] == [(r["path"], "rad/s2", 1.0) for r in rows]
    assert set(campaign.units(rows)) == {"record_s1", "record_s2", "block_E-shake"}
    for row in rows:
        campaign.simulate_step(row, row["path"])
    paths = [r["path"] for r in rows]
    monkeypatch.chdir(tmp_path)
    for unit, members in (("record_s1", rows[:1]), ("block_E-shake", rows)):
        doc, result = campaign.estimate_unit(members, campaign.options(members[0]), tmp_path, rockdec)
        assert doc["test"] == "shake" and result.to_dict() == doc and campaign.plan(members, campaign.options(members[0]))["calibrations"] == {}
        files = paths[: len(members)]
        argv = ["estimate", "--test", "shake", *files, "--base", *files, "--base-variable", "base", "--g", "1", "--json"]
        assert cli.main(argv) in (0, None)
        assert json.loads(capsys.readouterr().out) == doc, unit


def test_a_free_rocking_row_takes_no_record_model(folder):
    with pytest.raises(SheetError, match="row 1 \\(record 'a'\\), column 'load': the free-rocking test reads g off its arcs"):
        campaign.read_sheet(sheet(folder, "record\tpath\ttest\tload", "a\tr1.csv\tfree\twhite"))


# --- the plan and the estimate: the calibration the plan names is the one the estimate reads


@pytest.fixture(scope="module")
def simulated(tmp_path_factory):
    """A short simulated record of known e (the demonstration's recipe) in a sheet of its own."""
    folder = tmp_path_factory.mktemp("simulated")
    rows = campaign.read_sheet(sheet(folder, "record\ttrue_e\tdt\tsimulate", "a\t0.9\t0.796\tseed=4 n_points=4000"), simulated=folder)
    campaign.simulate_step(rows[0], rows[0]["path"])
    return rows


def test_the_plan_names_the_calibration_the_estimate_asks_for(simulated, tmp_path, monkeypatch):
    from rockdec.calibrate import calibration

    import fake_calibration

    monkeypatch.setattr(calibration, "_grid_point", fake_calibration.grid_point)
    opts = campaign.options(simulated[0])
    first = campaign.plan(simulated, opts, tmp_path)
    ((name, settings),) = first["calibrations"].items()
    assert name == f"calibration-{calibration.settings_hash(settings)}.nc"
    assert not list(tmp_path.iterdir())  # planning builds nothing
    assert campaign.build_calibration(settings, tmp_path).name == name
    planned = campaign.plan(simulated, opts, tmp_path, first)
    for more in planned["calibrations"].values():
        campaign.build_calibration(more, tmp_path)
    doc, result = campaign.estimate_unit(simulated, opts, tmp_path, rockdec)
    assert doc["calibration"]["file"] in planned["calibrations"] and doc["calibration"]["cached"] is True
    assert doc == result.to_dict()


def test_a_row_sharing_lengths_plans_the_length_grids_calibration(simulated):
    """``share_lengths yes`` is ``rockdec estimate --share-lengths``: the plan asks for the
    calibration on the length grid's length at or below the record's, not the record's own."""
    from rockdec.calibrate import calibration

    (own,) = campaign.plan(simulated, campaign.options(simulated[0]))["calibrations"].values()
    row = {**simulated[0], "share_lengths": "yes"}
    (shared,) = campaign.plan([row], campaign.options(row))["calibrations"].values()
    assert own["lengths"] == [4000] and "length_grid" not in own
    assert shared["lengths"] == [calibration.length_bin(4000)] == [3160] and shared["length_grid"]["samples"] == 3160


def test_a_declared_filter_reaches_the_calibration_the_plan_names(simulated):
    """The sheet's ``sensor_filter`` is what ``rockdec estimate --sensor-filter`` declares: the
    calibration the plan asks for filters its records alike (the filter in its record model)."""
    from rockdec.physics.record_model import RecordModel

    row = {**simulated[0], "load": "white", "sensor_noise": "0", "sensor_filter": "butterworth:4:10:zero-phase"}
    planned = campaign.plan([row], campaign.options(row))
    (settings,) = planned["calibrations"].values()
    found = RecordModel.from_key(settings["record_model"]).filter
    assert planned["error"] is None and (found.kind, found.order, found.zero_phase) == ("butterworth", 4, True)
    (plain,) = campaign.plan(simulated, campaign.options(simulated[0]))["calibrations"].values()
    assert RecordModel.from_key(plain["record_model"]).filter is None


def test_the_simulated_record_has_the_rows_step_and_its_true_e(simulated):
    with xr.open_dataset(simulated[0]["path"]) as ds:
        assert ds.attrs["true_e"] == 0.9 and ds["theta"].size == 4000
        assert float(ds["time"][1] - ds["time"][0]) == pytest.approx(0.796)


def test_the_table_says_whether_each_interval_holds_the_true_e():
    def doc(e, low, high, reason=None):
        return {"e": e, "interval": [low, high], "estimator": "e_v" if e else None, "reason": reason, "g": 1.0,
                "warnings": [], "estimators": {"e_v": {"e": e, "interval": [low, high]}}}

    rows = [{"record": name, "block": "A", "true_e": 0.9} for name in ("a", "b", "c")]
    units = [("record_a", doc(0.91, 0.88, 0.93)), ("record_b", doc(0.8, 0.75, 0.85)), ("record_c", doc(None, None, None, "declined"))]
    ds = campaign.summary_dataset([campaign.unit_dataset(name, [row], d) for (name, d), row in zip(units, rows)])
    assert set(ds["e"].dims) == {"record"} and ds["estimator_e"].dims == ("record", "estimator")
    assert list(ds["block"].values) == ["A", "A", "A"]
    tab = campaign.table(ds)
    assert list(tab["holds_true_e"]) == ["yes", "no", "no estimate"]
    assert list(tab["reason"]) == ["", "", "declined"]
    assert "| a " in campaign.markdown(tab)


def test_every_number_of_the_document_becomes_a_variable():
    doc = {"e": 0.9, "interval": [0.8, 0.95], "g_given": False, "records": ["x"], "calibration": {"seconds": 1.5},
           "diagnostics": {"drift": {"statistic": 1.0, "threshold": 2.0, "fired": False}}}
    ds = campaign.unit_dataset("record_a", [{"record": "a", "block": "a"}], doc)
    assert float(ds["interval_high"][0]) == 0.95 and float(ds["g_given"][0]) == 0.0
    assert ds["calibration_seconds"].attrs["units"] == "s"
    assert float(ds["check_threshold"].sel(check="drift")[0]) == 2.0
    assert json.dumps(doc)  # the document itself stays JSON


def test_the_comparison_sets_each_blocks_free_test_beside_its_random_estimate():
    """Issue 37: per block with both tests, the pooled random estimate (or the one record) and
    the free-rocking estimate side by side; they agree when their intervals overlap."""
    import pandas as pd

    tab = pd.DataFrame({
        "record": ["a1", "a2", "fa", "A (records pooled)", "b1", "fb", "c1"],
        "kind": ["record", "record", "record", "block", "record", "record", "record"],
        "test": ["random", "random", "free", "random", "random", "free", "random"],
        "block": ["A", "A", "A", "A", "B", "B", "C"],
        "e": [0.88, 0.91, 0.90, 0.895, 0.70, 0.80, 0.85],
        "low": [0.85, 0.88, 0.899, 0.88, 0.65, 0.79, 0.8],
        "high": [0.91, 0.94, 0.901, 0.91, 0.75, 0.81, 0.9],
    })
    out = campaign.comparison(tab)
    assert list(out["block"]) == ["A", "B"]  # C has no free test
    a, b = out.iloc[0], out.iloc[1]
    assert (a["random_e"], a["free_e"], a["agree"]) == (0.895, 0.90, "yes")  # the pooled estimate, not a record's
    assert (b["random_high"], b["free_low"], b["agree"]) == (0.75, 0.79, "no")


def test_the_comparison_sets_a_blocks_shake_table_tests_beside_its_free_test():
    import pandas as pd

    tab = pd.DataFrame({
        "record": ["s1", "s2", "fe", "E (shake-table tests pooled)", "s9"],
        "kind": ["record", "record", "record", "block", "record"],
        "test": ["shake", "shake", "free", "shake", "shake"],
        "block": ["E", "E", "E", "E", "F"],
        "e": [0.90, 0.91, 0.899, 0.902, 0.9],
        "low": [0.89, 0.90, 0.898, 0.899, 0.89],
        "high": [0.91, 0.92, 0.900, 0.905, 0.91],
    })
    out = campaign.comparison(tab, ("free", "shake"))
    assert list(out.columns) == ["block", "free_e", "free_low", "free_high", "shake_e", "shake_low", "shake_high", "agree"]
    assert list(out["block"]) == ["E"] and (out.iloc[0]["shake_e"], out.iloc[0]["agree"]) == (0.902, "yes")  # the pooled shake estimate; F has no free test
    assert campaign.comparison(tab).empty  # no random response anywhere

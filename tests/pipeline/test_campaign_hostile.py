"""Hostile campaigns (rockdec.pipeline.campaign): records the estimate repairs, whose plans must
name every calibration the estimate reads; records refused one by one, named in the table;
angle units a NetCDF file does not state; blocks whose estimates' names could collide; sizes
and ids beyond what a run can do; sheets with a byte-order mark or not separated by tabs;
sampling steps at the ends of the floats. Without Snakemake (the campaign of repaired records
through the workflow: test_campaign_workflow.py)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import xarray as xr

import rockdec
from rockdec.pipeline import campaign
from rockdec.pipeline.campaign import SheetError
from test_hostile import hostile, marked

DT = 0.796


def sheet(folder: Path, *lines: str, prefix: str = "") -> Path:
    path = folder / "records.tsv"
    path.write_text(prefix + "\n".join(lines) + "\n", encoding="utf-8")
    return path


def one_sentence(message: str) -> None:
    assert message.count(". ") == 0 and message.endswith("."), message


def refused_sheet(path: Path, row: int | None, column: str | None, *words: str) -> str:
    with pytest.raises(SheetError) as err:
        campaign.read_sheet(path, simulated=path.parent)
    message = str(err.value)
    one_sentence(message)
    assert row is None or f"row {row}" in message, message
    assert column is None or f"column '{column}'" in message, message
    for word in words:
        assert word in message, (word, message)
    return message


@pytest.fixture
def fake_calibration(monkeypatch):
    """Calibrations built without simulation (tests/fake_calibration.py)."""
    from rockdec.calibrate import calibration

    import fake_calibration as fake

    monkeypatch.setattr(calibration, "_grid_point", fake.grid_point)


# --- 1. the plans name every calibration the estimate reads, the repair's included ----------


@pytest.fixture(scope="module")
def repaired(tmp_path_factory) -> Path:
    """Records the estimate repairs, as ``.npy`` files of a record of e = 0.9 (the
    demonstration's recipe, 20000 samples): with three spikes of 30 times its rms (replaced
    before the analysis), under a linear drift of 3 times its rms (the record model measures
    drift: the estimate reads the records' calibration, then the high-passed records'), and
    under one slow cycle of twice its rms (the records as given are refused: the high-passed
    records' calibration only)."""
    folder = tmp_path_factory.mktemp("repaired")
    row = {"record": "x", "true_e": 0.9, "dt": DT, "simulate": campaign.simulation("seed=4 n_points=20000")}
    theta = campaign.simulated_record(row)["theta"].values
    rms = float(np.sqrt(np.mean(theta**2)))
    spiky = theta.copy()
    spiky[[3000, 9000, 15000]] += 30 * rms
    np.save(folder / "spiky.npy", spiky)
    np.save(folder / "drift.npy", theta + np.linspace(0, 3 * rms, theta.size))
    np.save(folder / "cycle.npy", theta + 2 * rms * np.sin(2 * np.pi * np.arange(theta.size) / theta.size))
    return folder


REPAIRS = {
    # the record: (what the repair did, calibrations the estimate reads)
    "spikes": ("spiky", "spikes_removed", 1),
    "drift measured": ("drift", "highpass_corner_rocking", 2),
    "refused until high-passed": ("cycle", "highpass_corner_rocking", 1),
}


@pytest.mark.parametrize("record, repair, reads", marked(REPAIRS, "wrong answers", "answered"))
def test_the_plans_name_every_calibration_the_repaired_estimate_reads(repaired, tmp_path, fake_calibration, record, repair, reads):
    rows = campaign.read_sheet(sheet(repaired, "record\tpath\tdt", f"{record}\t{record}.npy\t{DT}"))
    opts, cache, plans = campaign.options(rows[0]), tmp_path / "cache", tmp_path / "plans"
    plans.mkdir()
    campaign.plan_step(rows, opts, None, None, str(plans / "first.json"))
    assert not cache.exists()  # the first plan reads and builds nothing
    for settings in json.loads((plans / "first.json").read_text())["calibrations"].values():
        campaign.build_calibration(settings, cache)  # the workflow's calibration jobs
    campaign.plan_step(rows, opts, cache, str(plans / "first.json"), str(plans / "plan.json"))
    planned = json.loads((plans / "plan.json").read_text())["calibrations"]
    for settings in planned.values():
        campaign.build_calibration(settings, cache)
    out = tmp_path / "record.json"
    campaign.estimate_step("record_x", rows, opts, cache, str(plans / "plan.json"), str(out), str(tmp_path / "record.nc"),
                           "campaign_record", rockdec)
    doc = json.loads(out.read_text())
    assert doc["repair"][repair] and doc["e"] is not None
    assert doc["calibration"]["file"] in planned and doc["calibration"]["cached"] is True
    assert len(planned) == reads and sorted(p.name for p in cache.glob("calibration-*.nc")) == sorted(planned)  # the estimate built none


def test_an_estimate_that_reads_a_calibration_its_plan_did_not_name_is_stopped(repaired, tmp_path, fake_calibration):
    """The check behind the plans: a plan that missed a calibration is a bug, not the user's."""
    rows = campaign.read_sheet(sheet(repaired, "record\tpath\tdt", f"drift\tdrift.npy\t{DT}"))
    first = campaign.plan(rows, campaign.options(rows[0]))
    (tmp_path / "first.json").write_text(json.dumps(first))
    with pytest.raises(RuntimeError, match="its plan built calibration-"):
        campaign.estimate_step("record_drift", rows, campaign.options(rows[0]), tmp_path, str(tmp_path / "first.json"),
                               str(tmp_path / "r.json"), str(tmp_path / "r.nc"), "campaign_record", rockdec)


# --- 2, 8. records refused one by one are rows of the table, with their reason --------------


@pytest.fixture(scope="module")
def lab(tmp_path_factory) -> Path:
    """Record files a campaign refuses or answers: ``.npy`` and CSV (one with a byte-order mark
    and a time column, one with a byte-order mark and no time axis), a constant record, and
    NetCDF files with and without the angle's units."""
    folder = tmp_path_factory.mktemp("lab")
    theta = 0.01 * np.sin(np.arange(1200) * 0.3)
    np.save(folder / "r.npy", theta)
    np.save(folder / "flat.npy", np.zeros(1200))
    (folder / "bom_time.csv").write_text("time,theta\n" + "".join(f"{i * 0.01:.6f},{v:.6g}\n" for i, v in enumerate(theta)),
                                         encoding="utf-8-sig")
    (folder / "bom_bare.csv").write_text("theta\n" + "".join(f"{v:.6g}\n" for v in theta), encoding="utf-8-sig")
    time = ("time", np.arange(1200) * 0.01, {"units": "s"})
    xr.Dataset({"theta": ("time", theta)}, coords={"time": time}).to_netcdf(folder / "bare.nc")
    xr.Dataset({"theta": ("time", theta, {"units": "degree"})}, coords={"time": time}).to_netcdf(folder / "degree.nc")
    return folder


REFUSED_ROWS = {
    # case: (sheet row after the header 'record path dt fs', words of its reason)
    "constant record": ("flat\tflat.npy\t0.01\t", "the record is constant"),
    "fs 1e-320": ("tiny\tr.npy\t\t1e-320", "not a positive, finite number"),
    "dt 1e308": ("huge\tr.npy\t1e308\t", "beyond the range of a float"),
    "a BOM CSV given dt": ("bom\tbom_bare.csv\t0.01\t", "bom_bare.csv"),
}


def _table(rows: list[dict], folder: Path) -> pd.DataFrame:
    """The campaign's table of ``rows``: each unit's estimate (:func:`campaign.estimate_unit`,
    refused or not) through :func:`campaign.table_step`, as the workflow's jobs make it."""
    units = campaign.units(rows)
    inputs = []
    for unit, members in units.items():
        doc, _ = campaign.estimate_unit(members, campaign.options(members[0]), folder / "cache", rockdec)
        path = folder / f"{unit}.json"
        path.write_text(json.dumps(doc))
        inputs.append(str(path))
    campaign.table_step(inputs, str(folder / "t.nc"), str(folder / "t.csv"), str(folder / "t.md"), units)
    return pd.read_csv(folder / "t.csv", keep_default_na=False)


@pytest.mark.parametrize("row, words", marked(REFUSED_ROWS, lambda name: "record files" if "BOM" in name else "numbers"))
def test_a_record_the_estimate_refuses_is_a_row_of_the_table_with_its_reason(lab, tmp_path, row, words):
    rows = campaign.read_sheet(sheet(lab, "record\tpath\tdt\tfs", row))
    tab = _table(rows, tmp_path)
    assert list(tab["record"]) == [rows[0]["record"]] and tab["e"].tolist() == [""]
    assert words in tab["reason"].iloc[0]
    assert f"| {rows[0]['record']} " in (tmp_path / "t.md").read_text()


@hostile("numbers", "refused")
def test_every_record_refused_still_makes_the_table_naming_each(lab, tmp_path):
    rows = campaign.read_sheet(sheet(lab, "record\tpath\tdt\tfs", *(row for row, _ in REFUSED_ROWS.values())))
    tab = _table(rows, tmp_path)
    assert list(tab["record"]) == [row["record"] for row in rows]
    assert (tab["e"] == "").all() and all(tab["reason"]) and all(words in reason for (_, words), reason in zip(REFUSED_ROWS.values(), tab["reason"]))


@hostile("record files", "answered")
def test_a_bom_csvs_time_axis_is_read_at_the_sheet(lab):
    """As the reader reads it: the step given must agree with it, and the reader is given none."""
    rows = campaign.read_sheet(sheet(lab, "record\tpath\tdt", "a\tbom_time.csv\t0.01"))
    assert rows[0]["file_has_time"] is True and campaign._given_step(rows[0]) is None
    refused_sheet(sheet(lab, "record\tpath\tdt", "a\tbom_time.csv\t0.02"), 1, "dt", "disagrees with the file's time axis")


# --- 3. the row's units apply where the file states none ------------------------------------


UNITS = {
    # case: (file, the row's units, factor to rad of what the file holds)
    "no units attribute, deg given": ("bare.nc", "deg", math.pi / 180),
    "no units attribute, none given": ("bare.nc", "", 1.0),
    "units attribute, none given": ("degree.nc", "", math.pi / 180),
    "units attribute, the same given": ("degree.nc", "degrees", math.pi / 180),
}


@pytest.mark.parametrize("path, units, factor", marked(UNITS, "units", "answered"))
def test_a_netcdf_angle_is_read_in_the_units_the_file_or_else_the_row_states(lab, path, units, factor):
    rows = campaign.read_sheet(sheet(lab, "record\tpath\tunits", f"a\t{path}\t{units}"))
    stored = 0.01 * np.sin(np.arange(1200) * 0.3)
    np.testing.assert_allclose(campaign.read(rows)[0].theta, stored * factor, rtol=1e-12)
    np.testing.assert_allclose(campaign._theta(rows, rockdec)[0].values, stored * factor, rtol=1e-12)  # what the estimate reads


@hostile("units", "refused")
def test_a_rows_units_that_disagree_with_the_files_are_refused(lab):
    refused_sheet(sheet(lab, "record\tpath\tunits", f"a\tdegree.nc\trad"), 1, "units", "differs from the file's own units 'degree'")


# --- 4. every estimate's name is its own ------------------------------------------------------


@hostile("output paths", "answered")
def test_a_block_named_like_another_blocks_free_tests_gets_its_own_estimate(lab):
    rows = campaign.read_sheet(sheet(lab, "record\tpath\tblock\ttest\tdt", "a\tr.npy\tA_free\t\t0.01", "b\tr.npy\tA_free\t\t0.01",
                                     "c\tr.npy\tA\tfree\t0.01", "d\tr.npy\tA\tfree\t0.01"))
    units = campaign.units(rows)
    pooled = {unit: [row["record"] for row in members] for unit, members in units.items() if unit.startswith("block_")}
    assert pooled == {"block_A_free": ["a", "b"], "block_A-free": ["c", "d"]}
    assert len({unit.lower() for unit in units}) == len(units) == 6  # distinct on a file system that ignores case too


# --- 5, 6. sizes and ids a run cannot do, refused at the sheet --------------------------------


def test_the_simulated_size_limit_is_the_longest_records_whose_coverage_was_measured():
    from rockdec.calibrate import calibration
    from rockdec import estimation

    assert campaign.MAX_SIMULATED_POINTS == estimation.LONG_RATIO * calibration.LENGTH_CAP


SIZES = {
    # case: (the simulate cell, words)
    "5e7 samples": ("seed=1 n_points=5e7", "more than the 2e+07"),
    "1e12 samples": ("seed=1 n_points=1e12", "more than the 2e+07"),
    "1e400 samples": ("seed=1 n_points=1e400", "not a finite number"),
    "not a number": ("seed=1 n_points=1.2.3", "not a number"),
}


@pytest.mark.parametrize("recipe, words", marked(SIZES, "sizes"))
def test_a_simulated_record_beyond_the_size_limit_is_refused_at_the_sheet(tmp_path, recipe, words):
    refused_sheet(sheet(tmp_path, "record\ttrue_e\tdt\tsimulate", f"a\t0.9\t{DT}\t{recipe}"), 1, "simulate", words)


IDS = {
    "a block of 250 characters": ("block", "a\tr.npy\t0.01\t" + "B" * 250),
    "a record of 250 characters": ("record", "R" * 250 + "\tr.npy\t0.01\tA"),
}


@pytest.mark.parametrize("column, row", marked(IDS, "output paths"))
def test_an_id_longer_than_a_file_name_allows_is_refused_at_the_sheet(lab, column, row):
    refused_sheet(sheet(lab, "record\tpath\tdt\tblock", row), 1, column, "250 characters", f"the {campaign.MAX_ID} an id may have")


def test_the_longest_ids_names_fit_a_file_name():
    """The longest file the workflow names by an id: a free-tests block's first plan's log,
    and a plan being written (its ``.partial``)."""
    from rockdec.validate import MAX_NAME_BYTES

    block = "B" * campaign.MAX_ID
    longest = max(f"first_plan_block_{block}-free.log", f".block_{block}-free.first.json.partial", key=len)
    assert len(longest.encode()) <= MAX_NAME_BYTES


@hostile("numbers", "refused")
def test_a_simulated_record_whose_step_a_float_cannot_hold_is_refused_at_the_sheet(tmp_path):
    refused_sheet(sheet(tmp_path, "record\ttrue_e\tdt\tsimulate", "a\t0.9\t1e308\tseed=1 n_points=2000"), 1, "dt", "1e+308")


# --- 7. sheets with a byte-order mark or not separated by tabs --------------------------------


@hostile("configs", "answered")
def test_a_sheet_with_a_byte_order_mark_is_read(lab):
    rows = campaign.read_sheet(sheet(lab, "record\tpath\tdt", "a\tr.npy\t0.01", prefix="\ufeff"))
    assert [row["record"] for row in rows] == ["a"]


SEPARATORS = {
    "spaces": (["record path dt", "a r.npy 0.01"], None, "separated by spaces"),
    "commas": (["record,path,dt", "a,r.npy,0.01"], None, "separated by commas"),
    "semicolons": (["record;path;dt", "a;r.npy;0.01"], None, "separated by semicolons"),
    "a row by spaces": (["record\tpath\tdt", "a r.npy 0.01"], 1, "separated by spaces"),
}


@pytest.mark.parametrize("lines, row, words", marked(SEPARATORS, "configs"))
def test_a_sheet_not_separated_by_tabs_is_told_to_use_tabs(lab, lines, row, words):
    message = refused_sheet(sheet(lab, *lines), row, None, words, "separate the columns by tabs")
    assert "no such column" not in message

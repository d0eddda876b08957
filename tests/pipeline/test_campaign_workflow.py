"""A small campaign through the workflow, built once: two simulated records of one block, a
measured record (a CSV file) and a free-rocking test, records of 6000 samples so that their calibrations take a second or
two each. Each record's JSON is what ``rockdec estimate --json`` prints for its file; each distinct
calibration is built once, by a job of its own; a new row reruns only its record, its block
and the summaries; the table, the NetCDF (CF), the figures and the verified archive; the
cluster profile's plan; the code fingerprints (a module edited reruns what reaches it). And a
campaign of records the estimate repairs (spikes, drift) beside one it refuses.
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import xarray as xr

from cf_check import NO_FINDINGS, cf_findings
from conftest import snakemake
from rockdec import cli
from rockdec.pipeline import archive
from test_workflow import REPO, job_stats

#: A Snakemake campaign end to end: the slow tier (docs/development/testing.md).
pytestmark = pytest.mark.slow

SHEET = [
    "record\tpath\tblock\ttrue_e\tdt\tsimulate\ttest",
    "a1\t\tA\t0.9\t0.796\tseed=4 n_points=6000\t",
    "a2\t\tA\t0.9\t0.796\tseed=2 n_points=6000\t",
    "m1\tlab/m1.csv\tM\t\t\t\t",
    "f1\t\tA\t0.9\t0.796\tseed=41 n_points=3000 theta0=20 noise=0.01\tfree",
    "s1\t\tE\t0.9\t0.005\tseed=51 n_points=8000 shake=3 noise=0.01\tshake",
]
NEW_ROW = "a3\t\tA\t0.9\t0.796\tseed=3 n_points=6000\t"


def measured_record(path: Path) -> None:
    """A 'measured' record of e = 0.8 as a CSV file with a time column (the demonstration's
    recipe, written as a lab's file)."""
    from rockdec.pipeline import campaign

    row = {"record": "m1", "true_e": 0.8, "dt": 0.564, "simulate": campaign.simulation("seed=11 n_points=6000")}
    ds = campaign.simulated_record(row)
    path.parent.mkdir(parents=True)
    pd.DataFrame({"time": ds["time"].values, "theta": ds["theta"].values}).to_csv(path, index=False, float_format="%.10g")


def campaign_copy(root: Path, sheet: list[str]) -> dict:
    """The workflow and the package copied into ``root`` (``<root>/rockdec``: the rules'
    modules are the copy's), the campaign's ``sheet`` (lines) and its cache in the copy."""
    shutil.copy(REPO / "Snakefile", root)
    for folder in ("workflow", "config", "profiles"):
        shutil.copytree(REPO / folder, root / folder)
    # numba's caches come along (their index holds the sources' times, which the copy keeps):
    # compiling the kernels afresh for the copy would take longer than the campaign
    shutil.copytree(REPO / "src" / "rockdec", root / "rockdec", ignore=shutil.ignore_patterns("*.pyc"))
    (root / "config" / "records.tsv").write_text("\n".join(sheet) + "\n")
    cache = root / "cache"
    config = root / "config" / "config.yaml"
    config.write_text(config.read_text().replace("campaign: {name: demo, sheet: config/records.tsv, cache: null}",
                                                 f"campaign: {{name: demo, sheet: config/records.tsv, cache: {cache}}}"))
    return {"root": root, "cache": cache, "results": root / "results" / "demo"}


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """:func:`campaign_copy` of :data:`SHEET`, ``snakemake campaign`` run once."""
    copy = campaign_copy(tmp_path_factory.mktemp("campaign"), SHEET)
    measured_record(copy["root"] / "config" / "lab" / "m1.csv")
    code, log = snakemake(copy["root"], "campaign")
    assert code == 0, log
    return {**copy, "log": log}


def test_each_records_json_is_what_rockdec_estimate_prints_for_its_file(built, monkeypatch, capsys):
    monkeypatch.chdir(built["root"])
    rows = {"a1": "results/demo/simulated/a1.nc", "m1": str(built["root"] / "config" / "lab" / "m1.csv")}
    for record, path in rows.items():
        capsys.readouterr()
        assert cli.main(["estimate", path, "--json", "--cache", str(built["cache"])]) in (0, None)
        printed = json.loads(capsys.readouterr().out)
        ours = json.loads((built["results"] / "estimates" / f"record_{record}.json").read_text())
        for doc in (printed, ours):  # timing: how long this run's calibration took to read
            doc["calibration"].pop("seconds")
        assert ours == printed, record


def test_each_distinct_calibration_is_built_once_by_a_job_of_its_own(built):
    plans = {p.stem: json.loads(p.read_text()) for p in (built["results"] / "plans").glob("*.json") if not p.name.endswith(".first.json")}
    assert plans["record_f1"]["calibrations"] == plans["record_s1"]["calibrations"] == {}  # free-rocking and shake-table tests need none
    wanted = {name for unit, plan in plans.items() for name in plan["calibrations"]}
    assert len(plans) == 6 and all(plans[unit]["calibrations"] for unit in plans if unit not in ("record_f1", "record_s1"))  # and block A
    assert built["log"].count("rule campaign_calibration:") == len(wanted)
    assert {p.name for p in built["cache"].glob("calibration-*.nc")} == wanted
    for path in (built["results"] / "estimates").glob("*.json"):
        if path.stem not in ("record_f1", "record_s1"):
            assert json.loads(path.read_text())["calibration"]["cached"] is True, path.name  # no estimate built one


def test_adding_a_row_reruns_only_that_record_its_block_and_the_summaries(built):
    sheet = built["root"] / "config" / "records.tsv"
    before = sheet.read_text()
    code, out = snakemake(built["root"], "-n", "campaign")
    assert code == 0 and job_stats(out) == {}, out
    sheet.write_text(before + NEW_ROW + "\n")
    try:
        code, out = snakemake(built["root"], "-n", "campaign")
    finally:
        sheet.write_text(before)
    assert code == 0, out
    assert job_stats(out) == {
        "campaign_simulate": 1, "campaign_first_plan": 2, "campaign_plan": 2, "campaign_record": 1, "campaign_block": 1,
        "campaign_table": 1, "campaign_figures": 1, "campaign_archive": 1, "campaign": 1,
    }, out


def test_the_table_shows_each_estimate_beside_the_true_e_and_says_why_when_there_is_none(built):
    tab = pd.read_csv(built["results"] / "estimates.csv", keep_default_na=False)
    assert list(tab["record"]) == ["a1", "a2", "m1", "f1", "s1", "A (records pooled)"]
    assert float(tab.loc[tab["record"] == "f1", "e"].iloc[0]) == pytest.approx(0.9, abs=0.01)  # the free-rocking test's
    for row in tab.itertuples():
        assert row.holds_true_e in ("yes", "no", "no estimate", "")
        assert (row.e != "") or row.reason, row  # no e: the reason says why
    assert (tab["true_e"] == "").tolist() == [False, False, True, False, False, False]
    shake = json.loads((built["results"] / "estimates" / "record_s1.json").read_text())
    assert shake["test"] == "shake" and (shake["e"] is not None or shake["reason"])
    md = (built["results"] / "estimates.md").read_text()
    assert "| A (records pooled) |" in md
    side = md[md.index("## The free-rocking test beside the random response"):]  # block A holds both tests
    assert "| A " in side and ("| yes " in side or "| no " in side)


def test_the_estimates_netcdf_runs_along_record_and_estimator_and_is_cf_clean(built, tmp_path):
    path = built["results"] / "estimates.nc"
    with xr.open_dataset(path) as ds:
        assert ds["e"].dims == ("record",) and ds["estimator_e"].dims == ("record", "estimator")
        assert list(ds["block"].values) == ["A", "A", "M", "A", "E", "A"]
        assert ds["g"].attrs["units"] == "rad s-2" and ds["dt"].attrs["units"] == "s"
        one = json.loads((built["results"] / "estimates" / "record_a1.json").read_text())
        assert float(ds["e"].sel(record="a1")) == pytest.approx(np.nan if one["e"] is None else one["e"], nan_ok=True)
    assert cf_findings(path, tmp_path) == NO_FINDINGS


def test_the_figures_are_drawn(built):
    import matplotlib.image

    for name in ("forest", "record_model", "diagnostics"):
        assert matplotlib.image.imread(built["results"] / "figures" / f"{name}.png").shape[0] > 100


def test_the_archive_holds_exactly_what_its_manifest_lists_and_verifies(built):
    folder = built["results"] / "archive"
    manifest = json.loads((folder / "manifest.json").read_text())
    listed = {entry["name"] for entry in manifest["workflow"] + manifest["files"]} | {"manifest.json", "ro-crate-metadata.json"}
    present = {p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file()}
    assert present == listed  # no .snakemake_timestamp
    assert manifest["kind"] == "campaign" and "estimates/record_a1.json" in listed and "config/records.tsv" in listed
    assert archive.verify(folder) == []


def test_the_slurm_profile_plans_a_job_per_record_block_and_calibration(built):
    """Once the first plans are made (they read the records), a dry run on the cluster profile lists a
    job per record, per block and per calibration they ask for, and the plans that read those
    calibrations (into an empty cache here)."""
    empty = built["root"] / "empty_cache"
    code, out = snakemake(built["root"], "-n", "--profile", "profiles/slurm", "campaign",
                          "--config", f"campaign={{name: demo, sheet: config/records.tsv, cache: {empty}}}")
    assert code == 0, out
    stats = job_stats(out)
    assert stats["campaign_record"] == 5 and stats["campaign_block"] == 1 and stats["campaign_calibration"] == 4, out
    assert stats["campaign_plan"] == 6 and "campaign_first_plan" not in stats, out


def test_a_bad_sheet_stops_the_run_before_any_job_naming_row_and_column(built):
    sheet = built["root"] / "config" / "records.tsv"
    before = sheet.read_text()
    sheet.write_text(before + "m1\tlab/m1.csv\tM\t\t\t\t\n")
    try:
        code, out = snakemake(built["root"], "-n", "campaign")
    finally:
        sheet.write_text(before)
    assert code == 2 and "row 6 (record 'm1'), column 'record'" in out, out
    assert "Job stats" not in out


def test_a_module_touched_reruns_nothing_and_one_edited_reruns_what_reaches_it(built):
    """The rules' code inputs are fingerprints of the modules they reach (rockdec.sources.fingerprint_file)."""
    root = built["root"]
    codes = root / ".snakemake" / "rockdec-code"
    saved = root / "saved-code"
    shutil.copytree(codes, saved)
    module = root / "rockdec" / "report" / "campaign_figures.py"
    text = module.read_text()
    try:
        os.utime(module)  # a checkout: newer, the same text
        code, out = snakemake(root, "-n", "campaign")
        assert code == 0 and job_stats(out) == {}, out
        module.write_text(text + "\n# edited\n")
        code, out = snakemake(root, "-n", "campaign")
        assert code == 0 and job_stats(out) == {"campaign_figures": 1, "campaign": 1}, out
        assert all(len(line) < 1000 for line in out.splitlines())
    finally:
        module.write_text(text)
        shutil.rmtree(codes)
        shutil.copytree(saved, codes)  # the fingerprints and their times as the build left them
        shutil.rmtree(saved)
    code, out = snakemake(root, "-n", "campaign")
    assert code == 0 and job_stats(out) == {}, out


def test_the_demonstration_runs_from_an_empty_folder_with_the_workflow_elsewhere(tmp_path):
    """As `rockdec workflow -- campaign` runs it from an install (the Snakefile and its config in
    the package's copy of the workflow): the sheet is found beside the workflow."""
    code, out = snakemake(tmp_path, "campaign", "-n", "--snakefile", str(REPO / "Snakefile"),
                          "--configfile", str(REPO / "config" / "config.yaml"))
    assert code == 0, out
    stats = job_stats(out)
    # 21 records, block A's random responses and block E's shake-table tests pooled
    assert stats["campaign_simulate"] == 21 and stats["campaign_first_plan"] == stats["campaign_plan"] == 23, out


#: A campaign of records the estimate repairs and one it refuses (:func:`repaired_records`).
REPAIRED_SHEET = [
    "record\tpath\tdt\ttrue_e",
    "spiky\tlab/spiky.npy\t0.796\t0.9",
    "drifting\tlab/drifting.npy\t0.796\t0.9",
    "flat\tlab/flat.npy\t0.796\t",
]


def repaired_records(folder: Path) -> None:
    """Three records of 6000 samples as ``.npy`` files in ``folder``: one of e = 0.9 (the
    demonstration's recipe) with three spikes of 30 times its rms (the repair replaces them),
    the same under a drift of one slow cycle of twice its rms (the records as given are
    refused, the high-passed ones estimated), and a constant one (refused)."""
    from rockdec.pipeline import campaign

    row = {"record": "x", "true_e": 0.9, "dt": 0.796, "simulate": campaign.simulation("seed=4 n_points=6000")}
    theta = campaign.simulated_record(row)["theta"].values
    rms = float(np.sqrt(np.mean(theta**2)))
    spiky = theta.copy()
    spiky[[1000, 3000, 5000]] += 30 * rms
    folder.mkdir(parents=True)
    np.save(folder / "spiky.npy", spiky)
    np.save(folder / "drifting.npy", theta + 2 * rms * np.sin(2 * np.pi * np.arange(theta.size) / theta.size))
    np.save(folder / "flat.npy", np.zeros(theta.size))


def test_records_the_repair_despikes_or_high_passes_and_a_refused_one_finish_the_campaign(tmp_path):
    """Each estimate reads only calibrations its plans asked for and the workflow built (the
    repair decides in the plans as in the estimate); the refused record is a row of the table
    with its reason."""
    copy = campaign_copy(tmp_path, REPAIRED_SHEET)
    repaired_records(copy["root"] / "config" / "lab")
    code, log = snakemake(copy["root"], "campaign")
    assert code == 0, log
    docs = {unit: json.loads((copy["results"] / "estimates" / f"record_{unit}.json").read_text()) for unit in ("spiky", "drifting", "flat")}
    assert docs["spiky"]["repair"]["spikes_removed"] == 3 and docs["drifting"]["repair"]["highpass_corner_rocking"] is not None
    planned = set()
    for unit, doc in docs.items():
        plan = json.loads((copy["results"] / "plans" / f"record_{unit}.json").read_text())
        planned |= set(plan["calibrations"])
        if unit != "flat":
            assert doc["calibration"]["file"] in plan["calibrations"] and doc["calibration"]["cached"] is True, unit
    assert {p.name for p in copy["cache"].glob("calibration-*.nc")} == planned  # no estimate built one
    assert log.count("rule campaign_calibration:") == len(planned)
    tab = pd.read_csv(copy["results"] / "estimates.csv", keep_default_na=False)
    assert list(tab["record"]) == ["spiky", "drifting", "flat"]
    flat = tab[tab["record"] == "flat"].iloc[0]
    assert flat["e"] == "" and "the record is constant" in flat["reason"]

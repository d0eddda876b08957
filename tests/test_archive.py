"""Archives and `rockdec verify`, and workflow runs killed and resumed.

A copy of the workflow runs the tiny scene shrunk to 2 replicates of 10 series with every
series stored (`store_series: all`) and a fixed step (no calibration) without interruption:
the reference, and its archive. Copies of that run without the products of rule `readings`
are rerun and killed while `readings` runs: with SIGTERM, then resumed by the README's
command; with SIGKILL, then recovered by the README's recovery command. Both must end with
the reference's outputs.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import xarray as xr
import yaml

from rockdec import archive, simulate
from rockdec.cli import main

REPO = Path(__file__).resolve().parents[1]
SCENE = "tiny"
TABLE_SUFFIXES = (".nc", ".csv", ".md", ".json")


def environment() -> dict:
    """The environment of the test, with this interpreter's scripts (snakemake) first on PATH."""
    return {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"}


def run(root: Path, command: str) -> tuple[int, str]:
    """A shell command line run in ``root`` (as a user types it); exit code and output."""
    proc = subprocess.run(command, shell=True, cwd=root, env=environment(), capture_output=True, text=True, timeout=900)
    return proc.returncode, proc.stdout + proc.stderr


def start(root: Path) -> subprocess.Popen:
    """`snakemake --cores 2` in the background, in a process group of its own (with its jobs)."""
    return subprocess.Popen(
        ["snakemake", "--cores", "2"], cwd=root, env=environment(), stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL, start_new_session=True,
    )


def wait_for(path: Path, proc: subprocess.Popen, timeout: float = 600.0) -> None:
    """Wait until ``path`` exists (a job's log: the rule's script is running)."""
    deadline = time.monotonic() + timeout
    while not path.exists():
        assert proc.poll() is None, f"the run ended before {path} appeared"
        assert time.monotonic() < deadline, f"{path} did not appear"
        time.sleep(0.02)


def end_group(proc: subprocess.Popen) -> None:
    """SIGKILL whatever is left of the process group of ``proc`` (started by :func:`start`)."""
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    proc.wait(timeout=60)


def products(results: Path) -> dict[str, Path]:
    """Every output file under ``results`` by relative name (no logs, benchmarks, archive)."""
    skip = ("logs", "benchmarks", "archive")
    return {
        str(p.relative_to(results)): p
        for p in results.rglob("*")
        if p.is_file() and not p.name.startswith(".") and p.relative_to(results).parts[0] not in skip
    }


def assert_same_products(reference: Path, results: Path) -> None:
    """Same files; NetCDF data equal, tables and figures equal byte for byte."""
    ref, got = products(reference), products(results)
    assert sorted(got) == sorted(ref)
    for name, path in ref.items():
        if path.suffix == ".nc":
            assert archive.same_data(path, got[name]), name
        else:
            assert path.read_bytes() == got[name].read_bytes(), name


def assert_no_half_written_netcdf(results: Path) -> None:
    """Every NetCDF at an output path opens and reads whole."""
    for path in results.rglob("*.nc"):
        if not path.name.startswith("."):
            with xr.open_dataset(path) as ds:
                ds.load()


def partial_files(root: Path) -> list[Path]:
    return [p for p in (root / "results").rglob("*") if p.name.endswith(".partial")]


@pytest.fixture(scope="module")
def reference(tiny_workflow):
    """The uninterrupted run, with the archive of its scene (the session's build, tests/conftest.py)."""
    return tiny_workflow["root"]


# --- the archive ------------------------------------------------------------------------


def test_archive_holds_every_netcdf_and_table_of_the_products_with_the_rule_that_made_it(reference):
    code, out = run(reference, "snakemake --cores 2 --summary")
    assert code == 0, out
    made_by = {}
    for line in out.splitlines():
        fields = line.split("\t")
        if len(fields) > 2 and fields[0].startswith(f"results/{SCENE}/") and fields[0].endswith(TABLE_SUFFIXES):
            made_by[fields[0].removeprefix(f"results/{SCENE}/")] = fields[2]
    assert "series/replicate_1.nc" in made_by  # every series is stored, so archived
    manifest = json.loads((reference / "results" / SCENE / "archive" / "manifest.json").read_text())
    assert {f["name"]: f["rule"] for f in manifest["files"]} == made_by


def test_manifest_records_size_checksum_settings_versions_and_commit(reference):
    folder = reference / "results" / SCENE / "archive"
    manifest = json.loads((folder / "manifest.json").read_text())
    for entry in manifest["files"]:
        original = (reference / "results" / SCENE / entry["name"]).read_bytes()
        assert entry["size"] == len(original)
        assert entry["sha256"] == hashlib.sha256(original).hexdigest()
        assert (folder / entry["name"]).read_bytes() == original
    config = yaml.safe_load((reference / "config" / "config.yaml").read_text())
    assert manifest["scene"] == SCENE
    assert manifest["settings"]["records"] == {**config["scenes"][SCENE]["records"], "first_seed": 0, "replicates_per_job": None}
    assert set(manifest["versions"]) >= {"rockdec", "numpy", "xarray", "numba", "dask", "snakemake"}
    assert re.fullmatch(r"[0-9a-f]{40}|unknown", manifest["git_commit"])
    assert manifest["git_dirty"] in (True, False, None)


def verify(args, capsys) -> tuple[int, str]:
    try:
        code = main(["verify", *map(str, args)])
    except SystemExit as exc:
        code = exc.code
    out = capsys.readouterr()
    return code, out.out + out.err


def test_verify_says_ok_then_names_each_changed_and_missing_file(reference, tmp_path, capsys):
    folder = tmp_path / "archive"
    shutil.copytree(reference / "results" / SCENE / "archive", folder)
    code, out = verify([folder], capsys)
    assert code == 0 and out.startswith("OK") and len(out.strip().splitlines()) == 1, out
    with open(folder / "signatures.nc", "r+b") as f:  # one byte flipped, size unchanged
        f.seek(-100, os.SEEK_END)
        byte = f.read(1)
        f.seek(-100, os.SEEK_END)
        f.write(bytes([byte[0] ^ 1]))
    (folder / "table.md").unlink()
    code, out = verify([folder], capsys)
    assert code == 1
    assert sorted(out.strip().splitlines()) == ["changed: signatures.nc (SHA-256 differs from the manifest)", "missing: table.md"]


def test_verify_refuses_a_folder_without_manifest_and_an_existing_rebuild_folder(reference, tmp_path, capsys):
    code, out = verify([tmp_path], capsys)
    assert code == 2 and "holds no manifest.json" in out and "Traceback" not in out
    existing = tmp_path / "out"
    existing.mkdir()
    code, out = verify([reference / "results" / SCENE / "archive", "--rebuild", existing], capsys)
    assert code == 2 and "exists already" in out and not list(existing.iterdir())


def test_rebuild_remakes_tables_and_figures_from_the_archive_without_simulating(reference, tmp_path, capsys, monkeypatch):
    def no_simulation(*args, **kwargs):
        raise AssertionError("the rebuild simulated")

    monkeypatch.setattr(simulate, "simulate_block", no_simulation)
    monkeypatch.setattr(simulate, "simulation_dataset", no_simulation)
    folder = tmp_path / "archive"
    shutil.copytree(reference / "results" / SCENE / "archive", folder)
    out = tmp_path / "rebuilt"
    code, text = verify([folder, "--rebuild", out], capsys)
    assert code == 0, text
    assert text.count(": same as the archived") == 6 and "DIFFERS" not in text
    results = reference / "results" / SCENE
    rebuilt = products(out)
    expected = {name for name in products(results) if name.endswith((".csv", ".md", ".png", ".pdf"))}
    assert set(rebuilt) == expected | {"estimates.nc", "estimates_readings.nc"}
    for name in expected:
        assert rebuilt[name].read_bytes() == (results / name).read_bytes(), name
    for name in ("estimates.nc", "estimates_readings.nc"):
        assert archive.same_data(rebuilt[name], results / name), name


# --- killed and resumed -------------------------------------------------------------------

#: What rule `signatures` makes (its pass over the series runs after its log opens), and
#: what rule `table_readings` makes from it.
AFTER_SIGNATURES = ("signatures.nc", "readings.nc", "estimates_readings.nc", "table_readings.csv", "table_readings.md")


def half_built(reference: Path, root: Path) -> Path:
    """A copy of the finished reference run (results and Snakemake's records) without the
    products of rule `signatures` and of rule `table_readings` (the other rules after it
    rerun too, their inputs being newer)."""
    shutil.copytree(reference, root, dirs_exist_ok=True)
    results = root / "results" / SCENE
    for name in AFTER_SIGNATURES:
        (results / name).unlink()
    (results / "logs" / "signatures.log").unlink()
    return results


@pytest.mark.slow
def test_sigterm_then_the_readmes_command_gives_the_uninterrupted_outputs(reference, tmp_path):
    results = half_built(reference, tmp_path)
    proc = start(tmp_path)
    try:
        wait_for(results / "logs" / "signatures.log", proc)  # rule `signatures` runs
        os.killpg(proc.pid, signal.SIGTERM)  # to Snakemake and its jobs, as Ctrl-C, systemd or a batch system do
        assert proc.wait(timeout=120) != 0
    finally:
        end_group(proc)
    assert not (results / "readings.nc").exists()  # it was stopped on the way
    assert_no_half_written_netcdf(results)
    code, out = run(tmp_path, "snakemake --cores 2")  # the README's command
    assert code == 0, out
    assert_same_products(reference / "results" / SCENE, results)
    assert not partial_files(tmp_path)


@pytest.mark.slow
def test_sigkill_then_the_readmes_recovery_command_gives_the_uninterrupted_outputs(reference, tmp_path):
    results = half_built(reference, tmp_path)
    proc = start(tmp_path)
    try:
        wait_for(results / "logs" / "signatures.log", proc)
        os.killpg(proc.pid, signal.SIGKILL)  # Snakemake and its jobs at once, as a power loss
    finally:
        end_group(proc)
    assert not (results / "readings.nc").exists()  # it was killed on the way
    assert_no_half_written_netcdf(results)
    code, out = run(tmp_path, "snakemake --cores 2")
    assert code != 0 and "LockException" in out
    code, out = run(tmp_path, recovery_command())
    assert code == 0, out
    assert_same_products(reference / "results" / SCENE, results)
    assert not partial_files(tmp_path)


def recovery_command() -> str:
    """The one command the README gives under "If a run was killed"."""
    section = (REPO / "README.md").read_text().split("If a run was killed", 1)[1]
    return section.split("```bash\n", 1)[1].split("\n```", 1)[0].strip()

"""Archives, their Workflow Run Crate, `rockdec verify`, and workflow runs killed and resumed.

A copy of the workflow runs the tiny scene shrunk to 2 replicates of 10 series with every
series stored (`store_series: all`) and a fixed step (no calibration) without interruption:
the reference, and its archive. The archive's crate is checked as a reader would check it,
from the files themselves and the `rocrate` library; `rockdec verify` is run on copies of
the archive with one thing changed at a time. Copies of that run without the products of rule `readings`
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
import sys
import time
from pathlib import Path

from datetime import datetime

import pytest
import xarray as xr
import yaml
from rocrate.rocrate import ROCrate

from conftest import FORKS

from rockdec.pipeline import archive, steps
from rockdec.physics import simulate
from rockdec.pipeline import crate as crates
from rockdec import io as rockdec_io
from rockdec.cli import main

#: Every test here reads the tiny scene built by Snakemake end to end (conftest.tiny_workflow):
#: the slow tier (docs/development/testing.md).
pytestmark = pytest.mark.slow

REPO = Path(__file__).resolve().parents[2]
SCENE = "tiny"
TABLE_SUFFIXES = (".nc", ".csv", ".md", ".json")


def environment() -> dict:
    """The environment of the test, with this interpreter's scripts (snakemake) first on PATH."""
    return {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"}


def run(root: Path, command: str) -> tuple[int, str]:
    """A command line run by a shell in ``root`` as a user types it, ``snakemake`` being
    ``python -m snakemake`` forked by conftest.FORKS; its exit code and output."""
    code, out, err = FORKS.shell(root, command, env=environment())
    return code, out + err


def start(root: Path):
    """`snakemake --cores 2` in the background, in a process group of its own (with its
    jobs): a run forked by conftest.FORKS, read as a ``Popen``."""
    return FORKS.start(root, ["--cores", "2"], env=environment())


def wait_for(path: Path, proc, timeout: float = 600.0) -> None:
    """Wait until ``path`` exists (a job's log: the rule's script is running)."""
    deadline = time.monotonic() + timeout
    while not path.exists():
        assert proc.poll() is None, f"the run ended before {path} appeared"
        assert time.monotonic() < deadline, f"{path} did not appear"
        time.sleep(0.02)


def end_group(proc) -> None:
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


def test_the_archive_folder_holds_exactly_what_its_manifest_lists(reference):
    folder = reference / "results" / SCENE / "archive"
    manifest = json.loads((folder / "manifest.json").read_text())
    listed = {entry["name"] for entry in manifest["workflow"] + manifest["files"]} | {"manifest.json", "ro-crate-metadata.json"}
    assert {p.relative_to(folder).as_posix() for p in folder.rglob("*") if not p.is_dir()} == listed  # no .snakemake_timestamp


def test_verify_reports_a_snakemake_marker_left_in_the_folder(reference, tmp_path, capsys):
    copy = tmp_path / "archive"
    shutil.copytree(reference / "results" / SCENE / "archive", copy)
    (copy / ".snakemake_timestamp").touch()
    assert archive.verify(copy) == ["unlisted: .snakemake_timestamp (in the folder, not in manifest.json)"]


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


@pytest.mark.hostile("archive", "refused")
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


@pytest.mark.hostile("archive", "refused")
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
    assert "checked: the 6 files above" in text and "not rerun: the simulation" in text  # says what it compared
    results = reference / "results" / SCENE
    rebuilt = products(out)
    expected = {name for name in products(results) if name.endswith((".csv", ".md", ".png", ".pdf"))}
    assert set(rebuilt) == expected | {"estimates.nc", "estimates_readings.nc"}
    for name in expected:
        assert rebuilt[name].read_bytes() == (results / name).read_bytes(), name
    for name in ("estimates.nc", "estimates_readings.nc"):
        assert archive.same_data(rebuilt[name], results / name), name


# --- the archive as a Workflow Run Crate --------------------------------------------------

WORKFLOW_FILES = ("Snakefile", "workflow/", "config/")


def archived(folder: Path) -> dict[str, bytes]:
    """Every file of an archive folder by relative name, read as bytes (the crate file left out)."""
    return {
        p.relative_to(folder).as_posix(): p.read_bytes()
        for p in folder.rglob("*")
        if p.is_file() and p.name != "ro-crate-metadata.json"
    }


def flat(settings: dict, prefix: str = "") -> dict:
    """Nested settings as dotted names to values."""
    out = {}
    for key, value in settings.items():
        if isinstance(value, dict):
            out.update(flat(value, f"{prefix}{key}."))
        else:
            out[f"{prefix}{key}"] = value
    return out


def iso(text: str) -> datetime:
    return datetime.fromisoformat(text)


def test_crate_of_the_archive_is_a_workflow_run_crate_of_exactly_its_files(reference):
    folder = reference / "results" / SCENE / "archive"
    doc = json.loads((folder / "ro-crate-metadata.json").read_text())
    graph = {entity["@id"]: entity for entity in doc["@graph"]}
    ref = lambda value: [v["@id"] for v in (value if isinstance(value, list) else [value])]  # noqa: E731
    context = doc["@context"][0] if isinstance(doc["@context"], list) else doc["@context"]
    assert re.fullmatch(r"https://w3id\.org/ro/crate/1\.[1-9]\d*/context", context)
    assert {"sha256": "https://w3id.org/ro/terms/workflow-run#sha256"} in doc["@context"]  # no RO-Crate 1.1 term
    root = graph[ref(graph["ro-crate-metadata.json"]["about"])[0]]
    assert root["@type"] == "Dataset" and root["name"] and root["description"] and root["license"]
    assert iso(root["datePublished"])
    assert "https://w3id.org/ro/wfrun/workflow/0.5" in ref(root["conformsTo"])
    assert "https://w3id.org/ro/wfrun/process/0.5" in ref(root["conformsTo"])
    workflow = graph[ref(root["mainEntity"])[0]]
    assert workflow["@id"] == "Snakefile" and "ComputationalWorkflow" in workflow["@type"]
    language = graph[ref(workflow["programmingLanguage"])[0]]
    manifest = json.loads((folder / "manifest.json").read_text())
    assert language["name"] == "Snakemake" and language["version"] == manifest["versions"]["snakemake"]
    (action,) = [e for e in graph.values() if e["@type"] == "CreateAction"]
    assert ref(action["instrument"]) == ["Snakefile"]
    assert iso(action["startTime"]) <= iso(action["endTime"]) <= iso(root["datePublished"])
    settings = {graph[i]["name"]: graph[i]["value"] for i in ref(action["object"])}
    assert all(graph[i]["@type"] == "PropertyValue" for i in ref(action["object"]))
    expected = {k: v if isinstance(v, (bool, int, float, str)) else json.dumps(v) for k, v in flat(manifest["settings"]).items()}
    assert settings == {"scene": SCENE, **expected}
    files = archived(folder)
    products = {name for name in files if not name.startswith(WORKFLOW_FILES) and name != "manifest.json"}
    assert set(ref(action["result"])) == products
    assert set(ref(root["hasPart"])) == set(files)  # the products, the workflow and the manifest
    for name, data in files.items():
        entity = graph[name]
        assert entity["@type"] == "File" or "File" in entity["@type"], name
        assert int(entity["contentSize"]) == len(data), name
        assert entity["sha256"] == hashlib.sha256(data).hexdigest(), name
        assert entity["encodingFormat"], name
    assert graph["signatures.nc"]["encodingFormat"] == "application/x-netcdf"
    (paper,) = [graph[i] for i in ref(root["citation"])]
    assert paper["@type"] == "ScholarlyArticle"
    assert paper["name"] in " ".join((REPO / "README.md").read_text().split())  # the paper the README names


def test_rocrate_library_lists_every_archived_file_with_its_checksum_and_the_run_makes_the_products(reference):
    folder = reference / "results" / SCENE / "archive"
    crate = ROCrate(folder)
    listed = {entity.id: entity["sha256"] for entity in crate.get_by_type("File")}
    files = archived(folder)
    assert listed == {name: hashlib.sha256(data).hexdigest() for name, data in files.items()}
    (action,) = crate.get_by_type("CreateAction")
    assert action["instrument"] is crate.mainEntity
    products = {name for name in files if not name.startswith(WORKFLOW_FILES) and name != "manifest.json"}
    assert {entity.id for entity in action["result"]} == products
    assert crates.profile_problems(json.loads((folder / "ro-crate-metadata.json").read_text())) == []


@pytest.mark.hostile("archive", "refused")
@pytest.mark.parametrize(
    "damage",
    [
        lambda g: g["./"].pop("mainEntity"),
        lambda g: g["./"].update(conformsTo=[{"@id": "https://w3id.org/ro/crate/1.1"}]),
        lambda g: g["./"].pop("datePublished"),
        lambda g: g["./"].pop("license"),
        lambda g: g["Snakefile"].pop("programmingLanguage"),
        lambda g: g["Snakefile"].update({"@type": "File"}),
        lambda g: [e.pop("instrument") for e in g.values() if e["@type"] == "CreateAction"],
        lambda g: [e.pop("workExample") for e in g.values() if e["@type"] == "FormalParameter"],
        lambda g: g["ro-crate-metadata.json"].update(conformsTo={"@id": "https://w3id.org/ro/crate/1.0"}),
    ],
    ids=["mainEntity", "conformsTo", "datePublished", "license", "language", "workflow-type", "instrument",
         "parameter", "spec"],
)
def test_each_required_point_of_the_profile_is_checked(reference, damage):
    doc = json.loads((reference / "results" / SCENE / "archive" / "ro-crate-metadata.json").read_text())
    assert crates.profile_problems(doc) == []
    damage({entity["@id"]: entity for entity in doc["@graph"]})
    assert crates.profile_problems(doc)


def copy_archive(reference: Path, tmp_path: Path) -> Path:
    folder = tmp_path / "archive"
    shutil.copytree(reference / "results" / SCENE / "archive", folder, symlinks=True)
    return folder


def rewrite(folder: Path, manifest) -> None:
    """Replace the manifest, and the crate with the one derived from it (as someone who edits both would)."""
    path = folder / "manifest.json"
    path.write_text(json.dumps(manifest, indent=2) + "\n")
    try:
        archive.check_manifest(manifest, path)
    except archive.ArchiveError:
        return  # no crate derives from it
    else:
        entry = {"name": "manifest.json", "size": path.stat().st_size, "sha256": rockdec_io.sha256(path)}
        crate = crates.crate_from_manifest(manifest, entry)
        (folder / "ro-crate-metadata.json").write_text(json.dumps(crate, indent=2) + "\n")


@pytest.mark.hostile("archive", "refused")
def test_verify_catches_an_edited_manifest(reference, tmp_path, capsys):
    folder = copy_archive(reference, tmp_path)
    manifest = json.loads((folder / "manifest.json").read_text())
    manifest["settings"]["system"]["e"] = 0.9
    (folder / "manifest.json").write_text(json.dumps(manifest, indent=2) + "\n")
    code, out = verify([folder], capsys)
    assert code == 1 and "changed: manifest.json" in out, out
    assert "#setting-system.e' differs" in out


@pytest.mark.hostile("archive", "refused")
@pytest.mark.parametrize("edit", ["checksum", "result", "name"])
def test_verify_catches_an_edited_crate(reference, tmp_path, capsys, edit):
    folder = copy_archive(reference, tmp_path)
    doc = json.loads((folder / "ro-crate-metadata.json").read_text())
    graph = {entity["@id"]: entity for entity in doc["@graph"]}
    if edit == "checksum":
        graph["signatures.nc"]["sha256"] = graph["table.csv"]["sha256"]
    elif edit == "result":
        action = next(e for e in graph.values() if e["@type"] == "CreateAction")
        action["result"] = action["result"][1:]
    else:
        graph["./"]["name"] = "another archive"
    (folder / "ro-crate-metadata.json").write_text(json.dumps(doc))
    code, out = verify([folder], capsys)
    assert code == 1 and out.startswith("changed: ro-crate-metadata.json") and len(out.strip().splitlines()) == 1, out


def outside_file(tmp_path: Path) -> Path:
    path = tmp_path / "outside" / "secret.nc"
    path.parent.mkdir()
    path.write_bytes(b"not part of the archive")
    return path


def watch_reads(monkeypatch) -> list[str]:
    """Every path opened (by open, os.open or io.sha256, the archive's file hash) from now on."""
    seen: list[str] = []
    real_open, real_os_open, real_sha = open, os.open, rockdec_io.sha256

    def spy_open(file, *args, **kwargs):
        if isinstance(file, (str, os.PathLike)):
            seen.append(os.fspath(file))
        return real_open(file, *args, **kwargs)

    def spy_os_open(path, *args, **kwargs):
        seen.append(os.fspath(path))
        return real_os_open(path, *args, **kwargs)

    def spy_sha(path):
        seen.append(os.fspath(path))
        return real_sha(path)

    monkeypatch.setattr("builtins.open", spy_open)
    monkeypatch.setattr(os, "open", spy_os_open)
    monkeypatch.setattr(rockdec_io, "sha256", spy_sha)
    return seen


@pytest.mark.hostile("archive", "refused")
@pytest.mark.parametrize("entry", ["climb", "absolute"])
def test_verify_refuses_entries_outside_the_folder_without_opening_them(reference, tmp_path, capsys, monkeypatch, entry):
    folder = copy_archive(reference, tmp_path)
    secret = outside_file(tmp_path)
    manifest = json.loads((folder / "manifest.json").read_text())
    name = "../outside/secret.nc" if entry == "climb" else str(secret)
    manifest["files"][0].update(name=name, size=secret.stat().st_size, sha256=hashlib.sha256(secret.read_bytes()).hexdigest())
    (folder / "manifest.json").write_text(json.dumps(manifest))
    seen = watch_reads(monkeypatch)
    code, out = verify([folder], capsys)
    assert code == 2 and len(out.strip().splitlines()) == 1 and "Traceback" not in out, out
    assert "absolute path" in out if entry == "absolute" else "'..'" in out
    assert str(secret) not in seen and not any(Path(p).resolve() == secret for p in seen)


@pytest.mark.hostile("archive", "refused")
@pytest.mark.parametrize("link", ["file", "folder"])
def test_verify_refuses_a_symlinked_entry_with_updated_checksums_without_opening_it(reference, tmp_path, capsys, monkeypatch, link):
    folder = copy_archive(reference, tmp_path)
    manifest = json.loads((folder / "manifest.json").read_text())
    if link == "file":
        secret = outside_file(tmp_path)
        (folder / "table.md").unlink()
        (folder / "table.md").symlink_to(secret)
        entry = next(e for e in manifest["files"] if e["name"] == "table.md")
        entry.update(size=secret.stat().st_size, sha256=hashlib.sha256(secret.read_bytes()).hexdigest())
        expected = "not a plain file: table.md"
    else:  # the series folder moved out and linked back: same bytes, read through a link
        shutil.move(folder / "series", tmp_path / "series")
        (folder / "series").symlink_to(tmp_path / "series")
        secret = tmp_path / "series" / "replicate_1.nc"
        expected = "not a plain file: series/replicate_1.nc ('series' is a symbolic link"
    rewrite(folder, manifest)
    seen = watch_reads(monkeypatch)
    code, out = verify([folder], capsys)
    assert code == 1 and expected in out, out
    assert not any(os.path.realpath(p) == str(secret.resolve()) for p in seen), "the link's target was read"
    assert all(os.path.realpath(p).startswith(str(folder.resolve()) + os.sep) for p in seen if Path(p).is_relative_to(folder))


@pytest.mark.hostile("archive", "refused")
def test_verify_reports_files_nobody_listed(reference, tmp_path, capsys):
    folder = copy_archive(reference, tmp_path)
    (folder / "notes.txt").write_text("added later\n")
    (folder / "series" / "replicate_9.nc").write_bytes(b"added later")
    code, out = verify([folder], capsys)
    assert code == 1
    assert sorted(out.strip().splitlines()) == [
        "unlisted: notes.txt (in the folder, not in manifest.json)",
        "unlisted: series/replicate_9.nc (in the folder, not in manifest.json)",
    ]


@pytest.mark.hostile("archive", "refused")
@pytest.mark.parametrize(
    "change, words",
    [
        (lambda m: m.update(files=[]), "field files is empty"),
        (lambda m: m.pop("files"), "lacks the key 'files'"),
        (lambda m: m.pop("settings"), "lacks the key 'settings'"),
        (lambda m: m["files"][0].pop("sha256"), "field files.0 lacks the key 'sha256'"),
        (lambda m: m["files"][0].update(size="12"), "field files.0.size is a string, not an integer"),
        (lambda m: m["files"][0].update(sha256="0" * 63), "is not of the form"),
        (lambda m: m.update(git_dirty="maybe"), "field git_dirty is a string"),
        (lambda m: m["files"].append(dict(m["files"][0])), "is listed twice"),
        (lambda m: m["files"][0].update(name="./table.csv"), "not a plain relative path"),
        (lambda m: m["run"].update(startTime="yesterday"), "not an ISO 8601 time"),
    ],
    ids=["empty", "no-files", "no-settings", "no-sha", "size-text", "short-sha", "dirty", "twice", "dot", "time"],
)
def test_verify_refuses_a_malformed_manifest_in_one_sentence(reference, tmp_path, capsys, change, words):
    folder = copy_archive(reference, tmp_path)
    manifest = json.loads((folder / "manifest.json").read_text())
    change(manifest)
    rewrite(folder, manifest)
    code, out = verify([folder], capsys)
    assert code == 2 and len(out.strip().splitlines()) == 1 and words in out, out
    assert "internal error" not in out and "Traceback" not in out


@pytest.mark.hostile("archive", "refused")
@pytest.mark.parametrize("text", ["[]", '"files"', "{not json", ""])
def test_verify_refuses_a_manifest_that_is_not_an_object(reference, tmp_path, capsys, text):
    folder = copy_archive(reference, tmp_path)
    (folder / "manifest.json").write_text(text)
    code, out = verify([folder], capsys)
    assert code == 2 and len(out.strip().splitlines()) == 1 and "internal error" not in out, out


@pytest.mark.hostile("archive", "refused")
def test_rebuild_refuses_tampered_settings_and_leaves_no_folder(reference, tmp_path, capsys):
    folder = copy_archive(reference, tmp_path)
    manifest = json.loads((folder / "manifest.json").read_text())
    manifest["settings"]["estimates"]["weights"] = "bogus"
    rewrite(folder, manifest)  # both edited alike: verify cannot tell, the rebuild must refuse
    out = tmp_path / "rebuilt"
    code, text = verify([folder, "--rebuild", out], capsys)
    assert code == 2 and "estimates.weights" in text and "internal error" not in text, text
    assert sorted(p.name for p in tmp_path.iterdir()) == ["archive"]


@pytest.mark.hostile("limits", "refused")
def test_a_rebuild_that_fails_half_way_leaves_no_folder(reference, tmp_path, capsys, monkeypatch):
    def broken(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(steps, "fig1b", broken)  # after the tables are written
    folder = copy_archive(reference, tmp_path)
    code, text = verify([folder, "--rebuild", tmp_path / "rebuilt"], capsys)
    assert code != 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["archive"]


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


@pytest.mark.hostile("kills", "answered")
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


@pytest.mark.hostile("kills", "answered")
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
    """The one command the docs give under "If a run was killed" (docs/how-to/paper.md)."""
    section = (REPO / "docs" / "how-to" / "paper.md").read_text().split("If a run was killed", 1)[1]
    return section.split("```bash\n", 1)[1].split("\n```", 1)[0].strip()

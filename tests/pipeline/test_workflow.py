"""The Snakemake workflow end to end: a shrunken ``tiny`` scene built once (the session's
build, tests/conftest.py), its products, its job list, what reruns after a rule's code or a
setting changes, the same products on Dask worker processes, and the cluster profile's jobs.
The checks without a build are in test_workflow_rules.py.
"""

from __future__ import annotations

import contextlib
import re
import shutil
from pathlib import Path

import matplotlib.image
import pytest
import xarray as xr
import yaml

from cf_check import NO_FINDINGS, cf_findings
from conftest import snakemake
from rockdec.report import figures
from rockdec.pipeline import layout
from rockdec.physics import run

REPO = Path(__file__).resolve().parents[2]

# --- the workflow, end to end ---------------------------------------------------------

SCENE = "tiny"
FIGURE_FILES = [f"figures/{name}.{fmt}" for name in layout.FIGURES for fmt in ("png", "pdf")]
PRODUCTS = [
    "run.json",
    "stored_series.nc",
    "signatures.nc",
    "readings.nc",
    "stored_signature.nc",
    "estimates.nc",
    "estimates_readings.nc",
    "table.csv",
    "table.md",
    "table_readings.csv",
    "table_readings.md",
    *FIGURE_FILES,
]
JOBS = {
    "calibrate": 1,
    "series": 2,  # every series stored, one file a replicate
    "stored_series": 1,
    "signatures": 1,
    "estimates": 1,
    "table_readings": 1,
    "stored_signature": 1,
    **{name: 1 for name in layout.FIGURES},
    "all": 1,
}


def job_stats(output: str) -> dict[str, int]:
    """The first "Job stats" table of a Snakemake log as {rule: count}; {} if nothing to do."""
    if "Nothing to be done" in output:
        return {}
    table = output.split("Job stats:", 1)[1].splitlines()[3:]
    counts = {}
    for line in table:
        match = re.fullmatch(r"\s*(\S+)\s+(\d+)\s*", line)
        if not match or match[1] == "total":
            break
        counts[match[1]] = int(match[2])
    return counts


@pytest.fixture(scope="module")
def workflow(tiny_workflow):
    """The copy of the workflow with a shrunken tiny scene, dry-run and then built once (the
    session's build, tests/conftest.py)."""
    return tiny_workflow


@pytest.mark.slow
def test_dry_run_lists_exactly_the_jobs_of_the_default_scene(workflow):
    assert job_stats(workflow["dry_run"]) == JOBS


@pytest.mark.slow
def test_workflow_builds_every_product_and_each_opens(workflow):
    results = workflow["root"] / "results" / SCENE
    for name in PRODUCTS:
        path = results / name
        assert path.is_file() and path.stat().st_size > 0, name
        if path.suffix == ".json":
            assert run.Run.read(path).e == 0.95
        elif path.suffix == ".nc":
            with xr.open_dataset(path) as ds:
                assert ds.data_vars
        elif path.suffix == ".png":
            assert matplotlib.image.imread(path).ndim == 3
        elif path.suffix == ".pdf":
            assert path.read_bytes().startswith(b"%PDF")
    with xr.open_dataset(results / "stored_signature.nc") as stored:
        assert stored.sizes["group"] == 1
        assert int(stored["count"].sel(trigger="a").max()) > 0


@pytest.mark.slow
def test_every_rule_writes_its_benchmark_and_its_log_those_in_the_snakemake_process_too(workflow):
    results = workflow["root"] / "results" / SCENE
    singles = [name for name in JOBS if name not in ("all", "series")]
    for name in [*singles, "series_0", "series_1"]:
        with open(results / "benchmarks" / f"{name}.tsv") as f:
            header, row = f.read().splitlines()[:2]
        assert header.split("\t")[0] == "s" and float(row.split("\t")[0]) >= 0, name
    in_process = ["calibrate", "stored_series", "stored_signature", "estimates", "table_readings", *layout.FIGURES]
    logs = {**{name: name for name in in_process}, "series_0": "series", "series_1": "series"}
    for name, rule in logs.items():  # rockdec.pipeline.in_snakemake: a start line, an end line
        lines = (results / "logs" / f"{name}.log").read_text().splitlines()
        assert lines[0] == f"{rule}: started" and re.fullmatch(rf"{rule}: done in [\d.]+ s", lines[-1]), (name, lines)
    contract = run.Run.read(results / "run.json")
    assert (results / "logs" / "calibrate.log").read_text().splitlines()[1] == f"run: {contract}"


@pytest.mark.slow
def test_every_netcdf_product_is_cf_clean_and_carries_its_inputs_history(workflow, tmp_path):
    root = workflow["root"]
    products = sorted((root / "results" / SCENE).glob("*.nc"))
    assert len(products) == 6, products
    contract = run.Run.read(root / "results" / SCENE / "run.json")
    for path in products:
        assert cf_findings(path) == NO_FINDINGS, path.name
        with xr.open_dataset(path) as ds:
            attrs = ds.attrs
        history = attrs["history"].splitlines()
        assert len(set(history)) == len(history), path.name
        if path.name in ("stored_series.nc", "signatures.nc", "stored_signature.nc"):  # the run travels with the data
            assert run.Run.from_attrs(attrs) == contract, path.name
        for source in attrs["source_files"].splitlines():
            if not source.endswith(".nc"):  # run.json: read whole, no history
                continue
            with xr.open_dataset(root / source) as src:  # paths as the rule gave them
                before = src.attrs["history"].splitlines()
            assert set(before) <= set(history[:-1]), (path.name, source)
        assert history[-1].endswith(" ".join(attrs["source_files"].splitlines()))


def declared_localrules() -> set[str]:
    """The rules the Snakefile's ``localrules:`` block names (Snakemake refuses unknown names)."""
    block = (REPO / "Snakefile").read_text().split("\nlocalrules:\n", 1)[1]
    return set(re.findall(r"^    (\w+),$", block.split("\n\n", 1)[0], re.M))


def test_figure_table_and_archive_rules_run_on_the_submitting_node_and_compute_rules_do_not():
    local = declared_localrules()
    assert {"estimates", "table_readings", *layout.FIGURES, "fig_amplitude", "fig_tradeoff", "fig_coverage",
            "coverage_table", "archive_scene", "all"} <= local
    assert not local & {"calibrate", "stored_series", "series", "signatures", "signature_part", "stored_signature",
                        "choices", "amplitude", "tradeoff", "coverage_case"}


@pytest.mark.slow
def test_no_job_prints_an_empty_shell_command(workflow):
    assert "rule signatures:" in workflow["log"] and "Shell command" not in workflow["log"]


@pytest.mark.slow
def test_the_signature_log_has_labelled_lines_and_no_progress_bar_frames(workflow):
    log = (workflow["root"] / "results" / SCENE / "logs" / "signatures.log").read_text()
    assert "\r" not in log
    lines = log.splitlines()
    assert lines[0] == "signatures: 2 replicates x 10 series: started"
    assert re.fullmatch(r"signatures: 2 replicates x 10 series: done in [\d.]+ s", lines[-1])


@pytest.mark.slow
def test_reordering_the_keys_of_a_scene_reruns_nothing(workflow):
    def reorder(scene):
        for key, value in list(scene.items()):
            scene[key] = dict(reversed(list(value.items()))) if isinstance(value, dict) else value
        items = list(scene.items())
        scene.clear()
        scene.update(reversed(items))

    assert dry_run_after(workflow["root"], reorder) == {}


@pytest.mark.slow
def test_a_nested_config_override_is_read_as_yaml_values(workflow):
    code, out = snakemake(workflow["root"], "-n", "--config", "scenes={tiny: {signatures: {level: 2.5}}}")
    assert code == 0, out
    jobs = job_stats(out)
    assert jobs["signatures"] == 1 and "calibrate" not in jobs  # level 2.5 is a number: the pass reruns


@pytest.mark.slow
@pytest.mark.parametrize("scheduler", ["processes:2", pytest.param("tcp", marks=pytest.mark.dask_scheduler)])
def test_the_tiny_scene_on_worker_processes_gives_the_products_of_threads(workflow, tmp_path, scheduler, monkeypatch, request):
    """Rules ``signatures`` (the pass over the stored series on the Dask engine the variable
    names) and ``stored_series`` rerun in a copy of the threads' build, with the estimates of
    both readings after them, make the threads' products. The series written on each engine
    (rule ``series``): test_engine.py."""
    root = tmp_path / "copy"
    shutil.copytree(workflow["root"], root, symlinks=True)  # threads' products, mtimes kept
    products = ["stored_series.nc", "signatures.nc", "readings.nc", "estimates.nc", "estimates_readings.nc"]
    targets = [f"results/{SCENE}/{name}" for name in products]
    if scheduler == "tcp":  # the session's running scheduler on loopback, given by its address (tests/conftest.py)
        scheduler = request.getfixturevalue("dask_scheduler")
    monkeypatch.setenv("ROCKDEC_DASK_SCHEDULER", scheduler)  # the snakemake process inherits it
    code, out = snakemake(root, "--forcerun", "signatures", "stored_series", "--", *targets)
    assert code == 0, out
    assert job_stats(out) == {"stored_series": 1, "signatures": 1, "estimates": 1, "table_readings": 1}, out
    for name in products:
        with xr.open_dataset(root / "results" / SCENE / name) as got, \
                xr.open_dataset(workflow["root"] / "results" / SCENE / name) as want:
            assert got.equals(want), name  # every variable and coordinate, bit for bit


@pytest.mark.slow
def test_editing_a_figures_rule_code_reruns_only_that_figure(workflow):
    """A figure rule's code is its ``run:`` block (handing the figure to a figure worker,
    rockdec.pipeline.in_snakemake.draw); the code rerun trigger (profiles/default) redraws
    that figure alone when its code changes."""
    root = workflow["root"]
    code, out = snakemake(root, "-n")
    assert code == 0 and job_stats(out) == {}, out
    rules = root / "workflow" / "rules" / "figures.smk"
    before = rules.read_text()
    call = "in_snakemake.draw(rule, log[0], input.est, [output.png, output.pdf])"
    at = before.index(call, before.index("rule fig3:"))
    rules.write_text(before[:at] + call.replace("png, output.pdf", "pdf, output.png") + before[at + len(call):])
    try:
        code, out = snakemake(root, "-n")
    finally:
        rules.write_text(before)
    assert code == 0 and job_stats(out) == {"fig3": 1, "all": 1}, out
    code, out = snakemake(root, "-n")  # the code the products were made with again: nothing to do
    assert code == 0 and job_stats(out) == {}, out


@contextlib.contextmanager
def edited_scene(root: Path, edit):
    """The copy's config with ``edit(scene)`` applied to the tiny scene, restored afterwards."""
    path = root / "config" / "config.yaml"
    before = path.read_text()
    config = yaml.safe_load(before)
    edit(config["scenes"][SCENE])
    path.write_text(yaml.safe_dump(config, sort_keys=False))
    try:
        yield
    finally:
        path.write_text(before)


def dry_run_after(root: Path, edit) -> dict[str, int]:
    with edited_scene(root, edit):
        code, out = snakemake(root, "-n")
    assert code == 0, out
    return job_stats(out)


@pytest.mark.slow
def test_editing_a_description_reruns_nothing(workflow):
    assert dry_run_after(workflow["root"], lambda scene: scene.update(description="another text")) == {}


@pytest.mark.slow
def test_editing_the_extrapolation_weights_reruns_only_what_reads_them(workflow):
    jobs = dry_run_after(workflow["root"], lambda scene: scene["estimates"].update(weights="count"))
    # the estimates and the readings' table read the weights; the figures read the estimates
    assert jobs == {"estimates": 1, "table_readings": 1, "fig3": 1, "fig4": 1, "fig_ev": 1, "all": 1}


@pytest.mark.slow
def test_editing_a_signature_setting_reruns_the_pass_but_not_the_run(workflow):
    jobs = dry_run_after(workflow["root"], lambda scene: scene["signatures"].update(level=2.5))
    assert "calibrate" not in jobs and "stored_series" not in jobs and "fig1b" not in jobs
    assert jobs["signatures"] == 1 and jobs["stored_signature"] == 1 and jobs["estimates"] == 1


@pytest.mark.slow
def test_editing_the_system_reruns_from_the_run_contract(workflow):
    jobs = dry_run_after(workflow["root"], lambda scene: scene["system"].update(e=0.9))
    assert jobs["calibrate"] == 1 and jobs["stored_series"] == 1 and jobs["signatures"] == 1


# --- a cluster: the large scene's signature pass is split into jobs a cluster spreads


@pytest.mark.slow
def test_the_slurm_profile_lists_the_large_scenes_signature_jobs(workflow):
    code, out = snakemake(workflow["root"], "-n", "--profile", "profiles/slurm", "results/large/table.csv")
    assert code == 0, out
    assert job_stats(out) == {"calibrate": 1, "signature_part": 20, "signatures": 1, "estimates": 1}
    assert re.search(r"resources: .*mem_mb=\d+", out) and "runtime=60" in out, out

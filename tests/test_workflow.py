"""The Snakemake workflow as a whole: what reruns after which change, by dry runs only.

Organised by topic, one section each; the end-to-end section builds a shrunken ``tiny`` scene
once and checks its products, its job list and what reruns after a script or a setting
changes; the others use dry runs only.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import matplotlib.image
import pytest
import xarray as xr
import yaml

from cf_check import NO_FINDINGS, cf_findings
from conftest import snakemake
from rockdec import config, figures, job, run
from rockdec.validate import InputError

REPO = Path(__file__).resolve().parents[1]

# --- the workflow, end to end ---------------------------------------------------------

SCENE = "tiny"
FIGURE_FILES = [f"figures/{name}.{fmt}" for name in figures.FIGURES for fmt in ("png", "pdf")]
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
    **{name: 1 for name in figures.FIGURES},
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
    assert {"estimates", "table_readings", *figures.FIGURES, "fig_amplitude", "fig_tradeoff", "fig_coverage",
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
@pytest.mark.parametrize("scheduler", ["processes:2", "tcp"])
def test_the_tiny_scene_on_worker_processes_gives_the_products_of_threads(workflow, tmp_path, scheduler, monkeypatch):
    root = tmp_path / "copy"
    shutil.copytree(workflow["root"], root, symlinks=True)  # threads' products, mtimes kept
    products = ["series/replicate_0.nc", "series/replicate_1.nc", "stored_series.nc", "signatures.nc", "readings.nc",
                "estimates.nc", "estimates_readings.nc"]
    targets = [f"results/{SCENE}/{name}" for name in products]
    with contextlib.ExitStack() as stack:
        if scheduler == "tcp":  # a running scheduler on loopback, given by its address
            from dask.distributed import LocalCluster

            cluster = stack.enter_context(LocalCluster(n_workers=2, threads_per_worker=1, host="127.0.0.1",
                                                       dashboard_address=None))
            scheduler = cluster.scheduler_address
        monkeypatch.setenv("ROCKDEC_DASK_SCHEDULER", scheduler)  # the snakemake process inherits it
        code, out = snakemake(root, "--forcerun", "series", "stored_series", "signatures", "--", *targets)
    assert code == 0, out
    assert job_stats(out)["signatures"] == 1
    for name in products:
        with xr.open_dataset(root / "results" / SCENE / name) as got, \
                xr.open_dataset(workflow["root"] / "results" / SCENE / name) as want:
            assert got.equals(want), name  # every variable and coordinate, bit for bit


@pytest.mark.slow
def test_editing_a_figures_rule_code_reruns_only_that_figure(workflow):
    """A figure rule runs its code in the Snakemake process (``run:``); the code rerun
    trigger (profiles/default) redraws that figure alone when its code changes."""
    root = workflow["root"]
    code, out = snakemake(root, "-n")
    assert code == 0 and job_stats(out) == {}, out
    rules = root / "workflow" / "rules" / "figures.smk"
    before = rules.read_text()
    call = "job.step(rule, log[0], input.est, [output.png, output.pdf])"
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


# --- studies: a change to a study's compute code reruns it; a change to drawing code only redraws

STUDIES = {
    # target rule: (compute rule, its module, plot rule)
    "tradeoff_study": ("tradeoff", "tradeoff.py", "fig_tradeoff"),
    "amplitude_study": ("amplitude", "amplitude.py", "fig_amplitude"),
}
BUILT = 1_700_000_000  # modification time of every source file of the copy, in s since the epoch


def study_outputs(root: Path, compute_rule: str) -> tuple[list[Path], list[Path]]:
    """The files the compute rule and the plot rule of a study write (as in workflow/rules)."""
    folder = root / "results" / "studies" / compute_rule
    data = [folder / f"{compute_rule}.nc", folder / "table.csv", folder / "table.md"]
    figure = "pareto" if compute_rule == "tradeoff" else compute_rule
    return data, [folder / "figures" / f"{figure}.{fmt}" for fmt in ("png", "pdf")]


def set_times(root: Path) -> None:
    """Sources at :data:`BUILT`, each study's data 10 s later and its figures 20 s later: up to date."""
    for path in root.rglob("*"):
        if path.is_file():
            os.utime(path, (BUILT, BUILT))
    for compute_rule, _, _ in STUDIES.values():
        data, figures = study_outputs(root, compute_rule)
        for path in data:
            os.utime(path, (BUILT + 10, BUILT + 10))
        for path in figures:
            os.utime(path, (BUILT + 20, BUILT + 20))


def touch(path: Path) -> None:
    """Make ``path`` newer than every product."""
    os.utime(path, (BUILT + 30, BUILT + 30))


@pytest.fixture(scope="module")
def built_studies(tmp_path_factory):
    """A copy of the workflow and of the package with both studies' products in place (empty
    files, dated after their inputs), so a dry run has nothing to do until a file is touched.

    The package is copied to ``<copy>/rockdec``: ``python -m snakemake`` puts its working
    directory first on ``sys.path``, so the rules' ``find_spec("rockdec....")`` resolve to the
    copy, and touching it leaves the installed sources (and their products) alone.
    """
    root = tmp_path_factory.mktemp("studies")
    shutil.copy(REPO / "Snakefile", root)
    for folder in ("workflow", "config"):
        shutil.copytree(REPO / folder, root / folder)
    shutil.copytree(REPO / "src" / "rockdec", root / "rockdec", ignore=shutil.ignore_patterns("__pycache__"))
    for compute_rule, _, _ in STUDIES.values():
        for path in sum(study_outputs(root, compute_rule), []):
            path.parent.mkdir(parents=True, exist_ok=True)
            path.touch()
    return root


@pytest.fixture
def studies(built_studies):
    """The copy, every product up to date again (whatever an earlier test touched)."""
    set_times(built_studies)
    return built_studies


def dry_run(root: Path, target: str) -> dict[str, int]:
    code, out = snakemake(root, "-n", target)
    assert code == 0, out
    return job_stats(out)


def test_the_rules_read_the_copied_package(studies):
    code, out = snakemake(studies, "-n", "--forcerun", "tradeoff", "tradeoff")
    assert code == 0, out
    assert str(studies / "rockdec" / "tradeoff.py") in out
    assert str(REPO / "src") not in out


@pytest.mark.parametrize("target", STUDIES)
def test_an_up_to_date_study_has_nothing_to_do(studies, target):
    assert dry_run(studies, target) == {}


@pytest.mark.parametrize("target", STUDIES)
def test_changing_the_study_module_reruns_the_study_and_its_figure(studies, target):
    compute_rule, module, plot_rule = STUDIES[target]
    touch(studies / "rockdec" / module)
    assert dry_run(studies, target) == {compute_rule: 1, plot_rule: 1, target: 1}


def test_changing_a_module_the_study_imports_reruns_it(studies):
    touch(studies / "rockdec" / "tables.py")  # the replicate statistics of both studies
    assert dry_run(studies, "tradeoff_study") == {"tradeoff": 1, "fig_tradeoff": 1, "tradeoff_study": 1}


@pytest.mark.parametrize("target", STUDIES)
def test_changing_the_drawing_code_redraws_without_rerunning_the_study(studies, target):
    _, _, plot_rule = STUDIES[target]
    touch(studies / "rockdec" / "figures.py")
    assert dry_run(studies, target) == {plot_rule: 1, target: 1}


def test_the_compute_rule_alone_is_a_target(studies):
    touch(studies / "rockdec" / "tradeoff.py")
    assert dry_run(studies, "tradeoff") == {"tradeoff": 1}


# --- conventions: lint, versions, settings from the command line, sizes refused up front


@pytest.fixture(scope="module")
def bare(tmp_path_factory):
    """A copy of the workflow and its config, nothing built."""
    root = tmp_path_factory.mktemp("bare")
    shutil.copy(REPO / "Snakefile", root)
    for folder in ("workflow", "config", "profiles"):
        shutil.copytree(REPO / folder, root / folder)
    return root


def test_snakemake_lint_finds_nothing(bare):
    code, out = snakemake(bare, "--lint")
    assert code == 0, out
    assert "Lints for" not in out and "in a good condition" in out, out


def test_the_snakefile_names_the_snakemake_it_needs():
    assert re.search(r'^min_version\("9\.0"\)$', (REPO / "Snakefile").read_text(), re.M)


def test_a_bad_value_given_with_config_names_that_option(bare):
    code, out = snakemake(bare, "-n", "--config", "scenes={tiny: {records: {replicates: three}}}")
    assert code == 2, out
    line = out.strip().splitlines()[-1]
    assert "scenes.tiny.records.replicates" in line and config.OVERRIDE_SOURCE in line, out
    assert "config/config.yaml" not in line and "Traceback" not in out


SIZES = {
    "1e12 points": ({"n_points": 10**12}, "needs about 1.6e+14 samples"),
    "2e9 points": ({"n_points": 2 * 10**9, "chunk_seeds": 10}, "GB of memory"),
    "200,000 replicates": ({"replicates": 200_000, "series_per_replicate": 1000}, "needs about 1.2e+12 samples"),
    "1e6 x 1e6 series": ({"replicates": 10**6, "series_per_replicate": 10**6}, "needs about 6e+15 samples"),
}


@pytest.mark.parametrize("records, words", SIZES.values(), ids=SIZES.keys())
def test_a_scene_too_large_is_refused_at_validation_with_the_estimate(records, words):
    scene = {"records": {"replicates": 4, "series_per_replicate": 40, **records}}
    with pytest.raises(config.ConfigError, match="scenes.tiny.records") as refused:
        config.validate_scene(scene, "tiny", sizes=True)
    assert words in str(refused.value) and str(refused.value).count(". ") == 1  # one sentence, then the fix


def test_a_dry_run_refuses_a_scene_too_large_in_one_sentence(bare):
    records, words = SIZES["1e6 x 1e6 series"]  # a 7 TiB seed table if anything built it
    code, out = snakemake(bare, "-n", "--config", "scenes={tiny: {records: {replicates: 1000000, series_per_replicate: 1000000}}}")
    assert code == 2, out
    line = out.strip().splitlines()[-1]
    assert line.startswith("rockdec: error: config field 'scenes.tiny.records'") and words in line, out
    assert "Traceback" not in out


def test_every_scene_of_the_config_passes_the_size_checks():
    assert {"paper", "large", "tiny"} <= set(config.load(REPO / "config" / "config.yaml")["scenes"])


# --- around every script (rockdec.job): errors on the console, orphans of a killed Snakemake


class FakeJob:
    """What rockdec.job reads of Snakemake's ``snakemake`` object."""

    def __init__(self, folder: Path):
        self.rule, self.log, self.output = "signatures", [str(folder / "rule.log")], [str(folder / "out.nc")]


def test_a_user_error_in_a_rule_shows_its_sentence_on_the_console_and_exits_2(tmp_path, capsys):
    def main(smk):
        raise InputError("output 'x.nc' exists already; remove it.")

    with pytest.raises(SystemExit) as stop:
        job.run(main, FakeJob(tmp_path))
    assert stop.value.code == 2
    assert capsys.readouterr().err.strip() == "rockdec: error in rule signatures: output 'x.nc' exists already; remove it."
    assert (tmp_path / "rule.log").read_text().strip() == "rockdec: error: output 'x.nc' exists already; remove it."


ORPHAN = """
import json, pathlib, subprocess, sys, time
from rockdec import job
if sys.argv[1] == "parent":  # plays Snakemake: starts the job, then waits
    subprocess.Popen([sys.executable, __file__, "job", sys.argv[2]])
    time.sleep(120)
else:  # the job: records itself as rockdec.job does, then works on
    pathlib.Path(sys.argv[2]).write_text(json.dumps(job._record()))
    time.sleep(120)
"""


def start_job_under_a_parent(tmp_path: Path):
    """A parent process (standing for Snakemake) and the job it started; returns (parent, job pid)."""
    import psutil

    script = tmp_path / "orphan.py"
    script.write_text(ORPHAN)
    pid_file = Path(FakeJob(tmp_path).log[0] + ".pid")
    parent = subprocess.Popen([sys.executable, str(script), "parent", str(pid_file)])
    for _ in range(600):
        if pid_file.exists() and pid_file.read_text():
            break
        time.sleep(0.05)
    pid = json.loads(pid_file.read_text())["pid"]
    return parent, psutil.Process(pid)


def test_a_rerun_stops_the_orphan_of_a_killed_snakemake_and_clears_its_output(tmp_path, capsys):
    parent, orphan = start_job_under_a_parent(tmp_path)
    parent.kill()  # kill -9 of Snakemake alone: its job goes on
    parent.wait()
    assert orphan.is_running()
    (tmp_path / "out.nc").write_text("written by the orphan")
    ran = []
    job.run(lambda smk: ran.append(Path(smk.output[0]).exists()), FakeJob(tmp_path))
    assert ran == [False]  # the orphan's output was cleared before the rule ran
    assert not orphan.is_running() or orphan.status() == "zombie"
    assert "orphaned job of rule signatures" in capsys.readouterr().err
    assert not Path(FakeJob(tmp_path).log[0] + ".pid").exists()


def test_a_rerun_refuses_while_the_snakemake_of_a_running_job_still_runs(tmp_path, capsys):
    parent, orphan = start_job_under_a_parent(tmp_path)
    try:
        with pytest.raises(SystemExit) as stop:
            job.run(lambda smk: None, FakeJob(tmp_path))
        assert stop.value.code == 2
        assert f"running already for these outputs (process {orphan.pid}" in capsys.readouterr().err
        assert orphan.is_running()
    finally:
        orphan.kill()
        parent.kill()
        parent.wait()

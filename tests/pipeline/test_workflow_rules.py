"""The Snakemake workflow without a build: what reruns after a change to a study's code, by
dry runs on a copy whose products are dated; the conventions (lint, versions, settings from
the command line, sizes refused up front); and what every workflow script does around its
work (rockdec.pipeline.job). The end-to-end checks on a built copy are in test_workflow.py.

Apart from test_workflow.py so that another worker runs these while that one builds.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from conftest import snakemake
from rockdec.pipeline import config, job
from rockdec.validate import InputError
from test_workflow import REPO, job_stats


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
    """Edit ``path`` (a comment line more) and make it newer than every product: a rule's code
    input is the fingerprint of what its modules hold (rockdec.sources.fingerprint_file)."""
    path.write_text(path.read_text() + "\n# edited\n")
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
    fingerprint = (studies / ".snakemake" / "rockdec-code" / "tradeoff.sha256").read_text()
    assert f" {studies / 'rockdec' / 'studies' / 'tradeoff.py'}\n" in fingerprint
    assert str(REPO / "src") not in fingerprint + out


def test_a_module_touched_without_a_change_reruns_nothing(studies):
    os.utime(studies / "rockdec" / "studies" / "tradeoff.py", (BUILT + 30, BUILT + 30))
    assert dry_run(studies, "tradeoff_study") == {}


def test_no_line_of_a_dry_run_lists_the_package_sources(studies):
    code, out = snakemake(studies, "-n", "--forcerun", "tradeoff", "amplitude", "--", "tradeoff_study", "amplitude_study")
    assert code == 0, out
    inputs = [line for line in out.splitlines() if line.strip().startswith("input:")]
    assert len(inputs) == 6, out  # two studies, their figures and their targets
    for line in inputs:  # a study's fingerprint, the drawing code's one module, or none (the targets)
        assert line.count(".sha256") + line.count(str(studies / "rockdec")) <= 1, line


@pytest.mark.parametrize("target", STUDIES)
def test_an_up_to_date_study_has_nothing_to_do(studies, target):
    assert dry_run(studies, target) == {}


@pytest.mark.parametrize("target", STUDIES)
def test_changing_the_study_module_reruns_the_study_and_its_figure(studies, target):
    compute_rule, module, plot_rule = STUDIES[target]
    touch(studies / "rockdec" / "studies" / module)
    assert dry_run(studies, target) == {compute_rule: 1, plot_rule: 1, target: 1}


def test_changing_a_module_the_study_imports_reruns_it(studies):
    touch(studies / "rockdec" / "report" / "tables.py")  # the replicate statistics of both studies
    assert dry_run(studies, "tradeoff_study") == {"tradeoff": 1, "fig_tradeoff": 1, "tradeoff_study": 1}


@pytest.mark.parametrize("target", STUDIES)
def test_changing_the_drawing_code_redraws_without_rerunning_the_study(studies, target):
    _, _, plot_rule = STUDIES[target]
    touch(studies / "rockdec" / "report" / "figures.py")
    assert dry_run(studies, target) == {plot_rule: 1, target: 1}


def test_the_compute_rule_alone_is_a_target(studies):
    touch(studies / "rockdec" / "studies" / "tradeoff.py")
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


@pytest.mark.hostile("configs", "refused")
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


@pytest.mark.hostile("sizes", "refused")
@pytest.mark.parametrize("records, words", SIZES.values(), ids=SIZES.keys())
def test_a_scene_too_large_is_refused_at_validation_with_the_estimate(records, words):
    scene = {"records": {"replicates": 4, "series_per_replicate": 40, **records}}
    with pytest.raises(config.ConfigError, match="scenes.tiny.records") as refused:
        config.validate_scene(scene, "tiny", sizes=True)
    assert words in str(refused.value) and str(refused.value).count(". ") == 1  # one sentence, then the fix


@pytest.mark.hostile("sizes", "refused")
def test_a_dry_run_refuses_a_scene_too_large_in_one_sentence(bare):
    records, words = SIZES["1e6 x 1e6 series"]  # a 7 TiB seed table if anything built it
    code, out = snakemake(bare, "-n", "--config", "scenes={tiny: {records: {replicates: 1000000, series_per_replicate: 1000000}}}")
    assert code == 2, out
    line = out.strip().splitlines()[-1]
    assert line.startswith("rockdec: error: config field 'scenes.tiny.records'") and words in line, out
    assert "Traceback" not in out


def test_every_scene_of_the_config_passes_the_size_checks():
    assert {"paper", "large", "tiny"} <= set(config.load(REPO / "config" / "config.yaml")["scenes"])


# --- around every script (rockdec.pipeline.job): errors on the console, orphans of a killed Snakemake


class FakeJob:
    """What rockdec.pipeline.job reads of Snakemake's ``snakemake`` object."""

    def __init__(self, folder: Path):
        self.rule, self.log, self.output = "signatures", [str(folder / "rule.log")], [str(folder / "out.nc")]


@pytest.mark.hostile("configs", "refused")
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
from rockdec.pipeline import job
if sys.argv[1] == "parent":  # plays Snakemake: starts the job, then waits
    subprocess.Popen([sys.executable, __file__, "job", sys.argv[2]])
    time.sleep(120)
else:  # the job: records itself as rockdec.pipeline.job does, then works on
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


@pytest.mark.hostile("kills", "answered")
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


@pytest.mark.hostile("kills", "refused")
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


def test_every_rule_file_is_included_by_the_snakefile():
    """A rule file that no ``include:`` names is dead: its rules cannot be run by name."""
    repo = Path(__file__).resolve().parents[2]
    included = set()
    for source in [repo / "Snakefile", *(repo / "workflow" / "rules").glob("*.smk")]:
        included |= {Path(m).name for m in re.findall(r'^include:\s*"([^"]+)"', source.read_text(), flags=re.M)}
    rule_files = {p.name for p in (repo / "workflow" / "rules").glob("*.smk")}
    assert rule_files - included == set()

"""The Snakemake workflow as a whole: what reruns after which change, by dry runs only.

Organised by topic, one section each; the dry runs use the helpers of the workflow tests of
:mod:`test_figures` (``snakemake``, ``job_stats``).
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

from test_figures import REPO, job_stats, snakemake

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

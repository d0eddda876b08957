"""The Snakemake workflow as a whole: what reruns after which change, by dry runs only.

Organised by topic, one section each; the end-to-end section builds a shrunken ``tiny`` scene
once and checks its products, its job list and what reruns after a script or a setting
changes; the others use dry runs only.
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
from pathlib import Path

import matplotlib.image
import pytest
import xarray as xr
import yaml

from cf_check import cf_findings
from conftest import snakemake
from rockdec import figures, run

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
        assert cf_findings(path, tmp_path) == {"errors": [], "warnings": []}, path.name
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


@pytest.mark.slow
def test_touching_a_plotting_script_reruns_only_that_figure(workflow):
    root = workflow["root"]
    code, out = snakemake(root, "-n")
    assert code == 0 and job_stats(out) == {}, out
    script = root / "workflow" / "scripts" / "fig_3.py"
    script.touch()  # now: newer than the figures, built before the dry run above
    code, out = snakemake(root, "-n")
    assert code == 0 and job_stats(out) == {"fig3": 1, "all": 1}, out
    code, out = snakemake(root, "--touch", "-q")  # mark it done again for the next tests
    assert code == 0, out


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

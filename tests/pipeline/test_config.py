"""Scenes: the schema's checks and defaults, and errors that name the field, the file and the fix."""

import subprocess
import sys

import pytest

from rockdec.pipeline import config, layout
from rockdec.rdd import fits

from conftest import FORKS
from test_hostile import ROOT, config_file, refused


def test_defaults_are_filled_in_and_the_fit_points_come_from_the_estimators():
    scene = config.validate_scene({})
    assert scene["estimates"]["fit_points"] == fits.DEFAULT_FIT_POINTS
    assert scene["records"]["replicates_per_job"] is None and layout.signature_parts(scene["records"]) == []
    assert scene["system"]["e"] == 0.95 and scene["model"] == "auto"


def test_store_series_is_a_count_or_all(tmp_path):
    with pytest.raises(config.ConfigError, match="store_series"):
        config.validate_scene({"records": {"store_series": "most"}})
    rec = config.validate_scene({"records": {"replicates": 3, "store_series": 5}})["records"]
    assert layout.replicate_files(tmp_path, rec) == []
    assert layout.simulation_seeds(rec).tolist() == [0, 1, 2, 3, 4]
    rec["store_series"] = "all"
    assert [p.name for p in layout.replicate_files(tmp_path, rec)] == ["replicate_0.nc", "replicate_1.nc", "replicate_2.nc"]
    assert layout.simulation_seeds(rec).size == layout.FIGURE_SERIES


def test_replicates_per_job_splits_the_scene_into_whole_replicates():
    with pytest.raises(config.ConfigError, match="replicates_per_job"):
        config.validate_scene({"records": {"replicates_per_job": 0}})
    rec = config.validate_scene({"records": {"replicates": 7, "series_per_replicate": 3, "first_seed": 5, "replicates_per_job": 3}, "estimates": {"compare_readings": False}})["records"]
    parts = [layout.part_records(rec, p) for p in layout.signature_parts(rec)]
    seeds = [layout.scene_seeds(p).ravel() for p, _ in parts]
    assert [first for _, first in parts] == [0, 3, 6]
    assert list(map(int, sum(map(list, seeds), []))) == list(range(5, 5 + 21))  # every seed once, in order


CONFIG_CASES = {
    "e .nan": ("system: {e: .nan}", ["scenes.s.system.e", "not a finite number"]),
    "nu .inf": ("system: {nu: .inf}", ["scenes.s.system.nu", "not a finite number"]),
    "n_points decimal": ("records: {n_points: 6000.0}", ["scenes.s.records.n_points", "write 6000"]),
    "burn_in decimal": ("excitation: {burn_in: 10.0}", ["scenes.s.excitation.burn_in", "write 10"]),
    "windows with nan": ("signatures: {windows: [0.5, .nan]}", ["scenes.s.signatures.windows.1", "finite"]),
    "groups_of_10 with 5 series": (
        "records: {series_per_replicate: 5}\n    estimates: {reading: groups_of_10}",
        ["scenes.s.estimates.reading", "at least 10 series", "series_per_replicate' is 5"],
    ),
    "compare_readings with 5 series": (
        "records: {series_per_replicate: 5}",
        ["scenes.s.estimates.compare_readings", "compare_readings: false"],
    ),
    "reading unknown": ("estimates: {reading: all}", ["scenes.s.estimates.reading", "use one of pooled"]),
}


@pytest.mark.hostile("configs", "refused")
@pytest.mark.parametrize("body, keywords", CONFIG_CASES.values(), ids=CONFIG_CASES.keys())
def test_config_refused_naming_the_file_passed(tmp_path, capsys, body, keywords):
    path = config_file(tmp_path, f"default_scene: s\nscenes:\n  s:\n    {body}\n")
    argv = ["simulate", "--config", str(path), "--scene", "s", "--out", str(tmp_path / "o.nc")]
    refused(argv, tmp_path, capsys, [*keywords, str(path)])


@pytest.mark.hostile("configs", "refused")
@pytest.mark.parametrize(
    "text, keywords",
    [
        ("default_scene: ../evil\nscenes:\n  ../evil: {}\n", ["'../evil'", "not a plain name"]),
        ("default_scene: a\nscenes:\n  a/b: {}\n  a: {}\n", ["'a/b'", "not a plain name"]),
        ("scenes: [1, 2\n", ["not valid YAML"]),
        ("- just\n- a list\n", ["not a mapping"]),
        ("default_scene: nope\nscenes:\n  s: {}\n", ["default_scene", "'nope' is not a scene"]),
    ],
    ids=["scene name ../", "scene name with /", "YAML syntax", "not a mapping", "default scene missing"],
)
def test_config_file_refused(tmp_path, capsys, text, keywords):
    path = config_file(tmp_path, text)
    argv = ["simulate", "--config", str(path), "--scene", "s", "--out", str(tmp_path / "o.nc")]
    refused(argv, tmp_path, capsys, [*keywords, str(path)])


def test_workflow_names_the_configfile_passed(tmp_path):
    path = config_file(tmp_path, "default_scene: s\nscenes:\n  s:\n    system: {e: .nan}\n")
    code, _, err = FORKS.run(ROOT, ["-n", "--cores", "1", "--configfile", str(path)], timeout=120)  # python -m snakemake
    assert code == 2
    assert f"Fix it in {path}" in err and "scenes.s.system.e" in err
    assert "Traceback" not in err




def test_the_configuration_and_the_snakefiles_names_load_neither_numba_nor_xarray():
    """What the Snakefile's start imports (``rockdec.pipeline.config``, ``rockdec.pipeline.layout``) stays light,
    so a Snakemake run that has nothing to do starts fast."""
    probe = "import sys, rockdec.pipeline.config, rockdec.pipeline.layout; print(sorted({'numba', 'xarray', 'dask', 'scipy'} & set(sys.modules)))"
    proc = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120, check=True)
    assert proc.stdout.strip() == "[]"

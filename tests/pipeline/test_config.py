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


# --------------------------------------------------------------------------- issue 38: YAML 1.2, --config lists, sources

import re  # noqa: E402
import time  # noqa: E402

from rockdec import validate as checks  # noqa: E402


def _with_overrides(entries: list[str], tmp_path=None) -> dict:
    """The shipped config with ``snakemake --config ENTRIES`` applied as the workflow does:
    Snakemake's own parser and merge, then :func:`config.apply_overrides` and :func:`config.validate`."""
    from snakemake.cli import parse_config
    from snakemake.utils import update_config

    cfg = config.read_yaml((ROOT / "config/config.yaml").read_text(), "config/config.yaml")
    overrides = parse_config(entries)
    update_config(cfg, overrides)
    return config.validate(config.apply_overrides(cfg, overrides), "config/config.yaml", overrides, sizes=False)


@pytest.mark.hostile("configs", "answered")
@pytest.mark.parametrize(
    "entry, path, expected",
    [
        ("scenes={tiny: {records: {n_points: 06000}}}", ("records", "n_points"), 6000),
        ("scenes={tiny: {records: {n_points: 0o20}}}", ("records", "n_points"), 16),
        ("scenes={tiny: {signatures: {windows: [0.25, 0.5, 0.75, 1.0]}}}", ("signatures", "windows"), [0.25, 0.5, 0.75, 1.0]),
        ("scenes={tiny: {signatures: {windows: [0.1, 1]}}}", ("signatures", "windows"), [0.1, 1]),
        ("scenes={tiny: {system: {e: 9.5e-1}}}", ("system", "e"), 0.95),
        ("scenes={tiny: {signatures: {both_signs: false}}}", ("signatures", "both_signs"), False),
    ],
    ids=["octal-looking 06000 is 6000", "0o20 is octal", "windows list (the default)", "windows list", "exponent", "boolean"],
)
def test_snakemake_config_values_are_read_as_yaml_12(entry, path, expected):
    scene = _with_overrides([entry])["scenes"]["tiny"]
    value = scene[path[0]][path[1]]
    assert value == expected and type(value) is type(expected)


OVERRIDE_REFUSALS = {
    "misspelt key": ("scenes={tiny: {records: {n_pionts: 6000}}}", "scenes.tiny.records.n_pionts", ["not a setting", "n_points"]),
    "misspelt top-level key": ("scene=tiny", "scene", ["not a setting", "default_scene"]),
    "first_seed 2^64 - 1": ("scenes={tiny: {records: {first_seed: 18446744073709551615}}}", "scenes.tiny.records.first_seed", ["64-bit"]),
    "sigma_p 1e-300": ("scenes={tiny: {excitation: {sigma_p: 1e-300}}}", "scenes.tiny.excitation.sigma_p", ["1e-300", "outside"]),
    "nu 1e154": ("scenes={tiny: {system: {nu: 1e154}}}", "scenes.tiny.system.nu", ["1e+154", "g = nu^2 theta_cr"]),
    "theta_cr 1e-320": ("scenes={tiny: {system: {theta_cr: 1e-320}}}", "scenes.tiny.system.theta_cr", ["g = nu^2 theta_cr"]),
    "level 1e-300": ("scenes={tiny: {signatures: {level: 1e-300}}}", "scenes.tiny.signatures.level", ["1e-300", "raise the level"]),
    "n_points 1e150": ("scenes={tiny: {records: {n_points: 1e150}}}", "scenes.tiny.records.n_points", ["1e+150", "whole number"]),
    "n_points of 70 digits": ("scenes={tiny: {records: {replicates: " + "9" * 70 + "}}}", "scenes.tiny.records", []),
    "windows with text": ("scenes={tiny: {signatures: {windows: [0.25, abc]}}}", "scenes.tiny.signatures.windows.1", ["'abc'"]),
    "dt 1e-200 given": ("scenes={tiny: {excitation: {dt: 1e-200}}}", "scenes.tiny.excitation.dt", ["outside"]),
}


@pytest.mark.hostile("configs", "refused")
@pytest.mark.parametrize("entry, field, words", OVERRIDE_REFUSALS.values(), ids=OVERRIDE_REFUSALS.keys())
def test_snakemake_config_errors_name_the_field_and_the_option_and_show_short_numbers(entry, field, words):
    with pytest.raises(config.ConfigError) as info:
        if field == "scenes.tiny.records":  # a size: checked with the sizes
            from snakemake.cli import parse_config
            from snakemake.utils import update_config

            cfg = config.read_yaml((ROOT / "config/config.yaml").read_text(), "config/config.yaml")
            overrides = parse_config([entry])
            update_config(cfg, overrides)
            config.validate(config.apply_overrides(cfg, overrides), "config/config.yaml", overrides)
        else:
            _with_overrides([entry])
    message = str(info.value)
    assert f"config field '{field}" in message and config.OVERRIDE_SOURCE in message, message
    assert "config/config.yaml" not in message.split("Fix it in")[-1], message
    assert not re.search(r"\d{21}", message), message  # no number written out in more than 20 digits
    for word in words:
        assert word in message, (word, message)
    assert message.count(". ") <= 2 and "\n" not in message  # the problem, then where to fix it


@pytest.mark.hostile("configs", "refused")
@pytest.mark.parametrize(
    "body, field",
    [
        ("records: {n_pionts: 6000}", "scenes.s.records.n_pionts"),
        ("system: {nu: 1e154}", "scenes.s.system.nu"),
        ("excitation: {sigma_p: 1e-300}", "scenes.s.excitation.sigma_p"),
        ("signatures: {level: 1e-300}", "scenes.s.signatures.level"),
        ("records: {first_seed: 18446744073709551615}", "scenes.s.records.first_seed"),
    ],
    ids=["misspelt key", "nu 1e154", "sigma_p 1e-300", "level 1e-300", "first_seed 2^64 - 1"],
)
def test_config_file_errors_name_the_file_not_the_option(tmp_path, capsys, body, field):
    path = config_file(tmp_path, f"default_scene: s\nscenes:\n  s:\n    {body}\n")
    argv = ["simulate", "--config", str(path), "--scene", "s", "--out", str(tmp_path / "o.nc")]
    err = refused(argv, tmp_path, capsys, [field, str(path)])
    assert config.OVERRIDE_SOURCE not in err


def _alias_bomb(levels: int = 9) -> str:
    lines = ["a: &a [1, 1, 1, 1, 1, 1, 1, 1, 1, 1]"]
    for i in range(1, levels + 1):
        prev, name = chr(96 + i), chr(97 + i)
        lines.append(f"{name}: &{name} [" + ", ".join([f"*{prev}"] * 10) + "]")
    return "\n".join(lines) + "\n"


@pytest.mark.hostile("limits", "refused")
def test_a_yaml_alias_bomb_is_refused_at_once(tmp_path, capsys):
    path = config_file(tmp_path, "default_scene: s\nscenes:\n  s: {}\nbomb:\n" + "".join("  " + line + "\n" for line in _alias_bomb().splitlines()))
    start = time.perf_counter()
    refused(["simulate", "--config", str(path), "--scene", "s", "--out", str(tmp_path / "o.nc")], tmp_path, capsys,
            [str(path), "aliases", "100,000"])
    with pytest.raises(config.ConfigError, match="aliases"):
        config.apply_overrides({}, config.read_yaml(_alias_bomb(), "x") | {"scenes": {}})
    assert time.perf_counter() - start < 5


@pytest.mark.hostile("configs", "refused")
@pytest.mark.parametrize(
    "value, words",
    [("06000", ["3072", "6000"]), ("yes", ["true", "'yes'"]), ("1e5", ["'1e5'", "100000.0"]), ("1:30", ["90", "'1:30'"]),
     ("off", ["false", "'off'"]), ("0b101", ["5", "'0b101'"]), ("1_000", ["1000", "'1_000'"]), ("2001-12-14", ["'2001-12-14'"]),
     ("-017", ["-15", "-17"])],
    ids=["octal", "yes", "exponent without a point", "sexagesimal", "off", "binary", "underscore", "date", "negative octal"],
)
def test_a_file_snakemake_reads_is_refused_where_yaml_11_and_12_differ(tmp_path, value, words):
    path = config_file(tmp_path, f"scenes:\n  s:\n    records: {{n_points: {value}}}\n")
    with pytest.raises(config.ConfigError) as info:
        config.check_yaml11(path)
    assert f"config file {path}, line 3: {value}" in str(info.value)
    for word in words:
        assert word in str(info.value)
    config.check_yaml11(ROOT / "config/config.yaml")  # the shipped config reads the same in both
    assert config.load(config_file(tmp_path, "default_scene: s\nscenes:\n  s: {records: {n_points: 06000}}\n"))[
        "scenes"]["s"]["records"]["n_points"] == 6000  # rockdec's own reading: YAML 1.2


def test_show_writes_long_whole_numbers_short():
    assert checks.show(10**150) == "1e+150" and checks.show(-(10**5000)) == "-1e+5000"
    assert checks.show(2**64 - 1) == "18446744073709551615" and checks.show(123456789012345678901) == "1.23e+20"
    assert float(checks.show(3**200)) == pytest.approx(3.0**200, rel=5e-3)


@pytest.mark.hostile("configs", "refused")
def test_workflow_refuses_an_octal_looking_value_and_names_the_option(tmp_path):
    path = config_file(tmp_path, "default_scene: s\nscenes:\n  s:\n    records: {n_points: 06000}\n")
    code, _, err = FORKS.run(ROOT, ["-n", "--cores", "1", "--configfile", str(path)], timeout=120)
    assert code == 2 and "06000 reads as 3072 in YAML 1.1" in err and "Traceback" not in err, err
    code, _, err = FORKS.run(ROOT, ["-n", "--cores", "1", "--config", "scenes={tiny: {records: {n_pionts: 3}}}"], timeout=120)
    assert code == 2 and "scenes.tiny.records.n_pionts" in err and config.OVERRIDE_SOURCE in err, err


@pytest.mark.hostile("numbers", "refused")
@pytest.mark.parametrize("field, value", [("nu", 5e-324), ("nu", 1e-160), ("theta_cr", 5e-324), ("nu", 1.7976931348623157e308),
                                          ("theta_cr", 1e300)])
def test_a_g_that_under_or_overflows_blames_its_factor(field, value):
    with pytest.raises(config.ConfigError) as info:
        config.validate_scene({"system": {field: value}})
    assert info.value.field == f"scenes.cli.system.{field}" and "g = nu^2 theta_cr" in str(info.value)


from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from test_hostile import ANY_FLOAT  # noqa: E402

NUMERIC_FIELDS = [("system", "e"), ("system", "nu"), ("system", "theta_cr"), ("excitation", "sigma_p"),
                  ("excitation", "points_per_cycle"), ("excitation", "dt"), ("signatures", "level"), ("signatures", "n_periods"),
                  ("signatures", "window_max"), ("signatures", "v_level"), ("records", "n_points"), ("records", "first_seed")]


@pytest.mark.hostile("numbers", "refused or answered")
@settings(max_examples=80, deadline=None)
@given(where=st.sampled_from(NUMERIC_FIELDS), value=st.one_of(ANY_FLOAT, st.integers(-(2**70), 2**70)))
def test_any_number_in_any_field_validates_or_is_one_sentence_naming_a_field(where, value):
    """No number in a scene's numeric fields raises anything but a ConfigError that names a
    field of the scene, in one sentence without a number of more than 20 digits."""
    section, key = where
    try:
        config.validate_scene({section: {key: value}}, sizes=True)
    except config.ConfigError as exc:
        text = str(exc)
        assert exc.field is None or exc.field.startswith("scenes.cli"), text
        assert "\n" not in text and not re.search(r"\d{21}", text), text

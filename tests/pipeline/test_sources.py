"""The code dependencies of a step (:mod:`rockdec.sources`) and the calibration's cache key."""

from __future__ import annotations

from pathlib import Path

from rockdec.calibrate import calibration
from rockdec.physics import models
from rockdec.sources import _statement, package_sources

SRC = Path(calibration.__file__).resolve().parents[1]


def names(paths):
    return {Path(p).name for p in paths}


def test_sources_follow_imports_through_other_modules():
    """calibration imports simulate, which imports models: models is listed; figures is not."""
    found = names(package_sources("rockdec.calibrate.calibration"))
    assert {"calibration.py", "measured.py", "simulate.py", "models.py", "registry.py", "estimators.py"} <= found
    assert "figures.py" not in found


def test_a_script_lists_the_modules_it_reaches_not_itself(tmp_path):
    script = tmp_path / "step.py"
    script.write_text("from rockdec.report import tables\n\ndef f():\n    from rockdec.rdd.registry import ESTIMATORS\n")
    found = names(package_sources(str(script)))
    assert {"tables.py", "belt.py", "registry.py"} <= found
    assert "step.py" not in found


def test_every_listed_source_is_a_package_file():
    for path in package_sources("rockdec.cli"):
        assert Path(path).resolve().is_relative_to(SRC)


def test_editing_models_changes_the_calibration_cache_key(monkeypatch):
    """models.py sets the lag range and the samples-per-cycle bins: an edit to it must make
    stored calibrations stale (in the next process: the fingerprint is read once per process,
    here its cache cleared)."""
    key = calibration.calibration_settings([20_000], 75.0)
    before = calibration.settings_hash(key)
    models_file = Path(models.__file__).resolve()
    read_bytes = Path.read_bytes
    monkeypatch.setattr(Path, "read_bytes", lambda self: read_bytes(self) + (b"\n# edited\n" if self.resolve() == models_file else b""))
    calibration.pipeline_fingerprint.cache_clear()
    try:
        after = calibration.settings_hash(calibration.calibration_settings([20_000], 75.0))
    finally:
        calibration.pipeline_fingerprint.cache_clear()
    assert after != before


def test_kernels_do_not_reach_the_record_reader():
    """The simulation, signature and estimator modules never import the user-file reader."""
    for module in ("rockdec.rdd.signatures", "rockdec.rdd.estimators", "rockdec.physics.simulate", "rockdec.pipeline.replicates"):
        assert "records.py" not in names(package_sources(module)), module


def test_continued_imports_are_read_whole_and_a_docstring_fragment_is_no_import(tmp_path):
    """Only import lines are parsed: a parenthesised or backslash-continued import is read to
    its end, and a docstring line that starts like an import but is no statement (an
    unclosed parenthesis) sends the file to a whole parse, which finds only real imports."""
    script = tmp_path / "step.py"
    script.write_text(
        'from rockdec.physics.models import (\n    period_from_g,\n    SCALE_CONSTANT_GUESS,\n)\n\n'
        "def f():\n    import rockdec.report.tables, \\\n        rockdec.rdd.registry\n"
    )
    assert names(package_sources(str(script))) >= {"models.py", "tables.py", "registry.py"}
    text = script.read_text()
    assert _statement(text, 0) == text[: text.index(")") + 1]  # to the closing parenthesis, without a whole parse
    start = text.index("    import")
    assert _statement(text, start) == text[start:].rstrip("\n")  # over the backslash
    assert "figures.py" not in names(package_sources(str(script)))
    fragment = tmp_path / "fragment.py"
    fragment.write_text('"""Usage:\n\nfrom rockdec.report import (figures\n"""\n\nfrom rockdec.physics import models\n')
    found = names(package_sources(str(fragment)))
    assert "models.py" in found and "figures.py" not in found

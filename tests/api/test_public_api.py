"""The front door: ``import rockdec`` and its public names, the result object and the
command line as a thin layer over them."""

from __future__ import annotations

import dataclasses
import doctest
import importlib
import json
import re
from pathlib import Path

import jsonschema
import numpy as np
import pandas as pd
import pytest
import xarray as xr

import rockdec
from rockdec import io
from cf_check import cf_findings
from conftest import capped_calibration_sets
from rockdec.cli import main
from rockdec.report import result as result_mod

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module", autouse=True)
def capped_module():
    """Every calibration of the module on the capped sets per ``e`` (nothing here rests on their number)."""
    with capped_calibration_sets():
        yield


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("calibrations")


@pytest.fixture(scope="module")
def record():
    """The README's record: known e = 0.85 from the simulator (200,000 samples)."""
    return rockdec.simulate(0.85, 200_000, seed=1)


@pytest.fixture(scope="module")
def res(record, cache):
    return rockdec.estimate(record, cache=cache)


def test_help_of_the_package_names_its_public_calls():
    text = rockdec.__doc__
    assert all(name in text for name in ("estimate", "read_record", "simulate", "RestitutionEstimate"))
    assert set(rockdec.__all__) <= set(dir(rockdec))
    for name in rockdec.__all__:
        assert getattr(rockdec, name) is not None


@pytest.mark.parametrize("name", [n for n in rockdec.__all__ if n not in ("__version__",)])
def test_every_public_name_has_a_numpydoc_docstring_with_an_example(name):
    obj = getattr(rockdec, name)
    doc = obj.__doc__ or ""
    if isinstance(obj, type) and issubclass(obj, Exception) or name in ("ConfidenceInterval", "EstimateWarning"):
        assert doc.strip(), f"{name} has no docstring"
        return
    assert "Examples\n" in doc and ">>>" in doc, f"{name} has no Examples section"
    if callable(obj) and not isinstance(obj, type):
        assert "Parameters\n" in doc and "Returns\n" in doc, f"{name} lacks Parameters or Returns"


@pytest.mark.parametrize("module", [pytest.param("rockdec.api", marks=pytest.mark.slow), "rockdec.report.result", "rockdec.cache"])
def test_docstring_examples_run(module, res, cache, tmp_path, monkeypatch):
    monkeypatch.setenv("ROCKDEC_CACHE", str(cache))
    mod = importlib.import_module(module)
    finder, runner = doctest.DocTestFinder(), doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
    tests = [t for t in finder.find(mod, globs={"rockdec": rockdec, "res": res, "tmp": tmp_path}) if t.examples]
    assert tests
    for test in tests:
        runner.run(test)
    assert runner.summarize(verbose=False).failed == 0


def test_the_readme_example_runs_and_agrees_with_the_command_line(tmp_path, cache, monkeypatch, capsys):
    """The README's Python example, run as written (its record saved for the command line),
    gives the same e, interval and estimator as `rockdec estimate --json` on that record."""
    text = (ROOT / "README.md").read_text()
    match = re.search(r"<!-- example-start -->\s*```python\n(.*?)```\s*<!-- example-end -->", text, re.S)
    assert match, "README.md has no Python example between <!-- example-start --> and <!-- example-end -->"
    code = match.group(1)
    assert len(code.strip().splitlines()) <= 10
    monkeypatch.setenv("ROCKDEC_CACHE", str(cache))
    monkeypatch.chdir(tmp_path)
    import matplotlib

    matplotlib.use("Agg")
    scope: dict = {}
    exec(compile(code, "README.md", "exec"), scope)
    res, theta = scope["res"], scope["theta"]
    theta.to_dataset(name="theta").to_netcdf(tmp_path / "record.nc")
    capsys.readouterr()
    assert main(["-q", "estimate", str(tmp_path / "record.nc"), "--json", "--cache", str(cache)]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert (doc["e"], doc["interval"], doc["estimator"]) == (res.e, list(res.confidence_interval), res.estimator)


def test_to_dict_round_trips_through_json_and_validates_against_the_schema(res):
    doc = json.loads(json.dumps(res.to_dict()))
    jsonschema.validate(doc, result_mod.schema())
    back = rockdec.RestitutionEstimate.from_dict(doc)
    assert back.to_dict() == res.to_dict()
    assert (back.e, back.confidence_interval, back.estimator, back.warnings) == (res.e, res.confidence_interval, res.estimator, res.warnings)


def test_the_command_line_json_is_the_result_document(record, cache, tmp_path, capsys, res):
    record.to_dataset(name="theta").to_netcdf(tmp_path / "r.nc")
    assert main(["-q", "estimate", str(tmp_path / "r.nc"), "--json", "--cache", str(cache)]) == 0
    doc = json.loads(capsys.readouterr().out)
    jsonschema.validate(doc, result_mod.schema())
    mine = res.to_dict()
    for volatile in ("records", "calibration"):
        doc.pop(volatile), mine.pop(volatile)
    assert doc == mine


def test_to_dataset_is_cf_compliant_and_carries_the_estimate(res, tmp_path):
    ds = res.to_dataset()
    assert float(ds["e"]) == res.e and float(ds["e_low"]) == res.confidence_interval.low
    assert ds["e"].attrs["ancillary_variables"] == "e_low e_high" and ds["e"].attrs["units"] == "1"
    assert list(ds["estimator"].values) == list(res.document["estimators"])
    path = io.write_netcdf(ds, tmp_path / "estimate.nc")
    assert cf_findings(path) == {"errors": [], "warnings": [], "notes": []}
    with xr.open_dataset(path) as back:
        assert rockdec.RestitutionEstimate.from_dict(json.loads(back.attrs["rockdec_estimate"])).to_dict() == res.to_dict()


def test_repr_summary_and_html_are_short_and_lead_with_e(res):
    assert "\n" not in repr(res) and f"e={res.e:.4f}" in repr(res)
    first = res.summary().splitlines()[0]
    assert first.startswith(f"e = {res.e:.4f}") and "95 % interval" in first
    assert "<table>" in res._repr_html_()
    assert len(res.summary(verbose=True)) > len(res.summary())


def test_plot_draws_the_reported_estimators_signature_and_needs_the_analysis(res):
    fig = res.plot()
    left = fig.axes[0]
    from rockdec.rdd import registry

    wanted = "zero-crossing" if registry.trigger(res.estimator) == "v" else "signature of the record"
    assert wanted in left.get_title()
    declined = dataclasses.replace(res, belts={})
    assert "declined" in declined.plot().axes[1].texts[0].get_text()
    with pytest.raises(rockdec.InputError, match="read back from its document"):
        rockdec.RestitutionEstimate.from_dict(res.to_dict()).plot()


def test_inputs_in_every_form_give_the_same_records(record):
    from rockdec.api import _records

    dt = record.attrs["dt"]
    values = record.values
    base = _records(values, dt)[0]
    series = pd.Series(values, index=pd.to_timedelta(np.arange(values.size) * dt, unit="s"))
    assert abs(_records(series, None)[0].dt - dt) < 1e-9 * dt
    degrees = record.copy(data=np.degrees(values)).assign_attrs(units="degree")
    np.testing.assert_allclose(_records(degrees, None)[0].theta, base.theta, rtol=1e-12)
    milli = record.copy(data=values * 1e3).assign_attrs(units="mrad")
    np.testing.assert_allclose(_records(milli, None)[0].theta, base.theta, rtol=1e-12)
    two = _records([values, values[::-1].copy()], dt)
    assert len(two) == 2 and two[1].dt == dt


@pytest.mark.parametrize("call, named", [
    (lambda r: rockdec.estimate(r.values), "`dt`"),
    (lambda r: rockdec.estimate(r, load="purple"), "`load`"),
    (lambda r: rockdec.estimate(r, sensor_noise="-1"), "`sensor_noise`"),
    (lambda r: rockdec.estimate(r, model="housner"), "`theta_cr`"),
    (lambda r: rockdec.estimate(r, g=-1.0), "`g`"),
    (lambda r: rockdec.estimate(r.assign_attrs(units="furlong")), "furlong"),
    (lambda r: rockdec.estimate([]), "`theta`"),
    (lambda r: rockdec.estimate(r.values[:1], dt=0.01), "samples"),
    (lambda r: rockdec.estimate(np.full(5000, np.nan), dt=0.01), "NaN"),
    (lambda r: rockdec.estimate(r, dt=2 * r.attrs["dt"]), "`dt`"),
])
def test_refusals_name_the_python_parameter(record, call, named):
    with pytest.raises(rockdec.InputError) as info:
        call(record)
    assert named in str(info.value) and "--" not in str(info.value)


def test_no_command_line_flags_in_the_library():
    """Library messages name Python parameters; only the command line (and the workflow's
    adapter, rockdec.pipeline, and a study's own command) speak in flags."""
    flag = re.compile(r"(?<![\w-])--(dt|fs|g|load|sensor-noise|model|theta-cr|cache|column|variable|out|overwrite|burn-in|"
                      r"theta0|points-per-cycle|plot|json|seeds|yes|e|nu|sigma-p|n-points)\b")
    package = Path(rockdec.__file__).parent
    found = [f"{p.relative_to(package)}:{i}" for p in package.rglob("*.py") if p.name != "cli.py" and "pipeline" not in p.parts
             and p.name != "belt_study.py" for i, line in enumerate(p.read_text().splitlines(), 1) if flag.search(line)]
    assert not found


def test_the_command_line_maps_parameters_to_flags(tmp_path, capsys):
    np.save(tmp_path / "r.npy", np.sin(np.arange(5000) * 0.1))
    assert main(["estimate", str(tmp_path / "r.npy")]) == 2
    err = capsys.readouterr().err
    assert "--dt" in err and "`" not in err


def test_a_record_given_again_in_disguise_is_refused(record, cache):
    """The record and a copy offset by 1e-4 rad (issue 38) would count its triggers twice."""
    with pytest.raises(rockdec.RecordError, match="same data"):
        rockdec.estimate([record, record + 1e-4], cache=cache)


def test_a_simulation_that_misses_its_request_says_so(monkeypatch, tmp_path, capsys):
    from rockdec.api import SimulationWarning
    from rockdec.physics import run

    monkeypatch.setattr(run, "simulation_report", lambda theta, contract, seeds=None, step_given=False: ["2 of 4 series overturned"])
    with pytest.warns(SimulationWarning, match="overturned"):
        rockdec.simulate(0.85, 2_000, seed=1)
    assert main(["simulate", "--out", str(tmp_path / "s.nc"), "--e", "0.85", "--seeds", "1", "--n-points", "2000"]) == 0
    assert "warning: 2 of 4 series overturned" in capsys.readouterr().err


def test_ctrl_c_ends_the_command_in_one_line(monkeypatch, capsys):
    import rockdec.cli as cli

    def interrupted(args):
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "cmd_verify", interrupted)
    assert cli.main(["verify", "x"]) == 130
    assert capsys.readouterr().err.strip() == "rockdec verify: interrupted."


def test_the_workflow_refuses_a_results_file_in_one_sentence(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "results").write_text("not a folder")
    assert main(["workflow", "--scene", "tiny", "-n"]) == 2
    err = capsys.readouterr().err
    assert "./results is a file" in err and err.count("\n") == 1


@pytest.fixture(scope="module")
def free_test():
    """A free-rocking record of known e = 0.85 with 1 % sensor noise (of the release angle)."""
    theta = rockdec.simulate(0.85, 2_500, seed=0, sigma_p=0.0, theta0=0.02)
    rng = np.random.default_rng(1)
    return theta + 0.01 * 0.02 * rng.standard_normal(theta.size)


def test_the_free_rocking_test_is_the_same_result_object(free_test, tmp_path):
    res = rockdec.free_rocking(free_test)
    assert res.test == "free" and res.confidence_interval.low < 0.85 < res.confidence_interval.high
    doc = json.loads(json.dumps(res.to_dict()))
    jsonschema.validate(doc, result_mod.schema())
    assert rockdec.RestitutionEstimate.from_dict(doc).to_dict() == res.to_dict()
    assert len(res.impacts) == len(doc["impacts"]) > 3 and res.summary().startswith(f"e = {res.e:.4f}")
    path = io.write_netcdf(res.to_dataset(), tmp_path / "free.nc")
    assert cf_findings(path) == {"errors": [], "warnings": [], "notes": []}
    assert len(res.plot().axes) == 2


def test_the_command_line_runs_the_free_rocking_test(free_test, tmp_path, capsys):
    free_test.to_dataset(name="theta").to_netcdf(tmp_path / "free.nc")
    assert main(["-q", "estimate", str(tmp_path / "free.nc"), "--test", "free", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["test"] == "free" and doc["e"] == rockdec.free_rocking(free_test).e
    assert main(["estimate", str(tmp_path / "free.nc"), "--test", "free", "--load", "white"]) == 2
    assert "--load" in capsys.readouterr().err


def test_a_record_run_backwards_in_time_is_declined(record, cache):
    """Issue 38: a time-reversed record has impacts that gain speed (e_v raw about 1/e); no
    block that loses energy at impacts gives that, so no e is given, with the reason."""
    backwards = record.copy(data=record.values[::-1].copy())
    res = rockdec.estimate(backwards, cache=cache)
    assert res.e is None and "gain speed" in res.reason
    assert res.document["estimators"]["e_v"]["raw"] > 1.05

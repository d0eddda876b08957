"""The command line: clear one-sentence errors with exit code 2, no partial files."""

import io as io_module
import json
import logging
import subprocess
import sys
import time

import numpy as np
import pytest
import xarray as xr

from rockdec.cli import main

import fake_calibration


def run(args, capsys):
    code = main(args)
    return code, capsys.readouterr().err


@pytest.mark.hostile("numbers", "refused")
@pytest.mark.parametrize(
    "args, names",
    [
        (["--e", "1.5"], "--e 1.5"),
        (["--e", "-0.1"], "--e -0.1"),
        (["--n-points", "-5"], "--n-points -5"),
        (["--burn-in", "-1"], "--burn-in -1"),
        (["--seeds", "3-1"], "--seeds '3-1'"),
        (["--scene", "nope", "--config", "config/config.yaml"], "unknown scene 'nope'"),
        (["--config", "no/such.yaml", "--scene", "paper"], "cannot read the config file"),
    ],
)
def test_bad_simulate_input_names_the_field_and_exits_2(tmp_path, capsys, args, names):
    out = tmp_path / "out.nc"
    code, err = run(["simulate", "--out", str(out), *args], capsys)
    assert code == 2
    assert names in err
    assert "Traceback" not in err
    assert not out.exists() and not list(tmp_path.iterdir())


@pytest.mark.hostile("output paths", "refused")
def test_unwritable_or_existing_output_is_refused(tmp_path, capsys):
    code, err = run(["simulate", "--out", str(tmp_path / "missing" / "x.nc")], capsys)
    assert code == 2 and "does not exist" in err
    existing = tmp_path / "x.nc"
    existing.write_text("keep me")
    code, err = run(["simulate", "--out", str(existing)], capsys)
    assert code == 2 and "--overwrite" in err
    assert existing.read_text() == "keep me"


@pytest.mark.hostile("numbers", "refused")
def test_e_one_needs_an_explicit_step(tmp_path, capsys):
    code, err = run(["simulate", "--out", str(tmp_path / "x.nc"), "--e", "1"], capsys)
    assert code == 2 and "--dt" in err


def test_free_response_run_writes_the_analytic_start(tmp_path, capsys):
    out = tmp_path / "free.nc"
    code, _ = run(
        ["simulate", "--out", str(out), "--sigma-p", "0", "--theta0", "1", "--burn-in", "0",
         "--seeds", "0", "--n-points", "100", "--e", "0.9", "--nu", "1", "--theta-cr", "1"],
        capsys,
    )
    assert code == 0
    with xr.open_dataset(out, decode_times=False) as ds:  # time in s from the end of the burn-in
        assert ds.theta.dtype == "float32"
        assert ds.theta.attrs["units"] == "rad"
        dt = ds.attrs["dt"]
        t = ds.time.values
        # before the first impact (t1 = sqrt(2), g = 1) the parabola 1 - t^2/2
        before = t < 2**0.5
        assert abs(ds.theta.values[0, before] - (1 - t[before] ** 2 / 2)).max() < 1e-6
        assert dt == pytest.approx(4 * 2**0.5 / 75)  # eq. 5 at amplitude 1, 75 points per cycle


@pytest.mark.hostile("numbers", "refused")
def test_console_script_exit_code_is_2_without_traceback(tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "rockdec.cli", "simulate", "--out", str(tmp_path / "x.nc"), "--e", "2"],
        capture_output=True, text=True,
    )
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr and "--e 2" in proc.stderr


def test_simulate_signatures_estimates_chain_gives_e_with_an_error_bar(tmp_path, capsys):
    sim, sig, est = (tmp_path / n for n in ("sim.nc", "sig.nc", "est.nc"))
    assert main(["simulate", "--out", str(sim), "--seeds", "0-59", "--scene", "tiny"]) == 0
    assert main(["signatures", str(sim), "--out", str(sig)]) == 0
    capsys.readouterr()
    assert main(["estimates", str(sig), "--out", str(est)]) == 0
    printed = capsys.readouterr().out
    assert "e_v:" in printed and "+-" in printed
    with xr.open_dataset(est) as ds:
        e_v = float(ds.e_hat0.sel(estimator="e_v", replicate=0))
        assert abs(e_v - 0.95) < 0.02  # 60 series: the D_v estimate scatters ~0.005


@pytest.mark.hostile("record files", "refused")
def test_signatures_refuses_a_file_without_the_record(tmp_path, capsys):
    bad = tmp_path / "bad.nc"
    xr.Dataset({"x": ("time", [0.0, 1.0])}).to_netcdf(bad)
    code, err = run(["signatures", str(bad), "--out", str(tmp_path / "o.nc")], capsys)
    assert code == 2 and "--variable" in err
    code, err = run(["estimates", str(bad), "--out", str(tmp_path / "o.nc")], capsys)
    assert code == 2 and "not a signature file" in err
    code, err = run(["signatures", str(tmp_path / "none.nc"), "--out", str(tmp_path / "o.nc")], capsys)
    assert code == 2 and "does not exist" in err


@pytest.mark.parametrize("model", ["simplified", "housner"])
def test_model_option_chooses_the_model_the_file_records(tmp_path, model):
    out = tmp_path / "sim.nc"
    args = ["simulate", "--out", str(out), "--seeds", "0-1", "--n-points", "100", "--dt", "0.01", "--burn-in", "0"]
    assert main([*args, "--scene", "tiny", "--model", model]) == 0  # the option overrides the scene's auto
    with xr.open_dataset(out) as ds:
        assert ds.attrs["model"] == model and ds.attrs["model_reason"] == "requested"


@pytest.mark.hostile("numbers", "refused")
def test_unknown_model_names_the_option_and_writes_nothing(tmp_path, capsys):
    code, err = run(["simulate", "--out", str(tmp_path / "x.nc"), "--model", "rigid"], capsys)
    assert code == 2 and "--model 'rigid'" in err and "housner" in err
    assert not list(tmp_path.iterdir())


def test_group_size_one_keeps_the_seeds_and_estimates_accepts_the_cube(tmp_path, capsys):
    sim, per_seed, pooled, est = (tmp_path / n for n in ("sim.nc", "per_seed.nc", "pooled.nc", "est.nc"))
    assert main(["simulate", "--out", str(sim), "--seeds", "3,5,8", "--scene", "tiny"]) == 0
    assert main(["signatures", str(sim), "--out", str(per_seed), "--group-size", "1"]) == 0
    assert main(["signatures", str(sim), "--out", str(pooled), "--group-size", "3"]) == 0
    with xr.open_dataset(per_seed) as cube, xr.open_dataset(pooled) as whole:
        assert cube["signature"].dims == ("seed", "trigger", "window", "lag")
        assert "group" not in cube.dims and cube["seed"].values.tolist() == [3, 5, 8]
        # the per-seed sums pool exactly into the 3-series signature (eq. 8)
        assert (cube["count"].sum("seed") == whole["count"].isel(group=0)).all()
        assert abs(cube["signature_sum"].sum("seed") - whole["signature_sum"].isel(group=0)).max() < 1e-12
    capsys.readouterr()
    assert main(["estimates", str(per_seed), "--out", str(est)]) == 0
    assert "e_v:" in capsys.readouterr().out
    with xr.open_dataset(est) as ds:
        assert ds["e_hat"].sizes["replicate"] == 1 and ds["e_hat"].sizes["estimator"] == 7
        assert np.isfinite(ds["e_hat0"].sel(estimator="e_v")).all()


# --------------------------------------------------------------------------- help, start-up, output

COMMANDS = ["estimate", "simulate", "signatures", "estimates", "verify", "workflow"]


def rockdec(*args, **kwargs):
    """``python -m rockdec args`` in a fresh interpreter."""
    return subprocess.run([sys.executable, "-m", "rockdec", *args], capture_output=True, text=True, **kwargs)


@pytest.mark.parametrize("args", [["--help"], ["-h"], *([name, "--help"] for name in COMMANDS)])
def test_every_help_exits_0_with_a_description_and_an_example(args, capsys):
    assert main(args) == 0
    out = capsys.readouterr().out
    assert out.startswith("usage: rockdec")
    assert "example" in out  # "examples:" atop, "example:" in each command


def test_the_command_list_names_every_command_with_its_summary(capsys):
    main(["--help"])
    out = capsys.readouterr().out
    assert all(f"    {name} " in out for name in COMMANDS)
    assert "95 % interval" in out  # the summary's percent sign, printed as written


def test_no_arguments_print_the_whole_help_and_exit_2(capsys):
    assert main([]) == 2
    out = capsys.readouterr().out
    assert out.startswith("usage: rockdec") and all(name in out for name in COMMANDS)


def test_estimate_help_explains_every_word_of_its_report(capsys):
    from rockdec.rdd import estimators

    main(["estimate", "--help"])
    out = " ".join(capsys.readouterr().out.split())
    for word in (*estimators.ESTIMATORS, "D_a", "D_v", "raw", "corrected", "95 % interval", "coverage", "triggers",
                 "below / above the calibrated range", "sigma_Y"):
        assert f" {word} " in out, word


def test_fit_points_default_shown_in_help_is_the_estimators_default(capsys):
    from rockdec.rdd import estimators

    main(["estimates", "--help"])
    assert f"(default {estimators.DEFAULT_FIT_POINTS})" in " ".join(capsys.readouterr().out.split())


@pytest.mark.parametrize("args", [["--version"], ["--help"], ["estimate", "--help"], ["simulate", "--bogus"]])
def test_version_help_and_a_refused_option_load_no_numerical_module(args):
    proc = subprocess.run(
        [sys.executable, "-X", "importtime", "-m", "rockdec", *args], capture_output=True, text=True
    )
    assert proc.returncode == (2 if "--bogus" in args else 0), proc.stderr[-500:]
    imported = {line.split("|")[-1].strip().split(".")[0] for line in proc.stderr.splitlines() if line.startswith("import time:")}
    assert "rockdec" in imported
    assert not imported & {"numpy", "numba", "xarray", "scipy", "dask", "pandas", "matplotlib"}


def test_python_dash_m_rockdec_is_the_rockdec_command():
    from rockdec import __version__

    proc = rockdec("--version")
    assert proc.returncode == 0 and proc.stdout.strip() == f"rockdec {__version__}"
    proc = rockdec("simulate", "--out", "x.nc", "--bogus")
    assert proc.returncode == 2 and "unrecognized arguments: --bogus" in proc.stderr and "Traceback" not in proc.stderr


def test_quiet_hides_the_progress_messages_and_verbose_keeps_them(tmp_path, capsys):
    args = ["simulate", "--seeds", "0", "--n-points", "100", "--dt", "0.01", "--burn-in", "0", "--scene", "tiny"]
    assert main([*args, "--out", str(tmp_path / "a.nc")]) == 0
    assert "rockdec: simulating 1 series" in capsys.readouterr().err
    assert main(["-q", *args, "--out", str(tmp_path / "b.nc")]) == 0
    assert capsys.readouterr().err == ""
    assert main(["-v", *args, "--out", str(tmp_path / "c.nc")]) == 0
    assert "rockdec: simulating" in capsys.readouterr().err
    package_log = logging.getLogger("rockdec")  # left as found: library use after a command logs nothing of ours
    assert package_log.handlers == [] and package_log.propagate and package_log.level == logging.NOTSET


class _Terminal(io_module.StringIO):
    def isatty(self):
        return True


@pytest.mark.parametrize("terminal", [True, False])
def test_progress_bar_is_labelled_on_a_terminal_and_absent_in_a_log(terminal, monkeypatch):
    import dask

    from rockdec import console

    stream = _Terminal() if terminal else io_module.StringIO()
    monkeypatch.setattr(sys, "stderr", stream)
    monkeypatch.setattr(console, "BAR_AFTER_S", 0.0)
    with console.configured(0), console.progress("calibrating"):
        dask.delayed(time.sleep)(0.3).compute(scheduler="threads")
    text = stream.getvalue()
    if terminal:
        assert "\rcalibrating [" in text and "100% Completed" in text
    else:
        assert text == ""  # a log file gets no carriage-return frames


@pytest.mark.parametrize("terminal", [True, False])
def test_a_workflow_job_logs_start_and_end_and_draws_the_same_bar_only_on_a_terminal(terminal, monkeypatch):
    import dask

    from rockdec import console
    from rockdec.pipeline import job

    log, screen = io_module.StringIO(), _Terminal() if terminal else io_module.StringIO()
    monkeypatch.setattr(sys, "stderr", log)
    monkeypatch.setattr(console, "BAR_AFTER_S", 0.0)
    with job.progress("signatures", terminal=screen):
        dask.delayed(time.sleep)(0.3).compute(scheduler="threads")
    lines = log.getvalue().splitlines()
    assert lines[0] == "signatures: started" and lines[-1].startswith("signatures: done in") and "\r" not in log.getvalue()
    assert ("\rsignatures [" in screen.getvalue()) == terminal


def test_workflow_without_snakemake_says_which_extra_to_install(monkeypatch, capsys):
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "snakemake" else real(name, *a))
    assert main(["workflow", "--scene", "tiny"]) == 2
    assert "pip install 'rockdec[workflow]'" in capsys.readouterr().err


@pytest.mark.slow
def test_workflow_passes_its_scene_and_every_other_option_to_snakemake(tmp_path, monkeypatch, capfd):
    """A dry run (-n) of the tiny scene from an empty folder: Snakemake plans the tiny scene's jobs there.
    The command runs in this process; Snakemake, its child, writes to the captured descriptors."""
    monkeypatch.chdir(tmp_path)
    code = main(["workflow", "--scene", "tiny", "-n", "--quiet", "rules"])
    out = capfd.readouterr()
    assert code == 0, out.err[-2000:]
    text = out.out + out.err
    assert "calibrate" in text and "signatures" in text
    assert "results/paper" not in text
    assert not (tmp_path / "results").exists()  # a dry run writes nothing


#: Libraries a warm ``rockdec estimate`` has no use for: each takes about as long to import as the estimate's analysis.
NOT_ON_THE_WARM_PATH = ("xarray", "pandas", "dask", "distributed", "matplotlib", "jsonschema", "scipy.stats", "scipy.signal")


@pytest.mark.slow
def test_a_warm_estimate_of_a_csv_record_loads_no_library_it_does_not_use(tmp_path, capsys, monkeypatch):
    """A CSV record's calibration built here (a fake one); ``rockdec estimate --json`` in a fresh
    interpreter then reads it from the cache, reads the record, repairs it, measures its
    model and answers without importing any of :data:`NOT_ON_THE_WARM_PATH`."""
    import rockdec
    from rockdec.calibrate import calibration

    monkeypatch.setattr(calibration, "_grid_point", fake_calibration.grid_point)
    theta = rockdec.simulate(0.85, 20_000, seed=1)
    record = tmp_path / "r.csv"
    np.savetxt(record, np.c_[theta["time"].values, theta.values], delimiter=",", header="time,theta", comments="", fmt="%.10g")
    args = ["estimate", str(record), "--cache", str(tmp_path / "cache"), "--json"]
    assert main(args) == 0
    built = json.loads(capsys.readouterr().out)
    probe = (f"import json, sys; from rockdec.cli import main; code = main({args!r}); "
             f"print(json.dumps([code, sorted(set({NOT_ON_THE_WARM_PATH!r}) & set(sys.modules))]), file=sys.stderr)")
    proc = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=300)
    code, loaded = json.loads(proc.stderr.strip().splitlines()[-1])
    warm = json.loads(proc.stdout)
    assert code == 0 and warm["calibration"]["cached"] is True and warm["e"] == built["e"], proc.stderr[-2000:]
    assert loaded == []


def test_calibrating_is_announced_only_when_a_calibration_is_built(tmp_path, capsys, monkeypatch):
    from rockdec import __version__
    from rockdec.calibrate import calibration

    monkeypatch.setattr(calibration, "_grid_point", fake_calibration.grid_point)
    record = tmp_path / "r.nc"
    assert main(["simulate", "--e", "0.85", "--seeds", "1", "--n-points", "20000", "--out", str(record)]) == 0
    capsys.readouterr()
    args = ["estimate", str(record), "--cache", str(tmp_path / "cache"), "--json"]
    assert main(args) == 0
    first = capsys.readouterr()
    assert "rockdec: calibrating" in first.err and "\r" not in first.err  # not a terminal: no bar frames
    assert main(args) == 0
    again = capsys.readouterr()
    assert "calibrating" not in again.err
    res = json.loads(again.out)
    assert res["calibration"]["cached"] is True and res["rockdec_version"] == __version__
    low, high = res["g_interval"]
    assert low < res["g"] < high and "95 % interval" in res["g_interval_note"] and 0.9 <= res["g_coverage"] <= 1.0


@pytest.mark.parametrize("raw, side, shown", [(0.39, "below", "< 0.400"), (1.0, "above", "> 0.995"), (0.7, None, "0.7000")])
def test_a_corrected_value_at_the_end_of_the_calibrated_range_is_shown_as_a_bound(raw, side, shown):
    """Identity belt (mean e, spread 0.01) on [0.4, 0.995]: a raw value beyond the mean curve
    is corrected to the range's end, which bounds e rather than estimating it."""
    from rockdec.calibrate import belt
    from rockdec import estimation
    from rockdec.report.summary import text as _estimate_text

    e = np.linspace(0.4, 0.995, 1191)
    b = belt.Belt(e, e.copy(), np.full(e.size, 0.01), 0.0)
    c = belt.correct(b, raw)
    assert estimation.beyond(b, raw, c) == side
    est = {"raw": raw, "e": None if side else c.value, "beyond": side, "calibrated_range": [0.4, 0.995],
           "interval": [c.low, c.high], "coverage": 0.95, "triggers": 100, "notes": []}
    res = {"records": ["r.csv"], "samples": 1000, "dt": 0.01, "nan_samples": 0, "sigma_y": 0.01, "points_per_cycle": 75.0,
           "g": 1.0, "g_given": True, "g_raw": 1.0, "calibration": {"file": "c.nc", "cached": True, "seconds": 0.0},
           "estimators": {"e_v": est}, "estimator": "e_v", "e": est["e"], "interval": est["interval"], "coverage": 0.95,
           "warnings": [], "record_model": None, "selection": [{"estimator": "e_v", "holds": True}]}
    row = next(line for line in _estimate_text(res).splitlines() if line.strip().startswith("e_v *"))
    assert shown in row
    if side:
        assert "0.4000 " not in row.split("[")[0] and "0.9950 " not in row.split("[")[0]  # the end is not printed as a value
        assert f"{side} the calibrated range" in _estimate_text(res, verbose=True)


def test_the_g_line_of_the_report_gives_g_s_interval_and_keeps_a_given_g_as_given():
    from rockdec.report.summary import text as _estimate_text

    est = {"raw": 0.9, "e": 0.9, "beyond": None, "calibrated_range": [0.4, 0.995], "interval": [0.88, 0.92],
           "coverage": 0.95, "triggers": 100, "notes": []}
    res = {"records": ["r.csv"], "samples": 1000, "dt": 0.01, "nan_samples": 0, "sigma_y": 0.01, "points_per_cycle": 75.0,
           "g": 1.02, "g_given": False, "g_raw": 0.99, "g_interval": [0.97, 1.08], "g_coverage": 0.94,
           "calibration": {"file": "c.nc", "cached": True, "seconds": 0.0}, "estimators": {"e_v": est}, "estimator": "e_v",
           "e": 0.9, "interval": [0.88, 0.92], "coverage": 0.95, "warnings": [], "record_model": None,
           "selection": [{"estimator": "e_v", "holds": True}]}
    line = next(line for line in _estimate_text(res).splitlines() if "restoring acceleration" in line)
    assert "= 1.02 rad/s^2" in line and "95 % interval [0.97, 1.08]" in line and "on 94% of the calibration's records" in line
    given = {**res, "g": 1.0, "g_given": True, "g_interval": None, "g_coverage": None}
    line = next(line for line in _estimate_text(given).splitlines() if "restoring acceleration" in line)
    assert "= 1 rad/s^2 (given;" in line and "interval" not in line


@pytest.mark.hostile("report", "answered")
@pytest.mark.parametrize("missing", [(), ("g",), ("g", "g_raw"), ("g_raw",), ("sigma_y", "points_per_cycle"),
                                     ("g", "g_raw", "sigma_y", "points_per_cycle")],
                         ids=["none", "g", "g and g_raw", "g_raw", "sigma_y", "all"])
def test_the_text_report_prints_whatever_the_record_could_not_give(missing):
    """Issue 21: the text report crashed when g could not be read off the record (after the
    whole calibration); each value the analysis leaves undetermined (None in the JSON) is
    shown as not determined, and the reason for a missing e is printed."""
    from rockdec.report.summary import text as _estimate_text

    est = {"raw": None, "e": None, "beyond": None, "calibrated_range": [0.4, 0.995], "interval": [None, None],
           "coverage": None, "triggers": 0, "notes": []}
    res = {"records": ["r.csv"], "samples": 1000, "dt": 0.01, "nan_samples": 0, "sigma_y": 0.01, "points_per_cycle": 75.0,
           "g": 1.02, "g_given": False, "g_raw": 0.99, "g_interval": None, "g_coverage": None,
           "calibration": {"file": "c.nc", "cached": True, "seconds": 0.0}, "estimators": {"e_v": est}, "estimator": None,
           "reason": "no estimator gave a value", "e": None, "interval": [None, None], "coverage": None,
           "warnings": ["w"], "record_model": None, "selection": []}
    text = _estimate_text({**res, **dict.fromkeys(missing)})
    g_line = next(line for line in text.splitlines() if "restoring acceleration" in line)
    assert ("not determined" in g_line) == ("g" in missing)
    assert ("0.99" in g_line) == ("g_raw" not in missing)
    assert "e: not estimated: no estimator gave a value" in text and "warning: w" in text
    if "sigma_y" in missing:
        assert "sigma_Y = - rad, - samples per rocking cycle" in text


def test_the_glossary_explains_every_estimator_and_word_of_the_estimate_report():
    from pathlib import Path

    from rockdec.rdd import estimators, registry

    page = (Path(__file__).resolve().parents[1] / "docs" / "reference" / "glossary.md").read_text()
    glossary = page[page.index("| word |"):]
    glossary = glossary[: glossary.index("\n\n")]
    rows = [line.split("|")[1] for line in glossary.splitlines() if line.startswith("| ")]
    assert all(registry.spec(name).reads.strip() for name in estimators.ESTIMATORS)  # the report's "reads" column
    named = " ".join(rows)
    for word in (*estimators.ESTIMATORS, "D_a", "D_v", "raw", "corrected", "95 % interval", "coverage", "triggers", "sigma_Y"):
        assert word in named or (word in ("e1", "e2", "e3", "e4") and "`e1` .. `e4`" in named), word


def test_a_scene_is_found_from_any_folder(tmp_path, monkeypatch):
    """Outside a checkout (no ./config/config.yaml), --scene reads the workflow's own config."""
    monkeypatch.chdir(tmp_path)
    args = ["simulate", "--scene", "tiny", "--seeds", "0", "--n-points", "100", "--dt", "0.01", "--burn-in", "0", "--out", "x.nc"]
    assert main(args) == 0
    with xr.open_dataset(tmp_path / "x.nc") as ds:
        assert json.loads(ds.attrs["settings"])["system"]["e"] == 0.95  # the tiny scene's e


def test_a_reader_that_stops_early_ends_the_command_quietly(monkeypatch, capsys):
    """`rockdec estimate ... | head`: the closed pipe is not reported as a bug in rockdec."""
    import os

    def prints_into_a_closed_pipe(args):
        raise BrokenPipeError(32, "Broken pipe")

    from rockdec import cli

    monkeypatch.setattr(cli, "cmd_estimate", prints_into_a_closed_pipe)
    saved = os.dup(1)  # the command points the process's stdout at /dev/null
    try:
        assert main(["estimate", "record.csv"]) == 141
    finally:
        os.dup2(saved, 1)
        os.close(saved)
    assert "internal error" not in capsys.readouterr().err

"""Hostile input: every failure a user can cause is one sentence naming the value and the
fix, exit code 2, no file written, no traceback; no entry point hangs or returns a silent
non-finite number (issue 13). Record time axes are checked in the records tests.
"""

from __future__ import annotations

import errno
import json
import math
import shutil
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rockdec.rdd import estimators, signatures
from rockdec.physics import fixed_step, housner, run, simulate
from rockdec import io
from rockdec import validate as checks
from rockdec.cli import main

from conftest import PYTHON_FORKS, calibrated_step

ROOT = Path(__file__).resolve().parents[1]
#: A fast simulate call: an explicit step and no burn-in skip the calibration.
FAST = ["--dt", "0.0034", "--burn-in", "0", "--seeds", "0", "--n-points", "50"]

hostile = pytest.mark.hostile
"""A hostile case, ``hostile(kind, outcome)``: what the user got wrong (``kind``) and what the
tool does (``outcome``: refused, answered, warned, or refused or answered for generated
values); ``benchmarks/hostile_matrix.py`` counts them by both."""


def marked(table: dict, kind, outcome: str = "refused") -> list:
    """The cases of ``table`` (name -> tuple of arguments) as parameters named by their case,
    each marked :data:`hostile` with ``kind`` (a kind, or a function of the case's name)."""
    return [
        pytest.param(*args, id=name, marks=hostile(kind(name) if callable(kind) else kind, outcome))
        for name, args in table.items()
    ]


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A small simulation file and its signature file, made by the command line."""
    folder = tmp_path_factory.mktemp("inputs")
    sim, sig = folder / "sim.nc", folder / "sig.nc"
    assert main(["simulate", "--out", str(sim), "--dt", "0.0034", "--seeds", "0-3", "--n-points", "3000"]) == 0
    assert main(["signatures", str(sim), "--out", str(sig)]) == 0
    (folder / "notes.txt").write_text("not NetCDF")
    return folder


def config_file(folder: Path, text: str) -> Path:
    path = folder / "hostile.yaml"
    path.write_text(textwrap.dedent(text))
    return path


def refused(argv, out_dir: Path, capsys, keywords):
    """Run the command; assert exit 2, one line naming ``keywords``, nothing written."""
    before = sorted(out_dir.iterdir())
    code = main(argv)
    err = capsys.readouterr().err
    assert code == 2, err
    errors = [line for line in err.splitlines() if "error:" in line]
    assert len(errors) == 1 and err.strip().splitlines()[-1] == errors[0], err  # one sentence, the last line
    assert "Traceback" not in err and "internal error" not in err
    for word in keywords:
        assert word in err, (word, err)
    assert sorted(out_dir.iterdir()) == before  # no output, no temporary file, no lock
    return err


# --------------------------------------------------------------------------- the matrix

SIMULATE_CASES = {
    "dt nan (spun forever)": (["--dt", "nan"], ["--dt nan", "finite"]),
    "dt inf": (["--dt", "inf"], ["--dt inf", "finite"]),
    "dt negative": (["--dt", "-1"], ["--dt -1.0", "> 0"]),
    "nu nan (spun forever)": (["--nu", "nan"], ["--nu nan", "finite"]),
    "theta_cr zero": (["--theta-cr", "0"], ["--theta-cr 0.0", "> 0"]),
    "nu overflows g": (["--nu", "1e200"], ["--nu 1e+200", "g = nu^2 theta_cr", "finite"]),
    "theta0 nan (spun forever)": (["--theta0", "nan"], ["--theta0 nan", "finite"]),
    "theta0 -inf": (["--theta0=-inf"], ["--theta0 -inf", "finite"]),
    "theta0 beyond float32": (["--theta0", "1e39"], ["'theta'", "float32", "smaller scales"]),
    "theta_dot0 nan": (["--theta-dot0", "nan"], ["--theta-dot0 nan", "finite"]),
    "sigma_p nan (wrote zeros)": (["--sigma-p", "nan"], ["--sigma-p nan", "finite"]),
    "sigma_p negative": (["--sigma-p", "-0.1"], ["--sigma-p -0.1", ">= 0"]),
    "e nan (NaN to integer)": (["--e", "nan"], ["--e nan", "finite", ">= 0 and <= 1"]),
    "e inf": (["--e", "inf"], ["--e inf", "finite"]),
    "points per cycle nan": (["--points-per-cycle", "nan", "--dt", None], ["--points-per-cycle nan", "finite"]),
    "points per cycle 2": (["--points-per-cycle", "2", "--dt", None], ["--points-per-cycle 2.0", "> 2"]),
    "n_points 1": (["--n-points", "1"], ["--n-points 1", ">= 2"]),
    "n_points decimal": (["--n-points", "6000.0"], ["--n-points", "'6000.0'"]),
    "n_points beyond memory": (["--n-points", str(10**13)], ["--n-points 10000000000000", "GiB", "lower --n-points"]),
    "burn-in beyond memory": (["--burn-in", str(10**12)], ["--burn-in 1000000000000", "GiB"]),
    "chunk seeds 0": (["--chunk-seeds", "0"], ["--chunk-seeds 0", ">= 1"]),
    "seeds empty (ran 20000)": (["--seeds", ""], ["--seeds ''", "0-99"]),
    "seeds repeated": (["--seeds", "0-2,2"], ["--seeds '0-2,2'", "twice"]),
    "seeds not numbers": (["--seeds", "a-b"], ["--seeds 'a-b'", "0-99"]),
    "seeds beyond memory": (["--seeds", "0-99999999999999"], ["--seeds '0-99999999999999'", "GiB", "fewer seeds"]),
    "seeds beyond int64": (["--seeds", str(2**64)], ["--seeds '18446744073709551616'", "0-99"]),
    "free response without amplitude": (["--sigma-p", "0", "--dt", None, "--burn-in", None], ["free response", "--theta0"]),
    "e so near 1 the burn-in never ends": (["--e", "0.9999999", "--burn-in", None], ["give --burn-in"]),
    "unknown scene": (["--scene", "../x", "--config", str(ROOT / "config/config.yaml")], ["unknown scene '../x'"]),
    "missing config file": (["--scene", "paper", "--config", "no/such.yaml"], ["no/such.yaml", "--config"]),
    "dt and points per cycle": (["--points-per-cycle", "75"], ["--points-per-cycle", "not allowed with", "--help"]),
    "unknown option": (["--ee", "0.9"], ["unrecognized", "--ee", "--help"]),
}


def _argv(extra):
    """``FAST`` with ``extra`` applied: ``[flag, value]`` sets a flag, ``[flag, None]`` drops it."""
    argv = list(FAST)
    if len(extra) == 1:  # one "--flag=value" word
        return argv + extra
    for flag, value in zip(extra[::2], extra[1::2]):
        if flag in argv:
            i = argv.index(flag)
            del argv[i : i + 2]
        if value is not None:
            argv += [flag, value]
    return argv


def _simulate_kind(name: str) -> str:
    if "memory" in name:
        return "limits"
    if "never ends" in name:
        return "sizes"
    return "configs" if "scene" in name or "config" in name else "numbers"


@pytest.mark.parametrize("extra, keywords", marked(SIMULATE_CASES, _simulate_kind))
def test_simulate_refuses(tmp_path, capsys, extra, keywords):
    refused(["simulate", "--out", str(tmp_path / "out.nc"), *_argv(extra)], tmp_path, capsys, keywords)


SIGNATURE_CASES = {
    "g nan": (["--g", "nan"], ["--g nan", "finite"]),
    "g zero": (["--g", "0"], ["--g 0.0", "> 0"]),
    "lag range longer than the record (3 GiB)": (["--g", "1e-10"], ["--g 1e-10", "longer than the record", "--n-periods"]),
    "level nan": (["--level", "nan"], ["--level nan", "finite"]),
    "level negative": (["--level", "-1"], ["--level -1.0"]),
    "windows descending": (["--windows", "0.5", "0.2"], ["--windows 0.5 0.2", "ascending"]),
    "windows nan": (["--windows", "0.5", "nan"], ["--windows 0.5 nan", "finite"]),
    "n_periods inf": (["--n-periods", "inf"], ["--n-periods inf", "finite"]),
    "v_level zero": (["--v-level", "0"], ["--v-level 0.0"]),
    "group size 0 (meant all)": (["--group-size", "0"], ["--group-size 0", "at least 1"]),
    "group size negative": (["--group-size", "-3"], ["--group-size -3"]),
    "variable missing": (["--variable", "nope"], ["nope", "--variable"]),
}


@pytest.mark.parametrize("extra, keywords", marked(
    SIGNATURE_CASES, lambda name: "limits" if "GiB" in name else "record files" if "variable" in name else "numbers"))
def test_signatures_refuses(files, tmp_path, capsys, extra, keywords):
    refused(["signatures", str(files / "sim.nc"), "--out", str(tmp_path / "o.nc"), *extra], tmp_path, capsys, keywords)


FILE_CASES = {
    "input missing": (["signatures", "{files}/none.nc"], ["none.nc", "does not exist"]),
    "input not NetCDF": (["signatures", "{files}/notes.txt"], ["notes.txt", "not a readable NetCDF"]),
    "simulation file given to estimates": (["estimates", "{files}/sim.nc"], ["not a signature file", "rockdec signatures"]),
    "fit points 2": (["estimates", "{files}/sig.nc", "--fit-points", "2"], ["--fit-points 2", "at least 3"]),
    "weights unknown": (["estimates", "{files}/sig.nc", "--weights", "all"], ["--weights", "'all'"]),
    "out is a folder": (["signatures", "{files}/sim.nc", "--out", "{out}"], ["is a folder", "file name"]),
    "out in a missing folder": (["signatures", "{files}/sim.nc", "--out", "{out}/no/o.nc"], ["does not exist"]),
    "out exists": (["estimates", "{files}/sig.nc", "--out", "{files}/sim.nc"], ["exists already", "--overwrite"]),
}


@pytest.mark.parametrize("argv, keywords", marked(
    FILE_CASES, lambda name: "output paths" if name.startswith("out") else "numbers" if " points" in name or "weights" in name
    else "record files"))
def test_files_are_refused(files, tmp_path, capsys, argv, keywords):
    argv = [a.format(files=files, out=tmp_path) for a in argv]
    if "--out" not in argv:
        argv += ["--out", str(tmp_path / "o.nc")]
    refused(argv, tmp_path, capsys, keywords)
    assert sorted(p.name for p in files.iterdir()) == ["notes.txt", "sig.nc", "sim.nc"]


@hostile("limits", "refused")
def test_memory_check_names_the_flag(tmp_path, capsys, monkeypatch, files):
    """A request the machine cannot hold is refused before the work, by the flag that asks for it."""
    monkeypatch.setattr(checks, "available_memory", lambda: 2**16)
    refused(["signatures", str(files / "sim.nc"), "--out", str(tmp_path / "o.nc")], tmp_path, capsys,
            ["--n-periods 2.5", "GiB", "more than the 6.1e-05 GiB"])
    refused(["simulate", "--out", str(tmp_path / "o.nc"), *FAST, "--n-points", "100000"], tmp_path, capsys,
            ["--n-points 100000", "--burn-in 0", "GiB"])


# --------------------------------------------------------------------------- errors of our own


def test_internal_error_is_one_line_and_debug_shows_the_traceback(tmp_path, capsys, monkeypatch):
    def broken(*args, **kwargs):
        raise KeyError("boom")

    monkeypatch.setattr(run, "from_scene", broken)
    argv = ["simulate", "--out", str(tmp_path / "o.nc"), *FAST]
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "internal error" in err and "--debug" in err
    assert main(["--debug", *argv]) == 1
    assert "Traceback" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


@hostile("limits", "refused")
def test_disk_full_is_one_sentence_and_leaves_nothing(tmp_path, capsys, monkeypatch):
    def full(self, path, *args, **kwargs):
        Path(path).write_bytes(b"\0" * 100)  # a partial file, as a real write leaves
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(xr.Dataset, "to_netcdf", full)
    refused(["simulate", "--out", str(tmp_path / "o.nc"), *FAST], tmp_path, capsys, ["no space left", "o.nc", "another output file"])


# --------------------------------------------------------------------------- concurrent writes

WRITER = """
import sys, time, os
import dask, dask.array, numpy as np, xarray as xr
from rockdec import io
go = sys.argv[2]
def wait():
    end = time.time() + 60
    while not os.path.exists(go) and time.time() < end:
        time.sleep(0.01)
    return np.arange(1000.0)
x = dask.array.from_delayed(dask.delayed(wait)(), shape=(1000,), dtype=float)
io.write_netcdf(xr.Dataset({"x": ("i", x)}), sys.argv[1])
"""


@hostile("concurrency", "refused")
@pytest.mark.slow
def test_concurrent_runs_on_one_output_refuse_and_on_two_do_not_interfere(tmp_path):
    out, other, go = tmp_path / "a.nc", tmp_path / "b.nc", tmp_path / "go"
    proc = PYTHON_FORKS.start_script(WRITER, out, go, output=tmp_path.parent / f"{tmp_path.name}-writer")  # a second process
    try:
        lock = tmp_path / ".a.nc.lock"
        end = time.time() + 60  # claimed: the lock holds the writer's pid (io._claim creates it, then writes the pid)
        while not (lock.exists() and lock.read_text().strip()) and time.time() < end:
            time.sleep(0.01)
        assert lock.exists() and lock.read_text().strip() == str(proc.pid), "the first writer never claimed its output"
        ds = xr.Dataset({"y": ("i", np.ones(10))})
        with pytest.raises(io.OutputError, match="being written by another run"):
            io.write_netcdf(ds, out)
        with pytest.raises(io.OutputError, match="being written by another run"):
            io.check_output(out)  # refused before any work too
        io.write_netcdf(ds, other)  # another output, meanwhile: no interference
        end = time.time() + 60  # the writer claims its output, then opens its temporary file
        while not list(tmp_path.glob(".a.nc.*.partial")) and time.time() < end:
            time.sleep(0.01)
        partials = list(tmp_path.glob(".a.nc.*.partial"))
        assert len(partials) == 1  # the first run's own temporary file survived the refused writes
    finally:
        go.touch()
        assert proc.wait(timeout=120) == 0, proc.communicate()[1]
    with xr.open_dataset(out) as a, xr.open_dataset(other) as b:
        assert a["x"].values.tolist() == list(range(1000)) and b["y"].values.tolist() == [1.0] * 10
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.nc", "b.nc", "go"]


@hostile("concurrency", "refused")
def test_threads_on_one_output_one_wins_one_refuses(tmp_path):
    release = threading.Event()

    def slow():
        release.wait(30)
        return np.arange(5.0)

    import dask
    import dask.array

    slow_ds = xr.Dataset({"x": ("i", dask.array.from_delayed(dask.delayed(slow)(), shape=(5,), dtype=float))})
    errors = []
    first = threading.Thread(target=lambda: io.write_netcdf(slow_ds, tmp_path / "o.nc", overwrite=True))
    first.start()
    end = time.time() + 30
    while not (tmp_path / ".o.nc.lock").exists() and time.time() < end:
        time.sleep(0.01)
    try:
        io.write_netcdf(xr.Dataset({"x": ("i", np.zeros(5))}), tmp_path / "o.nc", overwrite=True)
    except io.OutputError as exc:
        errors.append(str(exc))
    release.set()
    first.join(30)
    assert len(errors) == 1 and "being written by another run" in errors[0]
    with xr.open_dataset(tmp_path / "o.nc") as ds:
        assert ds["x"].values.tolist() == [0.0, 1.0, 2.0, 3.0, 4.0]


@hostile("kills", "answered")
def test_a_lock_left_by_a_killed_run_is_taken_over(tmp_path):
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    (tmp_path / ".o.nc.lock").write_text(dead.stdout)
    (tmp_path / ".o.nc.x1y2.partial").write_bytes(b"half")
    io.write_netcdf(xr.Dataset({"x": ("i", np.zeros(3))}), tmp_path / "o.nc")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["o.nc"]


# --------------------------------------------------------------------------- arbitrary floats

ANY_FLOAT = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([math.nan, math.inf, -math.inf, 5e-324, -5e-324, 2.2e-308, 1e300, -1e300, 0.0, -0.0, 1.0]),
)
FUZZ = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
TIME_BOUND = 60.0  # s, per call: a hang, not a slow call (a first call compiles its kernel, and CI machines are often shared)


def bounded(func, *args, **kwargs):
    """``func(...)``; a refusal (:class:`InputError`) is returned, not raised; no call may take long."""
    start = time.perf_counter()
    try:
        result = func(*args, **kwargs)
    except checks.InputError as exc:
        result = exc
    assert time.perf_counter() - start < TIME_BOUND, (func.__name__, args, kwargs)
    return result


def finite_or_refused(result):
    if isinstance(result, checks.InputError):
        assert str(result).strip()
        return False
    for array in result if isinstance(result, tuple) else (result,):
        assert np.all(np.isfinite(array)), result
    return True


SIM = dict(dt=0.0034, g=1.0, e=0.95, sigma_p=0.003, theta0=0.001, theta_dot0=0.0)


@hostile("numbers", "refused or answered")
@FUZZ
@given(name=st.sampled_from(sorted(SIM)), value=ANY_FLOAT, grid=st.booleans())
def test_simulate_block_gives_finite_series_or_refuses(name, value, grid):
    kw = {**SIM, name: value}
    finite_or_refused(bounded(simulate.simulate_block, [0, 1], 60, burn_in=20, grid_impacts=grid, **kw))


HOUSNER = dict(dt=0.0034, nu=2.0, theta_cr=0.25, e=0.95, sigma_p=0.003, theta0=0.001, theta_dot0=0.0)


@hostile("numbers", "refused or answered")
@FUZZ
@given(name=st.sampled_from(sorted(HOUSNER)), value=ANY_FLOAT)
def test_housner_gives_finite_series_until_it_falls_or_refuses(name, value):
    result = bounded(housner.simulate_block_housner, [0, 1], 60, burn_in=20, **{**HOUSNER, name: value})
    if isinstance(result, checks.InputError):
        return
    theta, theta_dot, fell = result
    standing = np.arange(60) < np.where(fell < 0, 60, fell)[:, None]
    assert np.isfinite(theta[standing]).all() and np.isfinite(theta_dot[standing]).all()
    assert np.isnan(theta[~standing]).all()


@hostile("numbers", "refused or answered")
@FUZZ
@given(
    theta=ANY_FLOAT, omega=ANY_FLOAT, dt=ANY_FLOAT, g=ANY_FLOAT, e=st.one_of(ANY_FLOAT, st.floats(0, 1)),
)
def test_kernel_steps_return_and_keep_nan(theta, omega, dt, g, e):
    """The compiled steps assume valid input, but never loop on anything: each returns at once
    (or, given g = 0 or a negative step, raises ZeroDivisionError), and a NaN state never
    becomes a finite one (it must not turn into a rest state)."""
    nan_in = math.isnan(theta) or math.isnan(omega)
    for step, args in (
        (simulate.flight, (g, e)), (fixed_step.step, (g, e)), (housner.housner_flight, (2.0, 0.25, e)),
    ):
        try:
            out = bounded(step, theta, omega, dt, *args)
        except ZeroDivisionError:
            assert g == 0.0 or dt < 0.0
            continue
        if nan_in:
            assert not (math.isfinite(out[0]) and math.isfinite(out[1])), (step, out)


@hostile("numbers", "refused or answered")
@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # a pilot that overflows: refused
@settings(max_examples=25, deadline=None)
@given(name=st.sampled_from(["e", "g", "sigma_p", "points_per_cycle"]), value=ANY_FLOAT)
def test_calibrate_dt_gives_a_finite_step_or_refuses(name, value):
    kw = {"e": 0.95, "g": 1.0, "sigma_p": 0.003, "points_per_cycle": 75.0, name: value}
    result = bounded(simulate.calibrate_dt, pilot_seeds=2, pilot_points=300, iterations=2, **kw)
    if not isinstance(result, checks.InputError):
        assert result["dt"] > 0 and np.isfinite([result["dt"], result["sigma_y"], result["sigma_ydot"]]).all()


def _free_response(n=120, e=0.95):
    """The ideal free response of eqs. 4, 6 from a = 1, g = 1, sampled at dt = 0.05."""
    dt = 0.05
    theta, _ = simulate.simulate_block([0], n, dt=dt, g=1.0, e=e, sigma_p=0.0, theta0=1.0)
    return theta[0], dt


@hostile("numbers", "refused or answered")
@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # overflow inside the fits: the reason says so
@FUZZ
@given(value=ANY_FLOAT, where=st.sampled_from(["dt", "scale", "sample", "d_sample"]))
def test_estimators_give_a_value_or_a_reason_or_refuse(value, where):
    r, dt = _free_response()
    d = np.concatenate([-r[:0:-1] * 0.95, r]) * -1.0
    if where == "dt":
        dt = value
    elif where == "scale":
        with np.errstate(all="ignore"):
            r = r * value
    elif where == "sample":
        r = r.copy()
        r[len(r) // 3] = value
    else:
        d = d.copy()
        d[len(d) // 2 + 2] = value
    result = bounded(estimators.estimate_all, r, d, dt)
    if isinstance(result, checks.InputError):
        assert where == "dt"
        return
    for name, est in result.items():
        assert np.isfinite(est.value) or (np.isnan(est.value) and est.reason), (name, est)


@hostile("numbers", "refused or answered")
@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # the period of eq. 5 overflows to inf: refused
@FUZZ
@given(value=ANY_FLOAT, where=st.sampled_from(["level", "velocity", "width", "dt", "sample", "n_periods", "g"]))
def test_signature_functions_give_finite_sums_or_refuse(value, where):
    y = np.sin(np.arange(400) * 0.3) * (1 + 0.3 * np.sin(np.arange(400) * 0.01))
    if where == "sample":
        y[200] = value
    args = {"level": 0.8, "velocity": 0.2, "width": 0.3, "dt": 0.1, **({where: value} if where != "sample" else {})}
    for result in (
        bounded(signatures.extremum_sums, y, args["level"], [args["width"]], 10),
        bounded(signatures.crossing_sums, y, args["velocity"], [args["width"]], 10, args["dt"]),
    ):
        if not isinstance(result, checks.InputError):
            assert np.isfinite(result.sum).all() and (result.count >= 0).all() and (result.skipped >= 0).all()
    lag = bounded(signatures.lag_samples, value if where == "n_periods" else 2.5, 0.01, value if where == "g" else 1.0, 0.0034)
    assert isinstance(lag, checks.InputError) or (isinstance(lag, int) and lag >= 0)


@hostile("numbers", "refused or answered")
@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    flag=st.sampled_from(["--e", "--nu", "--theta-cr", "--sigma-p", "--dt", "--theta0", "--theta-dot0"]),
    value=ANY_FLOAT,
)
def test_cli_simulate_options_give_a_finite_file_or_one_sentence(tmp_path_factory, flag, value):
    folder = tmp_path_factory.mktemp("fuzz")
    out = folder / "o.nc"
    argv = ["simulate", "--out", str(out), *_argv([flag, repr(value)])]
    start = time.perf_counter()
    code = main(argv)
    assert time.perf_counter() - start < 2 * TIME_BOUND  # a simulation of the fuzzed run: bounded, not hung
    if code == 0:
        with xr.open_dataset(out) as ds:
            assert np.isfinite(ds["theta"].values).all() and np.isfinite(ds["theta_dot"].values).all()
    else:
        assert code == 2 and list(folder.iterdir()) == []


# --------------------------------------------------------------------------- round two: rockdec estimate
# Records of 20,000 samples and a calibration of 6 e x 5 sets keep each answered case near 1 s;
# refusals come before any calibration.

from rockdec.calibrate import calibration

from rockdec import estimation  # noqa: E402

#: The calibration's own grid and sets, before any test shrinks them.
FULL_CALIBRATION = (calibration.E_GRID, calibration.SETS_PER_E)


@pytest.fixture(scope="module")
def tiny_calibration():
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(calibration, "E_GRID", (0.5, 0.65, 0.75, 0.85, 0.92, 0.97))
        mp.setattr(calibration, "SETS_PER_E", 5)
        mp.setattr(calibration, "SETS_PER_E_CAPPED", 5)
        yield


@pytest.fixture(scope="module")
def rocking(tmp_path_factory):
    """A simulated rocking record (e = 0.85, g = 1 rad/s^2, 20,000 samples) as CSV, and its parts."""
    folder = tmp_path_factory.mktemp("rocking")
    cal = calibrated_step(0.85, 1.0, 0.003)
    theta = simulate.simulate_block([11], 20_000, dt=cal["dt"], g=1.0, e=0.85, sigma_p=0.003, burn_in=cal["burn_in"])[0][0]
    dt = cal["dt"]
    t = np.arange(theta.size) * dt
    np.savetxt(folder / "rec.csv", np.c_[t, theta], delimiter=",", header="time,theta", comments="", fmt="%.10g")
    return {"folder": folder, "theta": theta, "dt": dt, "t": t, "csv": folder / "rec.csv"}


@pytest.fixture(scope="module")
def tiny_cache(rocking, tiny_calibration, tmp_path_factory) -> dict:
    """``folder``: a calibration folder holding the tiny calibration of :func:`rocking`, built
    once for the module by ``answer``, the estimate of :func:`rocking` that built it;
    :func:`tiny_cache_copy` copies it for a test, as a user's cache serves every run."""
    folder = tmp_path_factory.mktemp("tiny-cache") / "cache"
    code, answer, err = _estimate([rocking["csv"]], folder)
    assert code == 0 and answer["calibration"]["cached"] is False, err
    return {"folder": folder, "answer": answer}


def tiny_cache_copy(tiny_cache, tmp_path) -> Path:
    """``tmp_path / "cache"``, a copy of :func:`tiny_cache`: the test's runs on :func:`rocking`
    find its calibration there (the cache is keyed by content, so sharing it changes no answer)."""
    return Path(shutil.copytree(tiny_cache["folder"], tmp_path / "cache"))


def _estimate(argv, cache):
    """``rockdec estimate ARGV --json --cache CACHE``: exit code, parsed JSON (or None), stderr."""
    import io as _io
    from contextlib import redirect_stderr, redirect_stdout

    out, err = _io.StringIO(), _io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        code = main(["estimate", *map(str, argv), "--json", "--cache", str(cache)])
    return code, (json.loads(out.getvalue()) if code == 0 else None), err.getvalue()


def _nc(path, theta, dt, theta_units=None, time_units=None, attrs=None):
    var_attrs = {"units": theta_units} if theta_units else {}
    time_attrs = {"units": time_units} if time_units else {}
    t = np.arange(theta.shape[-1]) * dt
    dims = ("seed", "time") if theta.ndim == 2 else ("time",)
    ds = xr.Dataset({"theta": (dims, theta, var_attrs)}, coords={"time": ("time", t, time_attrs)}, attrs=attrs or {})
    ds.to_netcdf(path)
    return path


def _sparse(path, head: bytes, size: int):
    """A file of ``size`` bytes that starts with ``head`` and is a hole after it (no disk used)."""
    with open(path, "wb") as f:
        f.write(head)
        f.truncate(size)
    return path


def _estimate_cases(r):
    """name -> (argv, words in the refusal); ``r``: the rocking fixture."""
    f, theta, dt, t = r["folder"], r["theta"], r["dt"], r["t"]
    rng = np.random.default_rng(0)
    cases = {}

    def csv(name, y, tt=t, sep=","):
        path = f / name
        np.savetxt(path, np.c_[tt, y], delimiter=sep, header=f"time{sep}theta", comments="", fmt="%.10g")
        return path

    cases["white noise"] = ([csv("noise.csv", rng.standard_normal(theta.size) * 1e-3)], ["does not look like a rocking record", "white noise"])
    cases["white noise with --g"] = ([f / "noise.csv", "--g", "1"], ["does not look like a rocking record"])
    for g in ("57.3", "100", "1e-3", "1e308", "0.4", "3"):
        cases[f"--g {g} off the record's own"] = ([r["csv"], "--g", g], [f"--g {float(g):g}", "times the g the records show"])
    cases["same file twice"] = ([r["csv"], r["csv"]], ["same samples"])
    cases["a copy of the file"] = ([r["csv"], csv("copy.csv", theta)], ["copy.csv", "same samples"])
    cases["two identical series in a file"] = ([_nc(f / "twice.nc", np.stack([theta, theta]), dt)], ["[1] holds the same samples as", "[0]"])
    cases["angle units unknown"] = ([_nc(f / "grad.nc", theta, dt, theta_units="furlong")], ["units 'furlong'", "rad or degrees"])
    cases["time units unknown"] = ([_nc(f / "fortnight.nc", theta, dt, time_units="fortnight")], ["units 'fortnight'", "s or ms"])
    xr.Dataset({"theta": ("time", theta)}, attrs={"dt": "abc"}).to_netcdf(f / "abc.nc")
    cases["dt attribute 'abc'"] = ([f / "abc.nc"], ["attribute dt 'abc'", "not a number of seconds"])
    xr.Dataset({"theta": ("time", theta)}, attrs={"dt": np.array([0.01, 0.02])}).to_netcdf(f / "dt2.nc")
    cases["dt attribute of two values"] = ([f / "dt2.nc"], ["attribute dt", "not a number of seconds"])
    cases["a folder as record"] = ([f], ["a folder, not a record file"])
    one_col = f / "one_col.csv"
    np.savetxt(one_col, theta)
    npy = f / "rec.npy"
    np.save(npy, theta)
    for flag, value, words in (
        ("--fs", "0", ["--fs 0", "> 0"]), ("--fs", "1e-320", ["--fs 1e-320"]), ("--fs", "-5", ["--fs -5"]),
        ("--fs", "inf", ["--fs inf"]), ("--fs", "nan", ["--fs nan"]), ("--dt", "0", ["--dt 0"]), ("--dt", "-1", ["--dt -1"]),
        ("--dt", "nan", ["--dt nan"]), ("--dt", "inf", ["--dt inf"]),
        ("--dt", "1e308", ["1e+308 s", "beyond the range of a float"]), ("--dt", "5e-324", ["beyond the range of a float"]),
        ("--dt", "1e300", ["1e+300 s"]),
    ):
        cases[f"{flag} {value} (npy)"] = ([npy, flag, value], words)
        cases[f"{flag} {value} (one-column csv)"] = ([one_col, flag, value], words)
    long_name = f / ("r" * 300 + ".csv")
    cases["record name of 300 characters"] = ([long_name], ["bytes, longer than the 255", "shorter name"])
    cases["--plot .txt"] = ([r["csv"], "--plot", f / "p.txt"], ["--plot", ".txt is not a format", ".png or .pdf"])
    cases["--plot .svg"] = ([r["csv"], "--plot", f / "p.svg"], [".svg is not a format"])
    cases["--plot without suffix"] = ([r["csv"], "--plot", f / "plot"], ["no format suffix"])
    cases["--plot onto the input"] = ([r["csv"], "--plot", r["csv"]], ["is the record"])
    cases["--plot onto the input with --overwrite"] = ([r["csv"], "--plot", r["csv"], "--overwrite"], ["is the record"])
    cases["--plot name of 300 characters"] = ([r["csv"], "--plot", f / ("p" * 300 + ".png")], ["bytes, longer than the 255", "shorter name"])
    cases["--plot exists"] = ([r["csv"], "--plot", csv("exists.png", theta[:10], t[:10])], ["exists already", "--overwrite"])
    cases["--plot in a missing folder"] = ([r["csv"], "--plot", f / "no" / "p.png"], ["does not exist"])
    cases["--cache on a file"] = ([r["csv"], "--cache-file"], ["--cache", "is a file"])
    cases["2 GiB of NUL as CSV"] = ([_sparse(f / "nul.csv", b"", 2 * 2**30)], ["NUL bytes", "binary"])
    cases["NUL bytes after a header"] = ([_sparse(f / "nul2.csv", b"time,theta\n0,1\n", 2**20)], ["NUL bytes"])
    cases["no line break"] = ([_csv_bytes(f / "oneline.csv", b"1," * 40_000)], ["no line break"])
    big_npy = f / "big.npy"
    with open(big_npy, "wb") as handle:  # a header for 200 million float64 samples, then a hole
        np.lib.format.write_array_header_1_0(handle, {"descr": "<f8", "fortran_order": False, "shape": (200_000_000,)})
        handle.truncate(handle.tell() + 8 * 200_000_000)
    # refused for the time (pass --yes) or, on a small machine, for the memory: both name the size
    cases["200 million samples (npy)"] = ([big_npy, "--dt", "0.01"], ["records of about 2e+08 samples need"])
    head = b"time,theta\n" + b"".join(f"{k * 0.01:.2f},{v:.8f}\n".encode() for k, v in enumerate(theta[:4000]))
    cases["200 million samples (csv)"] = ([_sparse(f / "big.csv", head, 200_000_000 * (len(head) // 4001))], ["e+08 samples need"])
    spiky = theta.copy()
    spiky[::2000] = 1e3 * np.std(theta)
    cases["spikes"] = ([csv("spikes.csv", spiky)], ["spike of", "times the rms", "remove the spikes"])
    gaps = theta.copy()
    gaps[rng.choice(theta.size, theta.size // 20, replace=False)] = np.nan
    cases["5 % scattered NaN"] = ([csv("gaps.csv", gaps)], ["NaN, scattered", "fill short gaps"])
    cases["constant record"] = ([csv("const.csv", np.full_like(theta, 0.01))], ["constant"])
    return cases


@pytest.fixture(scope="module")
def estimate_cases(rocking):
    """:func:`_estimate_cases`, its files written once for the module (each case refuses, so
    none writes or changes a file: the test checks it)."""
    return _estimate_cases(rocking)


def _csv_bytes(path, data: bytes):
    path.write_bytes(data)
    return path


ESTIMATE_CASE_NAMES = [
    "white noise", "white noise with --g", *[f"--g {g} off the record's own" for g in ("57.3", "100", "1e-3", "1e308", "0.4", "3")],
    "same file twice", "a copy of the file", "two identical series in a file", "angle units unknown", "time units unknown",
    *[f"{flag} {value} ({kind})" for flag, value in (
        ("--fs", "0"), ("--fs", "1e-320"), ("--fs", "-5"), ("--fs", "inf"), ("--fs", "nan"), ("--dt", "0"), ("--dt", "-1"),
        ("--dt", "nan"), ("--dt", "inf"), ("--dt", "1e308"), ("--dt", "5e-324"), ("--dt", "1e300"),
    ) for kind in ("npy", "one-column csv")],
    "record name of 300 characters", "--plot .txt", "--plot .svg", "--plot without suffix", "--plot onto the input",
    "--plot onto the input with --overwrite", "--plot name of 300 characters", "--plot exists", "--plot in a missing folder",
    "--cache on a file", "2 GiB of NUL as CSV", "NUL bytes after a header", "no line break", "200 million samples (npy)",
    "200 million samples (csv)", "spikes", "5 % scattered NaN", "constant record", "dt attribute 'abc'", "dt attribute of two values", "a folder as record",
]


def _estimate_kind(name: str) -> str:
    if name.startswith(("white noise", "--g ", "same file", "a copy", "two identical", "constant")):
        return "wrong answers"
    if "--plot" in name:
        return "output paths"
    for words, kind in (("units", "units"), ("--cache", "cache"), ("million samples", "sizes")):
        if words in name:
            return kind
    return "numbers" if name.startswith(("--fs", "--dt", "dt attribute")) else "record files"


@pytest.mark.parametrize("name", marked({name: (name,) for name in ESTIMATE_CASE_NAMES}, _estimate_kind))
def test_estimate_refuses_in_one_sentence_before_any_calibration(name, estimate_cases, rocking, tmp_path, capsys):
    case = estimate_cases[name]
    argv, words = list(case[0]), case[1]
    cache = tmp_path / "cache"
    if "--cache-file" in argv:
        argv.remove("--cache-file")
        cache = tmp_path / "cachefile"
        cache.write_text("not a folder")
    before = sorted(p.name for p in rocking["folder"].iterdir())
    start = time.perf_counter()
    code, _, err = _estimate(argv, cache)
    assert time.perf_counter() - start < 60, "a refusal must come quickly"
    assert code == 2, err
    lines = [line for line in err.splitlines() if "error:" in line]
    assert len(lines) == 1 and "Traceback" not in err and "internal error" not in err, err
    for word in words:
        assert word in lines[0], (word, err)
    assert not (cache.is_dir() and any(cache.glob("*.nc"))), "a calibration was built for a refused record"
    assert sorted(p.name for p in rocking["folder"].iterdir()) == before  # no plot, lock or partial file


OTHER_CASES = {
    "simulate 1e8 seeds of 50 points": (["simulate", "--out", "{out}/o.nc", "--dt", "0.0034", "--seeds", "0-99999999", "--n-points", "50"],
                                        ["--seeds '0-99999999'", "pass --yes"]),
    "simulate --dt 5e-324": (["simulate", "--out", "{out}/o.nc", *_argv(["--dt", "5e-324"])], ["--dt 5e-324", "the step about", "outside"]),
    "simulate --dt 1e-320": (["simulate", "--out", "{out}/o.nc", *_argv(["--dt", "1e-320"])], ["--dt 1e-320", "the step about", "outside"]),
    "housner started beyond theta_cr": (["simulate", "--out", "{out}/o.nc", *_argv(["--model", "housner", "--theta0", "0.3"])],
                                        ["--theta0 0.3", "critical angle", "overturns"]),
    "housner started at -theta_cr": (["simulate", "--out", "{out}/o.nc", *_argv(["--model", "housner", "--theta0", "-0.25"])],
                                     ["critical angle"]),
    "simulate --out name of 300 characters": (["simulate", "--out", "{out}/" + "o" * 300 + ".nc", *FAST], ["bytes, longer than the 255"]),
    "signatures --n-periods 1e-300": (["signatures", "{files}/sim.nc", "--out", "{out}/s.nc", "--n-periods", "1e-300"],
                                      ["--n-periods 1e-300", "lag range of 0 samples"]),
    "signatures --g 1e308": (["signatures", "{files}/sim.nc", "--out", "{out}/s.nc", "--g", "1e308"], ["--g 1e+308", "lag range of 0"]),
    "signatures of a constant record": (["signatures", "{files}/const.nc", "--out", "{out}/s.nc", "--g", "1"], ["series 0", "constant"]),
    "signatures dt attribute 'abc'": (["signatures", "{files}/abc.nc", "--out", "{out}/s.nc", "--g", "1"], ["attribute dt 'abc'"]),
    "signatures --group-size 1e23 (as a float)": (["signatures", "{files}/sim.nc", "--out", "{out}/s.nc", "--group-size", "1e23"],
                                                  ["--group-size", "invalid int"]),
    "signatures --group-size 10**23": (["signatures", "{files}/sim.nc", "--out", "{out}/s.nc", "--group-size", str(10**23)],
                                       ["--group-size 100000000000000000000000", "more than the 4 series"]),
    "signatures --group-size 2**63": (["signatures", "{files}/sim.nc", "--out", "{out}/s.nc", "--group-size", str(2**63)],
                                      ["more than the 4 series"]),
    "signatures --group-size 5 of 4 series": (["signatures", "{files}/sim.nc", "--out", "{out}/s.nc", "--group-size", "5"],
                                              ["--group-size 5", "at most 4"]),
    "estimates --fit-points 10**20": (["estimates", "{files}/sig.nc", "--out", "{out}/e.nc", "--fit-points", str(10**20)],
                                      ["--fit-points 100000000000000000000", "more than the"]),
    "estimates --fit-points 1e20 (as a float)": (["estimates", "{files}/sig.nc", "--out", "{out}/e.nc", "--fit-points", "1e20"],
                                                 ["--fit-points", "invalid int"]),
    "unreachable tcp scheduler": (["--dask-scheduler", "tcp://127.0.0.1:9", "simulate", "--out", "{out}/o.nc", *FAST],
                                  ["cannot be reached", "tcp://127.0.0.1:9"]),
}


@pytest.fixture(scope="module")
def more_files(files):
    xr.Dataset({"theta": ("time", np.full(3000, 0.01))}, coords={"time": np.arange(3000) * 0.01}).to_netcdf(files / "const.nc")
    xr.Dataset({"theta": ("time", np.sin(np.arange(3000) * 0.1))}, attrs={"dt": "abc"}).to_netcdf(files / "abc.nc")
    return files


def _other_kind(name: str) -> str:
    if "1e8 seeds" in name:
        return "sizes"
    if "tcp" in name:
        return "engines"
    if "--out" in name:
        return "output paths"
    return "numbers" if "dt attribute" in name or "size" in name or "fit-points" in name else "wrong answers"


@pytest.mark.parametrize("argv, keywords", marked(OTHER_CASES, _other_kind))
def test_other_commands_refuse_in_one_sentence(more_files, tmp_path, capsys, argv, keywords):
    argv = [a.format(files=more_files, out=tmp_path) for a in argv]
    start = time.perf_counter()
    try:
        refused(argv, tmp_path, capsys, keywords)
    except SystemExit as exc:  # argparse refuses before the command runs
        assert exc.code == 2
    assert time.perf_counter() - start < 30


@hostile("engines", "refused")
def test_a_listener_that_is_not_dask_is_refused_at_once(tmp_path, capsys):
    import socket

    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen()
    port = server.getsockname()[1]

    def greet():
        conn, _ = server.accept()
        conn.sendall(b"SSH-2.0-OpenSSH_9.6\r\n")  # read as a frame length, this asks for exabytes
        time.sleep(2)
        conn.close()

    thread = threading.Thread(target=greet, daemon=True)
    thread.start()
    try:
        start = time.perf_counter()
        refused(["--dask-scheduler", f"tcp://127.0.0.1:{port}", "simulate", "--out", str(tmp_path / "o.nc"), *FAST], tmp_path, capsys,
                ["answers, but not as a Dask scheduler"])
        assert time.perf_counter() - start < 10
    finally:
        server.close()


@hostile("limits", "refused")
@pytest.mark.slow
def test_a_file_size_limit_is_one_sentence(tmp_path):
    script = (
        "import resource, sys; resource.setrlimit(resource.RLIMIT_FSIZE, (20000, 20000)); "
        "from rockdec.cli import main; "
        f"sys.exit(main(['simulate', '--out', {str(tmp_path / 'o.nc')!r}, '--dt', '0.0034', '--burn-in', '0', '--seeds', '0-9', '--n-points', '20000']))"
    )
    code, _, err = PYTHON_FORKS.script(script)  # a process of its own, with its own limit
    assert code == 2, err
    assert "ulimit -f" in err and "internal error" not in err
    assert list(tmp_path.iterdir()) == []


# --------------------------------------------------------------------------- answered, with the right note


@hostile("units", "answered")
def test_units_degrees_and_milliseconds_give_the_radian_second_answer(rocking, tiny_cache, tmp_path):
    theta, dt = rocking["theta"], rocking["dt"]
    cache = tiny_cache_copy(tiny_cache, tmp_path)
    _, plain, _ = _estimate([_nc(tmp_path / "rad.nc", theta, dt, theta_units="rad", time_units="s")], cache)
    _, deg, _ = _estimate([_nc(tmp_path / "deg.nc", np.degrees(theta), dt, theta_units="degrees")], cache)
    _, ms, _ = _estimate([_nc(tmp_path / "ms.nc", theta, dt * 1e3, time_units="ms")], cache)
    for other in (deg, ms):
        assert other["sigma_y"] == pytest.approx(plain["sigma_y"], rel=1e-9)
        assert other["dt"] == pytest.approx(plain["dt"], rel=1e-9)
        assert other["g"] == pytest.approx(plain["g"], rel=1e-6)
        assert other["e"] == pytest.approx(plain["e"], abs=1e-6)


@hostile("record files", "answered")
@pytest.mark.parametrize("sep", [";", "\t", " "], ids=["semicolon", "tab", "space"])
def test_csv_separators_give_the_comma_answer(rocking, tiny_cache, tmp_path, sep):
    path = tmp_path / "rec.csv"
    np.savetxt(path, np.c_[rocking["t"], rocking["theta"]], delimiter=sep, header=f"time{sep}theta", comments="", fmt="%.10g")
    cache = tiny_cache_copy(tiny_cache, tmp_path)
    _, comma, _ = _estimate([rocking["csv"]], cache)
    code, other, err = _estimate([path], cache)
    assert code == 0, err
    assert other["e"] == comma["e"] and other["interval"] == comma["interval"]


@hostile("wrong answers", "answered")
def test_a_given_g_near_the_records_own_is_used(rocking, tiny_cache, tmp_path):
    code, res, err = _estimate([rocking["csv"], "--g", "1.0"], tiny_cache_copy(tiny_cache, tmp_path))
    assert code == 0, err
    assert res["g"] == 1.0 and res["g_given"]


@hostile("wrong answers", "warned")
@pytest.mark.parametrize("g", ["0.7", "1.5"])
def test_a_given_g_off_the_records_own_within_the_factor_is_warned(rocking, tiny_calibration, tmp_path, g):
    """Issue 21: a given g was never compared with the record's own. Off by more than a
    factor 2 it is refused (above); within it, the report warns either that g lies outside
    the records' own calibrated interval or that the calibration gives none to check against."""
    code, res, err = _estimate([rocking["csv"], "--g", g], tmp_path / "cache")
    assert code == 0, err
    assert res["g"] == float(g) and res["g_given"]
    assert any(w.startswith(f"the given `g` {g}") for w in res["warnings"]), res["warnings"]


@hostile("wrong answers", "warned")
def test_a_null_e_always_carries_a_reason(rocking, tiny_calibration, tmp_path):
    drifting = rocking["theta"] * np.linspace(0.2, 3.0, rocking["theta"].size)
    path = tmp_path / "drift.csv"
    np.savetxt(path, np.c_[rocking["t"], drifting], delimiter=",", header="time,theta", comments="", fmt="%.10g")
    code, res, err = _estimate([path], tmp_path / "cache")
    assert code in (0, 2), err
    if code == 0:
        assert (res["e"] is None) == bool(res["reason"])
        if res["e"] is not None:  # answered: warned; declined (its model reads noise and a colour not ruled out): the reason
            assert any("not stationary" in w for w in res["warnings"])


@hostile("report", "answered")
def test_the_text_report_prints_when_g_is_given(rocking, tiny_cache, tmp_path, capsys):
    code = main(["estimate", str(rocking["csv"]), "--g", "1.0", "--cache", str(tiny_cache_copy(tiny_cache, tmp_path))])
    out = capsys.readouterr()
    assert code == 0, out.err
    assert "= 1 rad/s^2 (given;" in out.out


# --------------------------------------------------------------------------- the calibration cache


def _cached_file(cache):
    (path,) = cache.glob("calibration-*.nc")
    return path


@hostile("cache", "warned")
@pytest.mark.parametrize("damage", ["tampered value", "truncated", "settings edited", "checksum removed", "not NetCDF"])
def test_a_damaged_cache_file_is_rebuilt_with_a_note(rocking, tiny_cache, tmp_path, damage):
    """The module's calibration (:func:`tiny_cache`, built fresh) damaged in a copy: the
    rebuilt one gives the fresh one's answer."""
    cache = tiny_cache_copy(tiny_cache, tmp_path)
    fresh = tiny_cache["answer"]
    path = _cached_file(cache)
    if damage == "tampered value":
        with xr.open_dataset(path) as ds:
            ds = ds.load()
        ds["raw"][:] = ds["raw"].values * 0.97
        path.unlink()
        ds.to_netcdf(path)
    elif damage == "truncated":
        path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    elif damage in ("settings edited", "checksum removed"):
        with xr.open_dataset(path) as ds:
            ds = ds.load()
        if damage == "settings edited":
            ds.attrs["settings"] = ds.attrs["settings"].replace('"sets_per_e": 5', '"sets_per_e": 6')
        else:
            del ds.attrs["content_sha256"]
        path.unlink()
        ds.to_netcdf(path)
    else:
        path.write_text("hello")
    code, again, err = _estimate([rocking["csv"]], cache)
    assert code == 0, err
    assert again["calibration"]["cached"] is False
    assert any("was rebuilt" in w for w in again["warnings"])
    assert again["e"] == fresh["e"] and again["interval"] == fresh["interval"]
    _, third, _ = _estimate([rocking["csv"]], cache)
    assert third["calibration"]["cached"] is True and not any("rebuilt" in w for w in third["warnings"])


@hostile("concurrency", "answered")
def test_concurrent_builds_of_one_calibration_build_it_once(tmp_path, monkeypatch):
    built = []
    gate = threading.Event()

    def slow_build(settings):
        built.append(threading.get_ident())
        gate.wait(10)
        return xr.Dataset({"raw": (("e_true", "set", "name"), np.ones((2, 2, 1)))}, coords={"e_true": [0.5, 0.9]},
                          attrs={"settings": json.dumps(settings)})

    monkeypatch.setattr(calibration, "build", slow_build)
    monkeypatch.setattr(calibration, "POLL_S", 0.05)
    settings_ = {"lengths": [1000], "x": 1}
    results = []
    threads = [threading.Thread(target=lambda: results.append(calibration.load_or_build(settings_, tmp_path))) for _ in range(3)]
    for t in threads:
        t.start()
    time.sleep(0.5)
    gate.set()
    for t in threads:
        t.join(30)
    assert len(built) == 1
    assert sorted(cached for _, cached in results) == [False, True, True]
    assert sorted(p.name for p in tmp_path.iterdir()) == [f"calibration-{calibration.settings_hash(settings_)}.nc"]


@hostile("kills", "answered")
def test_a_build_lock_is_waited_for_while_fresh_and_taken_over_when_stale(tmp_path, monkeypatch):
    """The lock's liveness is its mtime (host and pid are for the reader): a lock from
    another node whose process is unknown here is still waited for while it is touched."""
    import os

    monkeypatch.setattr(calibration, "build", lambda s: xr.Dataset(
        {"raw": (("e_true", "set", "name"), np.ones((2, 2, 1)))}, coords={"e_true": [0.5, 0.9]}, attrs={"settings": json.dumps(s)}))
    settings_ = {"lengths": [1000], "y": 2}
    lock = tmp_path / f"calibration-{calibration.settings_hash(settings_)}.building"
    lock.write_text("host elsewhere pid 999999999 started 2026-01-01T00:00:00Z\n")
    notes = []
    assert calibration._take_lock(lock, notes) is False and lock.exists()  # fresh: another node's live build
    old = time.time() - calibration.STALE_S - 5
    os.utime(lock, (old, old))
    assert calibration._take_lock(lock, notes) is False and not lock.exists()
    assert "took over" in notes[0] and "host elsewhere" in notes[0]
    ds, cached = calibration.load_or_build(settings_, tmp_path)
    assert cached is False and not lock.exists()


# --------------------------------------------------------------------------- the plot


@hostile("concurrency", "refused")
def test_a_plot_claimed_by_a_running_estimate_is_refused_at_once(rocking, tmp_path, capsys):
    plot = tmp_path / "p.png"
    with io.claimed(plot):
        refused(["estimate", str(rocking["csv"]), "--plot", str(plot), "--cache", str(tmp_path / "c")], tmp_path, capsys,
                ["being written by another run"])


@hostile("output paths", "refused")
def test_a_plot_made_by_someone_else_during_the_calibration_is_kept_and_the_run_refuses(rocking, tiny_cache, tmp_path, monkeypatch):
    """Issue 21: ``--plot`` was checked only before the calibration, then written directly,
    replacing a file made meanwhile by a program that takes no lock."""
    plot = tmp_path / "p.png"
    real = estimation.estimate

    def meanwhile(*args, **kwargs):
        plot.write_bytes(b"made meanwhile")
        return real(*args, **kwargs)

    monkeypatch.setattr(estimation, "estimate", meanwhile)
    code, _, err = _estimate([rocking["csv"], "--plot", plot], tiny_cache_copy(tiny_cache, tmp_path))
    assert code == 2 and "appeared while this run wrote it" in err and "internal error" not in err, err
    assert plot.read_bytes() == b"made meanwhile"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cache", "p.png"]  # no lock, no partial file


@hostile("sizes", "refused")
@pytest.mark.parametrize("kind", ["npy", "csv"])
def test_a_50_million_sample_record_is_refused_up_front_with_its_estimate(rocking, tmp_path, capsys, monkeypatch, kind):
    """Issue 21: a 50-million-sample record hung. The refusal for time comes before the
    record is read (the header of a .npy, the size of a .csv), with the estimate in the
    sentence; the limit is set below that estimate, whatever the calibration costs."""
    from rockdec import cli

    monkeypatch.setattr(calibration, "E_GRID", FULL_CALIBRATION[0])
    monkeypatch.setattr(calibration, "SETS_PER_E", FULL_CALIBRATION[1])
    path = tmp_path / f"long.{kind}"
    if kind == "npy":
        with open(path, "wb") as handle:  # a header for 50 million float64 samples, then a hole
            np.lib.format.write_array_header_1_0(handle, {"descr": "<f8", "fortran_order": False, "shape": (50_000_000,)})
            handle.truncate(handle.tell() + 8 * 50_000_000)
    else:
        head = b"time,theta\n" + b"".join(f"{k * 0.01:.2f},{v:.8f}\n".encode() for k, v in enumerate(rocking["theta"][:4000]))
        _sparse(path, head, 50_000_000 * (len(head) // 4001))
    seconds, _ = estimation.cost(50_000_000, kind == "csv", False)
    monkeypatch.setattr(cli, "MAX_SECONDS", min(cli.MAX_SECONDS, seconds / 2))
    monkeypatch.setattr(checks, "available_memory", lambda: 2.0**50)  # the time refusal, whatever memory is free
    argv = ["estimate", str(path), "--cache", str(tmp_path / "c")] + (["--dt", "0.01"] if kind == "npy" else [])
    start = time.perf_counter()
    refused(argv, tmp_path, capsys, ["e+07 samples need about", "on 2 cores", "pass --yes", "records of 1e+06 samples"])
    assert time.perf_counter() - start < 10, "refused up front, not after reading the record"


@hostile("output paths", "answered")
def test_overwrite_replaces_a_symlinked_plot_not_its_target(rocking, tiny_cache, tmp_path):
    target = tmp_path / "precious.png"
    target.write_bytes(b"keep me")
    link = tmp_path / "p.png"
    link.symlink_to(target)
    code, _, err = _estimate([rocking["csv"], "--plot", link], tiny_cache_copy(tiny_cache, tmp_path))
    assert code == 2 and "exists already" in err
    code, _, err = _estimate([rocking["csv"], "--plot", link, "--overwrite"], tmp_path / "cache")
    assert code == 0, err
    assert target.read_bytes() == b"keep me" and not link.is_symlink() and link.stat().st_size > 10_000
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cache", "p.png", "precious.png"]


@hostile("sizes", "answered")
def test_a_long_record_is_calibrated_on_shorter_records_with_its_spread_scaled(rocking, tiny_calibration, tmp_path, monkeypatch):
    monkeypatch.setattr(calibration, "LENGTH_CAP", 10_000)  # the rocking record has 20,000
    monkeypatch.setattr(calibration, "E_GRID_LONG", calibration.E_GRID)  # tiny_calibration's grid
    code, res, err = _estimate([rocking["csv"]], tmp_path / "cache")
    assert code == 0, err
    assert res["calibration"]["simulated_samples"] == 10_000
    assert res["calibration"]["spread_scale"] == pytest.approx(math.sqrt(0.5))
    assert "calibrated on simulated records of 10000 samples" in err


@hostile("sizes", "refused")
def test_a_40_million_sample_record_is_refused_with_its_time_unless_yes(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(calibration, "E_GRID", FULL_CALIBRATION[0])
    monkeypatch.setattr(calibration, "SETS_PER_E", FULL_CALIBRATION[1])
    monkeypatch.setattr(calibration, "LENGTH_CAP", 10**12)  # a calibration as long as the record: the refusal's path
    path = tmp_path / "long.npy"
    with open(path, "wb") as handle:  # a header for 40 million float64 samples, then a hole
        np.lib.format.write_array_header_1_0(handle, {"descr": "<f8", "fortran_order": False, "shape": (40_000_000,)})
        handle.truncate(handle.tell() + 8 * 40_000_000)
    seconds, _ = estimation.cost(40_000_000, False, False)
    assert seconds > 600
    refused(["estimate", str(path), "--dt", "0.01", "--cache", str(tmp_path / "c")], tmp_path, capsys, ["4e+07 samples", "min", "--yes"])


ESTIMATE_PROCESS = """
import json, sys
from rockdec.calibrate import calibration
calibration.E_GRID = (0.5, 0.65, 0.75, 0.85, 0.92, 0.97)
calibration.SETS_PER_E = calibration.SETS_PER_E_CAPPED = 5
calibration.POLL_S = 0.05  # the waiting process reads the stored file within 0.05 s of its writing, not 1 s
from rockdec.cli import main
sys.exit(main(["estimate", sys.argv[1], "--json", "--cache", sys.argv[2]]))
"""


@hostile("concurrency", "answered")
@pytest.mark.slow
def test_two_concurrent_estimates_on_one_record_build_one_calibration(rocking, tmp_path):
    """Issue 19: two processes, same settings; the second waits for the first's build."""
    cache = tmp_path / "cache"
    procs = [PYTHON_FORKS.start_script(ESTIMATE_PROCESS, rocking["csv"], cache, output=tmp_path / f"process-{i}") for i in range(2)]
    outs = [p.communicate(timeout=300) for p in procs]
    assert [p.returncode for p in procs] == [0, 0], [err for _, err in outs]
    results = [json.loads(out) for out, _ in outs]
    assert sorted(r["calibration"]["cached"] for r in results) == [False, True]
    assert results[0]["e"] == results[1]["e"] and results[0]["interval"] == results[1]["interval"]
    assert [p.name for p in cache.iterdir()] == [results[0]["calibration"]["file"]]


@hostile("units", "answered")
def test_signatures_read_degrees_and_milliseconds_as_rad_and_s(rocking, tmp_path):
    theta, dt = rocking["theta"], rocking["dt"]
    files = {
        "rad": _nc(tmp_path / "rad.nc", theta, dt, theta_units="rad", time_units="s"),
        "deg": _nc(tmp_path / "deg.nc", np.degrees(theta), dt, theta_units="degree"),
        "ms": _nc(tmp_path / "ms.nc", theta, dt * 1e3, time_units="ms"),
    }
    cubes = {}
    for name, path in files.items():
        out = tmp_path / f"{name}_sig.nc"
        assert main(["signatures", str(path), "--out", str(out), "--g", "1"]) == 0
        with xr.open_dataset(out) as ds:
            cubes[name] = ds["free_response"].values
    np.testing.assert_allclose(cubes["deg"], cubes["rad"], rtol=1e-9, equal_nan=True)
    np.testing.assert_allclose(cubes["ms"], cubes["rad"], rtol=1e-9, equal_nan=True)


@hostile("engines", "answered")
def test_a_running_dask_scheduler_passes_the_probe(tmp_path):
    from dask.distributed import LocalCluster

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, protocol="tcp", dashboard_address=":0") as cluster:
        argv = ["--dask-scheduler", cluster.scheduler_address, "simulate", "--out", str(tmp_path / "o.nc"), *FAST]
        assert main(argv) == 0
    with xr.open_dataset(tmp_path / "o.nc") as ds:
        assert np.isfinite(ds["theta"].values).all()

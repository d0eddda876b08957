"""Hostile input: every failure a user can cause is one sentence naming the value and the
fix, exit code 2, no file written, no traceback; no entry point hangs or returns a silent
non-finite number (issue 13). Record time axes are checked in the records tests.
"""

from __future__ import annotations

import errno
import math
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

from rockdec import estimators, fixed_step, housner, io, run, signatures, simulate
from rockdec import validate as checks
from rockdec.cli import main

ROOT = Path(__file__).resolve().parents[1]
#: A fast simulate call: an explicit step and no burn-in skip the calibration.
FAST = ["--dt", "0.0034", "--burn-in", "0", "--seeds", "0", "--n-points", "50"]


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


@pytest.mark.parametrize("extra, keywords", SIMULATE_CASES.values(), ids=SIMULATE_CASES.keys())
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


@pytest.mark.parametrize("extra, keywords", SIGNATURE_CASES.values(), ids=SIGNATURE_CASES.keys())
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


@pytest.mark.parametrize("argv, keywords", FILE_CASES.values(), ids=FILE_CASES.keys())
def test_files_are_refused(files, tmp_path, capsys, argv, keywords):
    argv = [a.format(files=files, out=tmp_path) for a in argv]
    if "--out" not in argv:
        argv += ["--out", str(tmp_path / "o.nc")]
    refused(argv, tmp_path, capsys, keywords)
    assert sorted(p.name for p in files.iterdir()) == ["notes.txt", "sig.nc", "sim.nc"]


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

    monkeypatch.setattr(run, "calibrate", broken)
    argv = ["simulate", "--out", str(tmp_path / "o.nc"), *FAST]
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "internal error" in err and "--debug" in err
    assert main(["--debug", *argv]) == 1
    assert "Traceback" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_disk_full_is_one_sentence_and_leaves_nothing(tmp_path, capsys, monkeypatch):
    def full(self, path, *args, **kwargs):
        Path(path).write_bytes(b"\0" * 100)  # a partial file, as a real write leaves
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(xr.Dataset, "to_netcdf", full)
    refused(["simulate", "--out", str(tmp_path / "o.nc"), *FAST], tmp_path, capsys, ["no space left", "o.nc", "--out"])


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


def test_concurrent_runs_on_one_output_refuse_and_on_two_do_not_interfere(tmp_path):
    out, other, go = tmp_path / "a.nc", tmp_path / "b.nc", tmp_path / "go"
    proc = subprocess.Popen([sys.executable, "-c", WRITER, str(out), str(go)], stderr=subprocess.PIPE, text=True)
    try:
        lock = tmp_path / ".a.nc.lock"
        end = time.time() + 60
        while not lock.exists() and time.time() < end:
            time.sleep(0.01)
        assert lock.exists(), "the first writer never claimed its output"
        ds = xr.Dataset({"y": ("i", np.ones(10))})
        with pytest.raises(io.OutputError, match="being written by another run"):
            io.write_netcdf(ds, out)
        with pytest.raises(io.OutputError, match="being written by another run"):
            io.check_output(out)  # refused before any work too
        io.write_netcdf(ds, other)  # another output, meanwhile: no interference
        partials = list(tmp_path.glob(".a.nc.*.partial"))
        assert len(partials) == 1  # the first run's own temporary file survived
    finally:
        go.touch()
        assert proc.wait(timeout=120) == 0, proc.stderr.read()
    with xr.open_dataset(out) as a, xr.open_dataset(other) as b:
        assert a["x"].values.tolist() == list(range(1000)) and b["y"].values.tolist() == [1.0] * 10
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.nc", "b.nc", "go"]


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
TIME_BOUND = 5.0  # s, per call (the kernels are compiled by then; the sizes are small)


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


@FUZZ
@given(name=st.sampled_from(sorted(SIM)), value=ANY_FLOAT, grid=st.booleans())
def test_simulate_block_gives_finite_series_or_refuses(name, value, grid):
    kw = {**SIM, name: value}
    finite_or_refused(bounded(simulate.simulate_block, [0, 1], 60, burn_in=20, grid_impacts=grid, **kw))


HOUSNER = dict(dt=0.0034, nu=2.0, theta_cr=0.25, e=0.95, sigma_p=0.003, theta0=0.001, theta_dot0=0.0)


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
    assert time.perf_counter() - start < 20 * TIME_BOUND
    if code == 0:
        with xr.open_dataset(out) as ds:
            assert np.isfinite(ds["theta"].values).all() and np.isfinite(ds["theta_dot"].values).all()
    else:
        assert code == 2 and list(folder.iterdir()) == []

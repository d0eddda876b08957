"""Hostile cases of round 4: estimate documents read back with impossible fields, outputs
that are their own input, internal errors (.mat fields, cache and seed types, a full disk
while claiming an output) turned into one sentence, time axes printed with few digits or
stored as float32, a bad ``$ROCKDEC_CACHE``, and the time axis of a simulated record."""

from __future__ import annotations

import errno
import hashlib
import json
import os
import pathlib
from pathlib import Path

import matplotlib
import numpy as np
import pytest
import scipy.io
import xarray as xr

import fake_calibration
import rockdec
from rockdec.calibrate import calibration
from rockdec.cli import main
from rockdec.report.result import RestitutionEstimate
from rockdec.validate import InputError
from test_hostile import FAST, files, hostile, marked, refused  # noqa: F401  (files: the module's fixture)

matplotlib.use("Agg")

#: The sampling step of the records whose time columns are printed with few digits: 1/300 s,
#: which no decimal prints exactly.
STEP = 1.0 / 300.0


def one_sentence(message: str) -> bool:
    """A refusal in one sentence: one line, ending in a full stop, no traceback."""
    return "\n" not in message and message.endswith(".") and "Traceback" not in message


def sha(path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


@pytest.fixture(scope="module")
def fake_calibrations():
    """Every calibration of the module without simulation (tests/fake_calibration.py)."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(calibration, "_grid_point", fake_calibration.grid_point)
        yield


@pytest.fixture(scope="module")
def record(tmp_path_factory):
    """A simulated record (e = 0.85, 20,000 samples) as NetCDF, written by the command line."""
    folder = tmp_path_factory.mktemp("record")
    assert main(["-q", "simulate", "--e", "0.85", "--seeds", "1", "--n-points", "20000", "--out", str(folder / "r.nc")]) == 0
    return folder / "r.nc"


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("calibrations")


@pytest.fixture(scope="module")
def random_result(record, cache, fake_calibrations):
    """A real estimate of the random test (its calibration made without simulation)."""
    return rockdec.estimate(rockdec.read_record(record), cache=cache)


@pytest.fixture(scope="module")
def free_result():
    """A real estimate of the free-rocking test (e = 0.85, released from 0.02 rad)."""
    theta = rockdec.simulate(0.85, 2_500, seed=0, sigma_p=0.0, theta0=0.02)
    return rockdec.free_rocking(theta + 2e-4 * np.random.default_rng(1).standard_normal(theta.size))


# --------------------------------------------------------------------------- 1. documents read back


def _below_interval(doc):
    return doc["interval"][0] / 2


#: name -> (test, the fields changed (a value, or a function of the document), words of the refusal)
DOCUMENT_CASES = {
    "e outside its interval": ("random", {"e": _below_interval}, ["`doc` e", "outside its interval"]),
    "e outside its interval (free)": ("free", {"e": _below_interval}, ["`doc` e", "outside its interval"]),
    "interval reversed": ("random", {"interval": lambda doc: doc["interval"][::-1]}, ["`doc` interval", "reversed", "low <= high"]),
    "interval of three": ("random", {"interval": [0.1, 0.5, 0.9]}, ["`doc` interval", "pair [low, high]"]),
    "e NaN": ("random", {"e": float("nan")}, ["`doc` e nan", "not a finite number", "null or a number in [0, 1]"]),
    "e NaN (free)": ("free", {"e": float("nan")}, ["`doc` e nan", "not a finite number"]),
    "e 1.7": ("random", {"e": 1.7, "interval": [1.6, 1.8]}, ["`doc` e 1.7", "outside [0, 1]"]),
    "e as text": ("random", {"e": "0.85"}, ["`doc` e '0.85'", "not a number"]),
    "schema_version 99": ("random", {"schema_version": 99}, ["`doc` schema_version 99", "'1.0'"]),
    "schema_version '2.0'": ("free", {"schema_version": "2.0"}, ["`doc` schema_version '2.0'", "'1.0'"]),
    "warnings a string (one warning a character)": ("random", {"warnings": "check the sensor"}, ["`doc` warnings", "not a list of strings"]),
    "warnings of numbers": ("free", {"warnings": [1, 2]}, ["`doc` warnings", "not a list of strings"]),
    "more codes than warnings": ("random", {"warnings": [], "warning_codes": ["drift"]}, ["1 warning_codes for 0 warnings"]),
    "not a dict": ("random", {None: "a list"}, ["`doc` is a list", "not an estimate's JSON document"]),
}


@pytest.mark.parametrize("test, changes, words", marked(
    DOCUMENT_CASES, lambda name: "numbers" if name.startswith(("e ", "interval")) else "report"))
def test_a_document_with_impossible_fields_is_refused_in_one_sentence(random_result, free_result, test, changes, words):
    doc = json.loads(json.dumps((random_result if test == "random" else free_result).to_dict()))
    if None in changes:
        doc = [doc]
    else:
        doc.update({key: value(doc) if callable(value) else value for key, value in changes.items()})
    with pytest.raises(InputError) as info:
        RestitutionEstimate.from_dict(doc)
    message = str(info.value)
    assert one_sentence(message), message
    for word in words:
        assert word in message, (word, message)


@hostile("report", "answered")
@pytest.mark.parametrize("test", ["random", "free"])
def test_real_documents_round_trip_and_a_declined_one_stays_readable(random_result, free_result, test):
    res = random_result if test == "random" else free_result
    assert res.e is not None and res.confidence_interval.low <= res.e <= res.confidence_interval.high
    doc = json.loads(json.dumps(res.to_dict()))
    assert RestitutionEstimate.from_dict(doc).to_dict() == res.to_dict()
    reason = "the records show a defect that moves e by more than its interval"
    declined = RestitutionEstimate.from_dict({**doc, "e": None, "interval": [None, None], "coverage": None, "estimator": None,
                                             "reason": reason})
    assert declined.e is None and declined.reason == reason and "e=None" in repr(declined)
    assert declined.summary()  # prints
    assert declined.warnings == res.warnings  # each warning whole, not a character each


# --------------------------------------------------------------------------- 2. an output that is its own input


def _spellings(files: Path, tmp: Path, source: str) -> dict:
    """name -> the --out that reaches ``files/source`` (made in ``tmp``), and the input given."""
    (tmp / "sub").mkdir()
    (tmp / "folder").symlink_to(files)
    (tmp / "link.nc").symlink_to(files / source)
    os.link(files / source, tmp / "hard.nc")
    return {
        "the same name": (files / source, files / source),
        "through .. and .": (f"{tmp}/sub/../../{files.name}/./{source}" if tmp.parent == files.parent
                             else f"{files}/../{files.name}/./{source}", files / source),
        "relative and absolute": (os.path.relpath(files / source), files / source),
        "through a symlinked folder": (tmp / "folder" / source, files / source),
        "a symlink to the input": (tmp / "link.nc", files / source),
        "the input given by a symlink": (files / source, tmp / "link.nc"),
        "a hard link": (tmp / "hard.nc", files / source),
    }


SPELLINGS = ["the same name", "through .. and .", "relative and absolute", "through a symlinked folder", "a symlink to the input",
             "the input given by a symlink", "a hard link"]


@pytest.mark.parametrize("overwrite", [True, False], ids=["--overwrite", "no --overwrite"])
@pytest.mark.parametrize("command, source", [("signatures", "sim.nc"), ("estimates", "sig.nc")])
@pytest.mark.parametrize("spelling", marked({name: (name,) for name in SPELLINGS}, "output paths"))
def test_an_output_that_is_the_input_is_refused(files, tmp_path, capsys, monkeypatch, command, source, spelling, overwrite):
    monkeypatch.chdir(tmp_path)
    out, given = _spellings(files, tmp_path, source)[spelling]
    before = sha(files / source)
    err = refused([command, str(given), "--out", str(out)] + (["--overwrite"] if overwrite else []), tmp_path, capsys,
                  ["--out", "is the input", "a file name of its own"])
    assert "exists already" not in err
    assert sha(files / source) == before and sorted(p.name for p in files.iterdir()) == ["notes.txt", "sig.nc", "sim.nc"]


# --------------------------------------------------------------------------- 3. internal errors


def _cell(value):
    cell = np.empty((1, 1), dtype=object)
    cell[0, 0] = value
    return cell


#: name -> (the .mat file's variables besides theta (a function of theta), words of the refusal)
MAT_CASES = {
    "fs 0 (ZeroDivisionError)": (lambda th: {"fs": 0.0}, ["'fs' is 0", "positive, finite number of Hz", "--fs"]),
    "fs inf": (lambda th: {"fs": np.inf}, ["'fs' is inf"]),
    "dt 'abc' (ValueError)": (lambda th: {"dt": "abc"}, ["'dt' holds text", "not one number", "--dt"]),
    "dt negative": (lambda th: {"dt": -0.01}, ["'dt' is -0.01", "> 0"]),
    "dt a 1x1 cell (TypeError)": (lambda th: {"dt": _cell(0.01)}, ["'dt' holds a cell array", "not one number"]),
    "fs a 1x1 cell (TypeError)": (lambda th: {"fs": _cell(100.0)}, ["'fs' holds a cell array"]),
    "dt of two values (read as none)": (lambda th: {"dt": np.array([0.01, 0.02])}, ["'dt' holds 2 values", "not one number"]),
    "theta a 1x1 cell": (lambda th: {"theta": _cell(th)}, ["'theta' holds a cell array of size 1x1", "theta = theta{1}"]),
    "time a 1x1 cell": (lambda th: {"time": _cell(np.arange(th.size) * 0.01)}, ["'time' holds a cell array", "time = time{1}"]),
    "theta complex": (lambda th: {"theta": th + 1j}, ["'theta' holds complex values", "real numbers"]),
}


@pytest.mark.parametrize("fields, words", marked(MAT_CASES, "record files"))
def test_a_mat_record_with_a_bad_field_is_refused_in_one_sentence(tmp_path, capsys, fields, words):
    theta = 0.01 * np.sin(np.arange(3000) * 0.05)
    path = tmp_path / "rec.mat"
    scipy.io.savemat(path, {"theta": theta, **fields(theta)})
    refused(["estimate", str(path), "--cache", str(tmp_path / "c")], tmp_path, capsys, ["rec.mat", *words])


CACHE_CASES = {
    "bytes (TypeError)": (b"/tmp/calibrations", ["`cache` of type bytes", "str or pathlib.Path", "os.fsdecode"]),
    "an int (TypeError)": (123, ["`cache` of type int", "str or pathlib.Path"]),
    "a list": (["a", "b"], ["`cache` of type list"]),
}


@pytest.mark.parametrize("value, words", marked(CACHE_CASES, "cache"))
def test_a_cache_that_is_not_a_folder_name_is_refused_before_the_record(value, words):
    with pytest.raises(InputError) as info:
        rockdec.estimate(np.zeros(10), dt=0.01, cache=value)  # the record would be refused too: the cache first
    assert one_sentence(str(info.value)) and all(word in str(info.value) for word in words), str(info.value)


SEED_CASES = {
    "2**70 (OverflowError)": (2**70, ["seed 1.18e+21", "beyond 2**63 - 1"]),
    "2**63": (2**63, ["seed 9223372036854775808", "beyond 2**63 - 1"]),
    "one of a list beyond uint64": ([0, 2**64], ["seed 18446744073709551616", "beyond"]),
    "a uint64 beyond int64": (np.array([2**63 + 5], dtype=np.uint64), ["seed 9223372036854775813", "beyond"]),
    "negative": (-1, ["seed -1", "negative"]),
    "1.5 (read as 1)": (1.5, ["seed 1.5", "not a whole number"]),
    "True (read as 1)": (True, ["seed True", "not a whole number"]),
    "text (ValueError)": ("a", ["seed 'a'", "not a whole number"]),
    "a table (a dask error)": ([[1, 2]], ["seeds of shape (1, 2)", "a whole number or a list"]),
}


@pytest.mark.parametrize("seed, words", marked(SEED_CASES, "numbers"))
def test_a_seed_that_is_not_an_int64_is_refused_in_one_sentence(seed, words):
    with pytest.raises(InputError) as info:
        rockdec.simulate(0.85, 1000, seed=seed)
    assert one_sentence(str(info.value)) and all(word in str(info.value) for word in words), str(info.value)


@hostile("numbers", "answered")
def test_seeds_at_the_ends_of_their_range_are_simulated():
    theta = rockdec.simulate(0.85, 1000, seed=[0, 2**63 - 1], dt=0.0034, burn_in=0)
    assert list(theta["seed"].values) == [0, 2**63 - 1] and np.isfinite(theta.values).all()


def _lock_disk_full(monkeypatch):
    """The disk fills as the run writes its lock's own file (its process id)."""
    real = pathlib.Path.write_text

    def write_text(self, *args, **kwargs):
        if ".lock." in self.name:
            self.write_bytes(b"1")  # a partial write, as a real one leaves
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(self, *args, **kwargs)

    monkeypatch.setattr(pathlib.Path, "write_text", write_text)


def _plot_disk_full(monkeypatch):
    """The disk fills as the figure is written into its temporary file."""
    from matplotlib.figure import Figure

    def savefig(self, fname, *args, **kwargs):
        Path(fname).write_bytes(b"\0" * 100)
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(Figure, "savefig", savefig)


@hostile("limits", "refused")
@pytest.mark.parametrize("overwrite", [True, False], ids=["--overwrite", "new plot"])
@pytest.mark.parametrize("where", ["lock", "plot"])
def test_a_full_disk_under_estimate_plot_is_one_sentence_and_leaves_no_partial_file(
        record, cache, fake_calibrations, tmp_path, capsys, monkeypatch, where, overwrite):
    plot = tmp_path / "p.png"
    if overwrite:
        plot.write_bytes(b"the plot of the last run")
    {"lock": _lock_disk_full, "plot": _plot_disk_full}[where](monkeypatch)
    refused(["estimate", str(record), "--plot", str(plot), "--cache", str(cache)] + (["--overwrite"] if overwrite else []),
            tmp_path, capsys, ["no space left on the disk of", "p.png", "free some space"])
    assert not overwrite or plot.read_bytes() == b"the plot of the last run"


@hostile("limits", "refused")
def test_a_full_disk_as_simulate_claims_its_output_is_one_sentence(tmp_path, capsys, monkeypatch):
    _lock_disk_full(monkeypatch)
    refused(["simulate", "--out", str(tmp_path / "o.nc"), *FAST], tmp_path, capsys, ["no space left", "o.nc"])


# --------------------------------------------------------------------------- 4. time axes


def _write_csv(path: Path, t, theta, fmt: str) -> Path:
    lines = ["time,theta"] + [f"{fmt % a},{b:.8g}" for a, b in zip(t, theta)]
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture(scope="module")
def angles():
    """A rocking record of 3000 samples at STEP (its samples only: the tests here read time axes)."""
    return rockdec.simulate(0.85, 3000, seed=2, dt=STEP).values


def _times(case: str) -> tuple:
    """The time column of ``case`` and how it is printed."""
    k = np.arange(3000)
    t = k * STEP
    if case == "printed %.3f":
        return t, "%.3f"
    if case == "printed %.4f":
        return t, "%.4f"
    if case == "printed %.5g":
        return t, "%.5g"
    late = t + 1000.0  # a clock started earlier: the float32 spacing at 1000 s is 6e-5 s, 2 % of the step
    if case == "float32, printed as float32":
        return [str(v) for v in late.astype(np.float32)], "%s"
    if case == "float32, printed in full":
        return late.astype(np.float32).astype(np.float64), "%.17g"
    raise KeyError(case)


#: The most each time of a case is off its uniform axis: half its last digit (%.5g: 4 decimals
#: from 1 s on), the float32 spacing at 1010 s (half for the rounding, half for its shortest form).
ROUNDING = {"printed %.3f": 5e-4, "printed %.4f": 5e-5, "printed %.5g": 5e-5, "float32, printed as float32": 2**-14,
            "float32, printed in full": 2**-15}
UNIFORM_CASES = list(ROUNDING)


@pytest.mark.parametrize("case", marked({name: (name,) for name in UNIFORM_CASES}, "units", "answered"))
def test_a_time_column_uniform_within_its_printed_digits_is_read_at_its_fitted_step(angles, tmp_path, case):
    t, fmt = _times(case)
    path = _write_csv(tmp_path / "rec.csv", t, angles, fmt)
    theta = rockdec.read_record(path)
    # the least-squares step of n times each rounded by at most r errs by at most
    # r * sum|k - mean k| / sum (k - mean k)^2 < 3 r / n
    n, r = theta.sizes["time"], ROUNDING[case]
    assert abs(theta.attrs["dt"] - STEP) < 3 * r / n
    assert theta.sizes["time"] == 3000


@hostile("units", "answered")
def test_a_float32_netcdf_time_coordinate_is_read_at_its_fitted_step(angles, tmp_path):
    path = tmp_path / "rec.nc"
    t = (np.arange(angles.size) * STEP + 1000.0).astype(np.float32)  # float32 spacing 6e-5 s at 1000 s
    xr.Dataset({"theta": ("time", angles)}, coords={"time": ("time", t, {"units": "s"})}).to_netcdf(path)
    assert abs(rockdec.read_record(path).attrs["dt"] - STEP) < 3 * 2**-15 / angles.size  # half the spacing at 1010 s


def _bad_times(case: str):
    t = np.arange(3000) * STEP
    if case == "a sample missing":
        t[1500:] += STEP
    elif case == "jitter of a third of the step":
        t = t + np.random.default_rng(0).uniform(-STEP / 6, STEP / 6, t.size)
    elif case == "a step of 1.2 ms printed %.3f":
        t = np.arange(3000) * 0.0012
    elif case == "NaN":
        t[10] = np.nan
    elif case == "decreasing":
        t[10] = t[8]
    return t


#: name -> (how the times are printed, words of the refusal)
NON_UNIFORM_CASES = {
    "a sample missing": ("%.3f", ["not uniformly sampled", "at sample 1500", "resample the record",
                                  "drop the time axis and give the step as --dt (s) or --fs (Hz)"]),
    "jitter of a third of the step": ("%.5f", ["not uniformly sampled", "resample the record", "--dt"]),
    "a step of 1.2 ms printed %.3f": ("%.3f", ["too coarse to tell a missing sample", "write the times with more digits", "--dt"]),
    "NaN": ("%.6f", ["time value 10 is nan", "finite number of seconds"]),
    "decreasing": ("%.6f", ["time goes back at sample 10", "sort the record"]),
}


@pytest.mark.parametrize("case", marked({name: (name,) for name in NON_UNIFORM_CASES}, "units"))
def test_a_time_column_that_is_not_uniform_is_refused_saying_what_to_do(angles, tmp_path, capsys, case):
    fmt, words = NON_UNIFORM_CASES[case]
    folder = tmp_path / "in"
    folder.mkdir()
    path = _write_csv(folder / "rec.csv", _bad_times(case), angles, fmt)
    refused(["estimate", str(path), "--cache", str(tmp_path / "c")], folder, capsys, words)


@hostile("cache", "refused")
@pytest.mark.parametrize("where", ["a file", "under a file"])
def test_a_bad_rockdec_cache_variable_is_named_not_cache(record, tmp_path, capsys, monkeypatch, where):
    blocker = tmp_path / "blocker"
    blocker.write_text("x")
    monkeypatch.setenv("ROCKDEC_CACHE", str(blocker if where == "a file" else blocker / "calibrations"))
    err = refused(["estimate", str(record)], tmp_path, capsys, ["$ROCKDEC_CACHE", str(blocker), "set ROCKDEC_CACHE", "or unset it"])
    assert "--cache" not in err
    with pytest.raises(InputError, match=r"^\$ROCKDEC_CACHE"):
        rockdec.estimate(np.zeros(10), dt=0.01)
    assert blocker.read_text() == "x"


# --------------------------------------------------------------------------- 5. the time axis of a simulated record


@hostile("report", "answered")
@pytest.mark.parametrize("seed", [1, [1, 2]], ids=["one series", "two series"])
def test_a_plot_of_a_simulated_record_labels_its_time_in_seconds(seed):
    import matplotlib.pyplot as plt

    theta = rockdec.simulate(0.85, 2000, seed=seed)
    assert theta["time"].attrs["units"] == "s" and "calendar" not in theta["time"].attrs  # no reference date
    fig, ax = plt.subplots()
    try:
        (theta if np.ndim(seed) == 0 else theta.isel(seed=0)).plot(ax=ax)
        label = ax.get_xlabel()
    finally:
        plt.close(fig)
    assert label.replace("\n", " ") == "time since the end of the burn-in [s]"

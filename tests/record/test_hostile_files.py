"""Hostile record files (issue 38): a FIFO or device given as a record, a ``.npz`` named
``.npy``, a CSV with a byte-order mark, NetCDF times in any CF unit of time (with or without
a reference date), a record whose scale leaves the floats' square range. Each is read right
or refused in one sentence before anything blocks."""

from __future__ import annotations

import os
import threading
import time

import numpy as np
import pandas as pd
import pytest
import xarray as xr

from rockdec import io
from rockdec.record import records
from rockdec.timeaxis import RecordError

hostile = pytest.mark.hostile


@pytest.fixture(scope="module")
def rocking():
    """A rocking-like record: 3,000 samples at 0.0034 s, a few rocking cycles of varying height."""
    rng = np.random.default_rng(3)
    k = np.arange(3000)
    theta = 0.002 * np.sin(0.08 * k) * (1 + 0.5 * np.sin(0.003 * k)) + 1e-5 * rng.standard_normal(k.size)
    return theta, 0.0034


def _csv_text(theta, dt, sep=","):
    return f"time{sep}theta\n" + "".join(f"{i * dt:.6f}{sep}{v:.10g}\n" for i, v in enumerate(theta))


def _one_sentence(exc: Exception, *words):
    text = str(exc)
    assert "\n" not in text and text.endswith(".") and text.count(". ") == 0, text
    for word in words:
        assert word in text, (word, text)


def _within(seconds, func, *args, **kwargs):
    """``func(*args)`` in a thread: its result or exception, and fail if it is still running after ``seconds``."""
    out = {}

    def target():
        try:
            out["value"] = func(*args, **kwargs)
        except Exception as exc:  # noqa: BLE001 -- returned to the test
            out["error"] = exc

    thread = threading.Thread(target=target, daemon=True)
    thread.start()
    thread.join(seconds)
    assert not thread.is_alive(), f"{func.__name__} still running after {seconds} s (blocked)"
    return out


@hostile("record files", "refused")
@pytest.mark.parametrize("suffix", [".csv", ".nc", ".npy", ".txt"])
def test_a_fifo_is_refused_before_open_blocks(tmp_path, suffix):
    fifo = tmp_path / f"pipe{suffix}"
    os.mkfifo(fifo)
    out = _within(10, records.read_records, fifo, dt=0.01 if suffix == ".npy" else None)
    assert isinstance(out.get("error"), RecordError), out
    _one_sentence(out["error"], "FIFO", "not a regular file")
    assert _within(10, records.record_size, fifo)["value"] == 0
    out = _within(10, io.open_dataset, fifo)
    assert isinstance(out.get("error"), io.OutputError) and "FIFO" in str(out["error"]), out


@hostile("record files", "refused")
def test_a_character_device_is_refused(tmp_path):
    with pytest.raises(RecordError) as info:
        records.read_records("/dev/zero", dt=0.01)
    _one_sentence(info.value, "character device")


@hostile("record files", "refused")
@pytest.mark.parametrize("content", ["npz", "text", "pickle"])
def test_a_file_named_npy_that_is_not_one_is_refused_in_one_sentence(tmp_path, rocking, content):
    path = tmp_path / "rec.npy"
    if content == "npz":
        np.savez(tmp_path / "rec", theta=rocking[0])
        os.replace(tmp_path / "rec.npz", path)
    elif content == "text":
        path.write_text(_csv_text(*rocking))
    else:
        np.save(path, np.array([rocking[0], None], dtype=object), allow_pickle=True)
    with pytest.raises(RecordError) as info:
        records.read_records(path, dt=0.01)
    _one_sentence(info.value, str(path))
    if content == "npz":
        assert ".npz archive" in str(info.value)
    assert records.record_size(path) == 0


@hostile("record files", "answered")
@pytest.mark.parametrize("sep", [",", ";", "\t"], ids=["comma", "semicolon", "tab"])
@pytest.mark.parametrize("plain", [True, False], ids=["numbers", "with a blank cell"])
def test_a_csv_with_a_byte_order_mark_reads_as_without(tmp_path, rocking, sep, plain):
    theta, dt = rocking
    text = _csv_text(theta, dt, sep)
    if not plain:  # a gap: read by pandas, not NumPy
        lines = text.splitlines(keepends=True)
        lines[10] = lines[10].split(sep)[0] + sep + "\n"
        text = "".join(lines)
    (tmp_path / "plain.csv").write_text(text)
    (tmp_path / "bom.csv").write_bytes(b"\xef\xbb\xbf" + text.encode())
    (bom,) = records.read_records(tmp_path / "bom.csv")
    (ref,) = records.read_records(tmp_path / "plain.csv")
    assert bom.dt == ref.dt == pytest.approx(dt, rel=1e-6)
    np.testing.assert_array_equal(bom.theta, ref.theta)


@hostile("units", "answered")
@pytest.mark.parametrize(
    "unit, seconds",
    [("nanoseconds", 1e-9), ("microseconds", 1e-6), ("milliseconds", 1e-3), ("seconds", 1.0), ("minutes", 60.0),
     ("hours", 3600.0), ("days", 86400.0)],
)
@pytest.mark.parametrize("since", [" since 2020-01-01 00:00:00", ""], ids=["since a date", "no date"])
def test_netcdf_time_in_any_unit_gives_the_step_in_seconds(tmp_path, rocking, unit, seconds, since):
    theta, dt = rocking
    stamps = np.arange(theta.size) * dt / seconds
    if unit == "nanoseconds":
        stamps = np.round(stamps).astype(np.int64)
    path = tmp_path / "t.nc"
    xr.Dataset({"theta": ("time", theta)}, coords={"time": ("time", stamps, {"units": unit + since})}).to_netcdf(path)
    (rec,) = records.read_records(path)
    assert rec.dt == pytest.approx(dt, rel=1e-9)


@hostile("units", "answered")
def test_netcdf_of_datetimes_as_xarray_writes_them(tmp_path, rocking):
    theta, dt = rocking
    stamps = pd.Timestamp("2024-05-01 12:00") + pd.to_timedelta(np.arange(theta.size) * dt, unit="s")
    path = tmp_path / "dt64.nc"
    xr.Dataset({"theta": ("time", theta)}, coords={"time": stamps}).to_netcdf(path)
    with xr.open_dataset(path, decode_times=False) as raw:
        assert " since " in raw["time"].attrs["units"]  # xarray's own encoding of datetimes
    (rec,) = records.read_records(path)
    assert rec.dt == pytest.approx(dt, rel=1e-9)


@hostile("numbers", "refused")
@pytest.mark.parametrize("scale", [1e-160, 1e-155, 1e158, 1e300])
def test_a_record_scaled_beyond_the_square_range_is_refused(tmp_path, rocking, scale):
    path = tmp_path / "scaled.npy"
    np.save(path, rocking[0] * scale)
    with pytest.raises(RecordError) as info:
        records.read_records(path, dt=rocking[1])
    _one_sentence(info.value, "largest angle", "rad")


@hostile("numbers", "answered")
@pytest.mark.parametrize("scale", [1e-150, 1e150])
def test_a_record_scaled_inside_the_square_range_is_read(tmp_path, rocking, scale):
    (rec,) = records.check_values(rocking[0] * scale, rocking[1], "x"),
    assert np.isfinite(np.sum(rec.theta**2)) and np.sum(rec.theta**2) > 0

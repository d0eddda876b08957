"""Issue 38's hostile cases through the command line: the library's refusals (records,
loads, config, cache, archive) reach the user as one sentence with exit code 2, nothing
written, nothing blocked. The library side of each is tested in its own module."""

from __future__ import annotations

import json
import os
import shutil
import threading
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from rockdec.cli import main
from rockdec.physics import simulate
from rockdec.pipeline import archive, config

from conftest import calibrated_step
from test_hostile import FAST, ROOT, config_file, refused

hostile = pytest.mark.hostile


@pytest.fixture(scope="module")
def record(tmp_path_factory):
    """A rocking record (e = 0.85, 20,000 samples) as .npy, and its step."""
    folder = tmp_path_factory.mktemp("record")
    cal = calibrated_step(0.85, 1.0, 0.003)
    theta = simulate.simulate_block([11], 20_000, dt=cal["dt"], g=1.0, e=0.85, sigma_p=0.003, burn_in=cal["burn_in"])[0][0]
    np.save(folder / "rec.npy", theta)
    return {"npy": folder / "rec.npy", "theta": theta, "dt": cal["dt"]}


def _in_time(argv, seconds=60):
    """``main(argv)`` in a thread; fails if it is still running after ``seconds`` (a hang)."""
    out = {}

    def run():
        try:
            out["code"] = main(argv)
        except SystemExit as exc:  # `verify` ends with the count of its findings
            out["code"] = exc.code

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    thread.join(seconds)
    assert not thread.is_alive(), f"{argv} still running after {seconds} s"
    return out["code"]


@hostile("record files", "refused")
@pytest.mark.parametrize("suffix", [".csv", ".npy", ".nc"])
def test_estimate_refuses_a_fifo_without_blocking(tmp_path, capsys, suffix):
    fifo = tmp_path / f"pipe{suffix}"
    os.mkfifo(fifo)
    argv = ["estimate", str(fifo), "--cache", str(tmp_path / "c"), *(["--dt", "0.01"] if suffix == ".npy" else [])]
    assert _in_time(argv) == 2
    err = capsys.readouterr().err
    assert "FIFO" in err and "Traceback" not in err and "internal error" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == [fifo.name]


@hostile("record files", "refused")
def test_estimate_refuses_an_npz_named_npy(record, tmp_path, capsys):
    path = tmp_path / "rec.npy"
    np.savez(tmp_path / "rec", theta=record["theta"])
    os.replace(tmp_path / "rec.npz", path)
    refused(["estimate", str(path), "--dt", str(record["dt"]), "--cache", str(tmp_path / "c")], tmp_path, capsys, [".npz archive"])


@hostile("numbers", "refused")
@pytest.mark.parametrize("scale", [1e-160, 1e160])
def test_estimate_refuses_a_record_scaled_beyond_the_square_range(record, tmp_path, capsys, scale):
    path = tmp_path / "scaled.npy"
    np.save(path, record["theta"] * scale)
    refused(["estimate", str(path), "--dt", str(record["dt"]), "--cache", str(tmp_path / "c")], tmp_path, capsys,
            ["largest angle", "rad"])


@hostile("numbers", "refused")
@pytest.mark.parametrize("corner", ["1e5", "1e8", "1e300", "1e-300"])
def test_estimate_refuses_a_lowpass_corner_whose_pole_rounds_away(record, tmp_path, capsys, corner):
    refused(["estimate", str(record["npy"]), "--dt", str(record["dt"]), "--load", f"lowpass:{corner}", "--cache",
             str(tmp_path / "c")], tmp_path, capsys, [f"--load lowpass:{float(corner):g}", "pole"])


@hostile("cache", "refused")
def test_estimate_refuses_a_cache_under_a_file(record, tmp_path, capsys):
    blocker = tmp_path / "blocker"
    blocker.write_text("x")
    refused(["estimate", str(record["npy"]), "--dt", str(record["dt"]), "--cache", str(blocker / "cache")], tmp_path, capsys,
            ["cache", "lies under a file"])
    assert blocker.read_text() == "x"


@hostile("configs", "answered")
@pytest.mark.parametrize("written", ["06000", "0o13560", "6000"], ids=["leading zero", "YAML 1.2 octal", "plain"])
def test_simulate_reads_a_config_as_yaml_12(tmp_path, written):
    path = config_file(tmp_path, f"default_scene: s\nscenes:\n  s:\n    records: {{n_points: {written}}}\n")
    out = tmp_path / "o.nc"
    assert main(["simulate", "--config", str(path), "--scene", "s", "--out", str(out), *FAST[:4], "--seeds", "0"]) == 0
    with xr.open_dataset(out) as ds:
        assert ds.sizes["time"] == 6000


@hostile("limits", "refused")
@pytest.mark.parametrize("width", [5, 10, 30])
def test_simulate_refuses_an_alias_bomb_at_once(tmp_path, capsys, width):
    lines = ["default_scene: s", "scenes:", "  s: {}", "bomb:", "  a: &a [" + ", ".join(["1"] * width) + "]"]
    for i in range(1, 10):
        prev, name = chr(96 + i), chr(97 + i)
        lines.append(f"  {name}: &{name} [" + ", ".join([f"*{prev}"] * width) + "]")
    path = config_file(tmp_path, "\n".join(lines) + "\n")
    start = time.perf_counter()
    refused(["simulate", "--config", str(path), "--scene", "s", "--out", str(tmp_path / "o.nc")], tmp_path, capsys,
            ["aliases", str(path)])
    assert time.perf_counter() - start < 5


def _small_archive(tmp_path: Path) -> Path:
    results = tmp_path / "results"
    results.mkdir()
    (results / "signatures.nc").write_bytes(b"\x89HDF" + bytes(range(256)) * 8)
    (results / "table.csv").write_text("e,low,high\n0.95,0.94,0.96\n")
    folder = tmp_path / "archive"
    archive.write_archive(folder, results, {"signatures.nc": "signatures", "table.csv": "estimates"}, "tiny",
                          config.validate_scene({}), ROOT)
    shutil.rmtree(results)
    return folder


@hostile("output paths", "refused")
@pytest.mark.parametrize("target", ["dangling link", "inside the archive"])
def test_verify_refuses_a_rebuild_onto_a_link_or_into_the_archive(tmp_path, capsys, target):
    folder = _small_archive(tmp_path)
    out = tmp_path / "rebuilt" if target == "dangling link" else folder / "rebuilt"
    if target == "dangling link":
        out.symlink_to(tmp_path / "nowhere")
    code = _in_time(["verify", str(folder), "--rebuild", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and ("symbolic link" in err or "inside the archive" in err) and "Traceback" not in err, err
    assert not (folder / "rebuilt").exists() and not any(p.name.endswith(".partial") for p in tmp_path.rglob("*"))


@hostile("archive", "refused")
def test_verify_names_a_size_change_by_its_size(tmp_path, capsys):
    folder = _small_archive(tmp_path)
    with open(folder / "table.csv", "a") as f:
        f.write("0.9,0.8,1.0\n")
    code = _in_time(["verify", str(folder)])
    out = capsys.readouterr().out
    assert code == 1 and "changed: table.csv (its size is" in out and "SHA-256" not in out, out


# --------------------------------------------------------------------------- the Python API


@hostile("record files", "refused")
def test_read_record_refuses_a_fifo_without_blocking(tmp_path):
    import rockdec

    fifo = tmp_path / "pipe.csv"
    os.mkfifo(fifo)
    out = {}

    def read():
        try:
            rockdec.read_record(fifo)
        except rockdec.RecordError as exc:
            out["error"] = str(exc)

    thread = threading.Thread(target=read, daemon=True)
    thread.start()
    thread.join(30)
    assert not thread.is_alive() and "FIFO" in out["error"]


@hostile("record files", "answered")
def test_read_record_reads_a_csv_with_a_byte_order_mark(record, tmp_path):
    import rockdec

    theta, dt = record["theta"][:3000], record["dt"]
    text = "time,theta\n" + "".join(f"{i * dt:.8f},{v:.10g}\n" for i, v in enumerate(theta))
    (tmp_path / "bom.csv").write_bytes(b"\xef\xbb\xbf" + text.encode())
    got = rockdec.read_record(tmp_path / "bom.csv")
    assert got.attrs["dt"] == pytest.approx(dt, rel=1e-6)
    np.testing.assert_allclose(got.values, theta, rtol=1e-9)


@hostile("numbers", "refused")
@pytest.mark.parametrize("scale", [1e-160, 1e160])
def test_estimate_of_an_array_scaled_beyond_the_square_range_is_refused(record, tmp_path, scale):
    import rockdec

    with pytest.raises(rockdec.RecordError, match="largest angle"):
        rockdec.estimate(record["theta"] * scale, record["dt"], cache=tmp_path / "c")
    assert not (tmp_path / "c").exists()

"""The calibration cache under hostile conditions (issue 38): a build lock stamped in the
future, a lock left by a killed run, a folder where the lock goes, a cache folder that
cannot be written, SIGTERM and Ctrl-C during a build. No run waits forever, no lock is
left behind, every refusal is one sentence naming ``cache``."""

from __future__ import annotations

import errno
import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from rockdec.calibrate import calibration
from rockdec.validate import InputError

from conftest import PYTHON_FORKS

hostile = pytest.mark.hostile


def _quick_build(settings):
    return xr.Dataset({"raw": (("e_true", "set", "name"), np.ones((2, 2, 1)))}, coords={"e_true": [0.5, 0.9]},
                      attrs={"settings": json.dumps(settings)})


@pytest.fixture
def quick(monkeypatch):
    """A build of no cost, a poll of 0.05 s and locks stale after 0.5 s; the settings to build."""
    monkeypatch.setattr(calibration, "build", _quick_build)
    monkeypatch.setattr(calibration, "POLL_S", 0.05)
    monkeypatch.setattr(calibration, "STALE_S", 0.5)
    return {"lengths": [1000], "hostile": 38}


def _lock(folder: Path, settings) -> Path:
    return folder / f"calibration-{calibration.settings_hash(settings)}.building"


def _dead_pid() -> int:
    return int(subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True).stdout)


@hostile("kills", "answered")
@pytest.mark.parametrize("ahead", [60.0, 86400.0 * 365], ids=["a minute", "a year"])
def test_a_lock_stamped_in_the_future_holds_a_run_for_stale_s_not_forever(tmp_path, quick, ahead):
    lock = _lock(tmp_path, quick)
    lock.write_text("host elsewhere pid 4242 started 2999-01-01T00:00:00Z\n")  # another node, its clock ahead
    future = time.time() + ahead
    os.utime(lock, (future, future))
    notes = []
    start = time.perf_counter()
    ds, cached = calibration.load_or_build(quick, tmp_path, notes)
    waited = time.perf_counter() - start
    assert cached is False and calibration.STALE_S <= waited < calibration.STALE_S + 10
    assert any("in the future" in n for n in notes) and not lock.exists()


@hostile("kills", "answered")
def test_a_touched_lock_stamped_in_the_future_is_waited_for(tmp_path, quick):
    """A live holder touches its lock: each new stamp (in the future, its clock ahead) restarts the wait."""
    lock = _lock(tmp_path, quick)
    lock.write_text("host elsewhere pid 4242 started now\n")
    watch, notes = {}, []
    for k in range(6):
        stamp = time.time() + 3600 + k
        os.utime(lock, (stamp, stamp))
        assert calibration._take_lock(lock, notes, watch) is False and lock.exists()
        time.sleep(calibration.STALE_S / 3)
    assert notes == []


@hostile("kills", "answered")
def test_a_fresh_lock_of_an_ended_process_of_this_host_is_taken_over_at_once(tmp_path, quick):
    lock = _lock(tmp_path, quick)
    lock.write_text(f"host {socket.gethostname()} pid {_dead_pid()} started now\n")
    notes = []
    start = time.perf_counter()
    _, cached = calibration.load_or_build(quick, tmp_path, notes)
    assert cached is False and time.perf_counter() - start < calibration.STALE_S
    assert "process has ended" in notes[0] and not lock.exists()


@hostile("cache", "answered")
def test_an_empty_folder_where_the_lock_goes_is_removed(tmp_path, quick):
    _lock(tmp_path, quick).mkdir()
    notes = []
    _, cached = calibration.load_or_build(quick, tmp_path, notes)
    assert cached is False and not _lock(tmp_path, quick).exists() and "empty folder" in notes[0]


@hostile("cache", "refused")
def test_a_folder_with_content_where_the_lock_goes_is_refused(tmp_path, quick):
    lock = _lock(tmp_path, quick)
    lock.mkdir()
    (lock / "keep").write_text("mine")
    with pytest.raises(InputError) as info:
        calibration.load_or_build(quick, tmp_path)
    assert "cache" in str(info.value) and lock.name in str(info.value) and "\n" not in str(info.value)
    assert (lock / "keep").read_text() == "mine"


@hostile("cache", "refused")
@pytest.mark.parametrize("where", ["a file", "under a file", "deep under a file"])
def test_a_cache_that_is_or_lies_under_a_file_is_refused_naming_cache(tmp_path, quick, where):
    blocker = tmp_path / "blocker"
    blocker.write_text("x")
    cache = {"a file": blocker, "under a file": blocker / "cache", "deep under a file": blocker / "a" / "b"}[where]
    with pytest.raises(InputError) as info:
        calibration.load_or_build(quick, cache)
    text = str(info.value)
    assert text.startswith(f"`cache` '{cache}'") and "file" in text and text.endswith("stored calibrations.")
    assert blocker.read_text() == "x"


@hostile("cache", "refused")
@pytest.mark.parametrize("code, words", [(errno.EROFS, "read-only file system"), (errno.EACCES, "not writable"),
                                         (errno.ENOSPC, "full disk")], ids=["read-only", "no permission", "disk full"])
@pytest.mark.parametrize("folder_exists", [False, True], ids=["new folder", "existing folder"])
def test_a_cache_that_cannot_be_written_is_refused_naming_cache(tmp_path, quick, monkeypatch, code, words, folder_exists):
    cache = tmp_path / "cache"
    if folder_exists:
        cache.mkdir()
    real_open = os.open

    def refuse(path, flags, *args):
        if flags & os.O_CREAT and str(path).startswith(str(cache)):
            raise OSError(code, os.strerror(code), str(path))
        return real_open(path, flags, *args)

    def refuse_mkdir(self, *args, **kwargs):
        raise OSError(code, os.strerror(code), str(self))

    monkeypatch.setattr(os, "open", refuse)
    if not folder_exists:
        monkeypatch.setattr(Path, "mkdir", refuse_mkdir)
    with pytest.raises(InputError) as info:
        calibration.load_or_build(quick, cache)
    text = str(info.value)
    assert text.startswith(f"`cache` '{cache}' ") and words in text and text.endswith("stored calibrations.") and "\n" not in text


@hostile("kills", "answered")
def test_ctrl_c_during_a_build_removes_its_lock(tmp_path, quick, monkeypatch):
    def interrupted(settings):
        assert _lock(tmp_path, quick).exists()
        raise KeyboardInterrupt

    monkeypatch.setattr(calibration, "build", interrupted)
    before = signal.getsignal(signal.SIGTERM)
    with pytest.raises(KeyboardInterrupt):
        calibration.load_or_build(quick, tmp_path)
    assert list(tmp_path.iterdir()) == []
    assert signal.getsignal(signal.SIGTERM) == before  # the SIGTERM handler of the build is gone with it


BUILDER = """
import sys, time
from rockdec.calibrate import calibration
def slow(settings):
    time.sleep(120)
calibration.build = slow
calibration.load_or_build({"lengths": [1000], "hostile": "sigterm"}, sys.argv[1])
"""


@hostile("kills", "answered")
@pytest.mark.slow
def test_sigterm_during_a_build_removes_its_lock_and_the_next_run_does_not_wait(tmp_path, quick):
    cache = tmp_path / "cache"
    lock = _lock(cache, {"lengths": [1000], "hostile": "sigterm"})
    proc = PYTHON_FORKS.start_script(BUILDER, cache, output=tmp_path / "builder")
    end = time.time() + 60
    while not (lock.exists() and lock.read_text().strip()) and time.time() < end:
        time.sleep(0.02)
    assert lock.exists(), proc.communicate(1)
    time.sleep(0.3)  # the build under way
    os.kill(proc.pid, signal.SIGTERM)
    assert proc.wait(timeout=30) == -signal.SIGTERM  # ended by the signal, as without the handler
    assert not lock.exists() and list(cache.iterdir()) == []
    start = time.perf_counter()
    calibration.load_or_build({"lengths": [1000], "hostile": "sigterm"}, cache)  # the quick build
    assert time.perf_counter() - start < 5

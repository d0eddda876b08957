"""The steps the workflow runs inside the Snakemake process (rockdec.pipeline.in_snakemake):
the run contract and the stored series, their files and their logs, without Snakemake."""

import re
import signal
import subprocess
import sys
import threading

import netCDF4
import numpy as np
import pytest
import xarray as xr

from rockdec.pipeline import config, in_snakemake, layout, replicates, steps
from rockdec.physics import run
from rockdec.physics.simulate import simulate_block
from rockdec.validate import InputError

from conftest import PYTHON_FORKS

SCENE = config.validate_scene(
    {
        "excitation": {"dt": 0.0034, "burn_in": 2000},
        "records": {"n_points": 3000, "replicates": 1, "series_per_replicate": 10, "chunk_seeds": 4, "store_series": 3},
        "signatures": {"windows": [0.5, 1.0]},
    }
)
PHYSICS = {key: SCENE[key] for key in ("model", "system", "excitation")}


def test_calibrate_writes_the_run_of_the_physics_and_logs_it_between_its_start_and_end(tmp_path):
    log, out = tmp_path / "calibrate.log", tmp_path / "run.json"
    in_snakemake.calibrate(str(log), PHYSICS, str(out))
    contract = run.Run.read(out)
    assert contract == run.from_scene(PHYSICS)
    lines = log.read_text().splitlines()
    assert lines[:2] == ["calibrate: started", f"run: {contract}"]
    assert re.fullmatch(r"calibrate: done in [\d.]+ s", lines[2]) and len(lines) == 3


def test_calibrate_does_not_wait_for_a_step_that_holds_the_lock(tmp_path):
    done = threading.Event()
    with in_snakemake._STEP_LOCK:  # a figure drawing meanwhile
        worker = threading.Thread(target=lambda: (in_snakemake.calibrate(str(tmp_path / "c.log"), PHYSICS,
                                                                          str(tmp_path / "run.json")), done.set()))
        worker.start()
        assert done.wait(60)
    worker.join()


def test_a_bad_setting_leaves_its_sentence_in_the_calibrate_log_and_is_raised(tmp_path):
    bad = {**PHYSICS, "system": {**PHYSICS["system"], "e": 1.5}}
    log = tmp_path / "calibrate.log"
    with pytest.raises(InputError) as err:
        in_snakemake.calibrate(str(log), bad, str(tmp_path / "run.json"))
    assert log.read_text().splitlines() == ["calibrate: started", f"rockdec: error: {err.value}"]
    assert not (tmp_path / "run.json").exists()


@pytest.mark.parametrize("engine", ["threads", "processes:2"])
def test_stored_series_are_the_simulators_series_of_the_stored_seeds_as_float32_on_any_engine(tmp_path, monkeypatch, engine):
    monkeypatch.setenv("ROCKDEC_DASK_SCHEDULER", engine)  # in Snakemake's process: never a worker process
    contract = run.from_scene(PHYSICS)
    contract.write(tmp_path / "run.json")
    rec = SCENE["records"]
    in_snakemake.step("stored_series", str(tmp_path / "s.log"), str(tmp_path / "run.json"), str(tmp_path / "s.nc"), rec)
    seeds = layout.simulation_seeds(rec)
    theta, theta_dot = simulate_block(seeds, rec["n_points"], dt=contract.dt, g=contract.g, e=contract.e,
                                      sigma_p=contract.sigma_p, burn_in=contract.burn_in)
    with netCDF4.Dataset(tmp_path / "s.nc") as nc:
        assert nc["theta"].dtype == np.float32 and list(nc["seed"][:]) == list(seeds)
        np.testing.assert_array_equal(nc["theta"][:], theta.astype(np.float32))
        np.testing.assert_array_equal(nc["theta_dot"][:], theta_dot.astype(np.float32))
    steps.stored_signature(tmp_path / "s.nc", tmp_path / "sig.nc", SCENE["signatures"])
    with netCDF4.Dataset(tmp_path / "sig.nc") as nc:
        assert nc.dimensions["group"].size == 1 and run.Run.from_attrs(nc.__dict__) == contract


def test_calibrate_loads_what_the_tables_need_beside_the_signature_pass(tmp_path):
    probe = f"""
import sys, threading
from rockdec.pipeline import in_snakemake
before = [name for name in in_snakemake.PRELOAD if name in sys.modules]
in_snakemake.calibrate({str(tmp_path / 'c.log')!r}, {PHYSICS!r}, {str(tmp_path / 'run.json')!r})
starts = sorted(set(in_snakemake.STARTS) - in_snakemake._LOADED)
for thread in threading.enumerate():
    if thread.name == "rockdec-preload":
        thread.join()
print(before, [name for name in in_snakemake.PRELOAD if name not in sys.modules], starts)
"""
    code, out, err = PYTHON_FORKS.script(probe, timeout=120)  # a process whose libraries load none of them
    assert code == 0, err
    # none loaded before, all loaded after; what the pass and the steps start with, by calibrate's return
    assert out.split() == ["[]", "[]", "[]"]


def test_an_import_under_way_is_waited_for(monkeypatch):
    """A thread that needs modules another thread is importing (holding the import lock)
    waits for it to end instead of entering the import."""
    monkeypatch.setattr(in_snakemake, "_LOADED", set())
    with in_snakemake._IMPORTS:
        waiting = threading.Thread(target=in_snakemake._load, args=(["json"],))
        waiting.start()
        waiting.join(0.3)
        assert waiting.is_alive() and "json" not in in_snakemake._LOADED
    waiting.join(10)
    assert not waiting.is_alive() and in_snakemake._LOADED == {"json"}


class Named(list):
    """Snakemake's input or output of a rule: a list of paths whose parts have names."""

    def __init__(self, **parts):
        super().__init__(p for part in parts.values() for p in (part if isinstance(part, list) else [part]))
        self.__dict__.update(parts)


def test_the_signature_pass_on_two_threads_writes_the_one_thread_cubes_bit_for_bit_and_logs_its_label(tmp_path):
    contract = run.from_scene(PHYSICS)
    contract.write(tmp_path / "run.json")
    rec = {**SCENE["records"], "replicates": 2, "series_per_replicate": 12, "chunk_seeds": 5}  # chunks straddle replicates
    readings = ["pooled", "per_series", "groups_of_10"]
    settings = {"signatures": SCENE["signatures"], "readings": readings, "fit_points": SCENE["estimates"]["fit_points"]}
    inputs = Named(run=str(tmp_path / "run.json"), series=[], cubes=[], curves=[], code=["x.py"])
    outputs = Named(cube=str(tmp_path / "signatures.nc"), readings=str(tmp_path / "readings.nc"))
    log = tmp_path / "signatures.log"
    in_snakemake.signatures("signatures", str(log), inputs, outputs, rec, settings, 0, 2)
    one = replicates.scene_cubes(contract, rec, SCENE["signatures"], readings, threads=1)
    curves = replicates.reading_curves(one, settings["fit_points"])
    with xr.open_dataset(outputs.cube) as cube, xr.open_dataset(outputs.readings) as got:
        for name in ("signature_sum", "count", "skipped", "signature", "free_response"):
            assert np.array_equal(cube[name].values, one["pooled"][name].values, equal_nan=True), name
        assert np.array_equal(got["e_hat"].values, curves["e_hat"].values, equal_nan=True)
        assert np.array_equal(got["count"].values, curves["count"].values)
        assert cube.attrs["source_files"] == str(tmp_path / "run.json")  # the code inputs left out
    lines = log.read_text().splitlines()
    assert lines[0] == "signatures: 2 replicates x 12 series: started"
    assert re.fullmatch(r"signatures: 2 replicates x 12 series: done in [\d.]+ s", lines[1]) and len(lines) == 2


def test_a_signal_stops_the_signature_pass_before_it_writes_and_says_so_in_its_log(tmp_path):
    contract = run.from_scene(PHYSICS)
    contract.write(tmp_path / "run.json")
    settings = {"signatures": SCENE["signatures"], "readings": ["pooled"], "fit_points": SCENE["estimates"]["fit_points"]}
    inputs = Named(run=str(tmp_path / "run.json"), series=[], cubes=[], curves=[])
    outputs = Named(cube=str(tmp_path / "signatures.nc"), readings=str(tmp_path / "readings.nc"))
    log = tmp_path / "signatures.log"
    in_snakemake._STOP.set()
    try:
        with pytest.raises(in_snakemake.Stopped):
            in_snakemake.signatures("signatures", str(log), inputs, outputs, SCENE["records"], settings, 0, 2)
    finally:
        in_snakemake._STOP.clear()
    assert not list(tmp_path.glob("*.nc")) and not list(tmp_path.glob(".*"))
    assert log.read_text().splitlines()[-1] == ("signatures: 1 replicates x 10 series: stopped by a signal before the "
                                                "pass ended; nothing written")


def test_the_signals_set_the_stop_and_still_reach_the_handlers_before_them():
    probe = """
import os, signal
from rockdec.pipeline import in_snakemake
seen = []
signal.signal(signal.SIGINT, signal.default_int_handler)  # as Python starts, unless its parent ignores SIGINT (xdist's workers do)
signal.signal(signal.SIGTERM, lambda n, f: seen.append(n))  # Snakemake's graceful stop
in_snakemake.stop_on_signals()
os.kill(os.getpid(), signal.SIGTERM)
print(in_snakemake._STOP.is_set(), seen == [signal.SIGTERM])
in_snakemake.stop_on_signals()
print(in_snakemake._STOP.is_set())
try:
    os.kill(os.getpid(), signal.SIGINT)
except KeyboardInterrupt:
    print("KeyboardInterrupt", in_snakemake._STOP.is_set())
"""
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120, check=True).stdout
    assert out.split() == ["True", "True", "False", "KeyboardInterrupt", "True"]


def test_a_signal_the_process_ignores_stays_ignored_and_stops_nothing():
    probe = """
import os, signal
from rockdec.pipeline import in_snakemake
signal.signal(signal.SIGINT, signal.SIG_IGN)
in_snakemake.stop_on_signals()
os.kill(os.getpid(), signal.SIGINT)
print(signal.getsignal(signal.SIGINT) == signal.SIG_IGN, in_snakemake._STOP.is_set())
"""
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120, check=True).stdout
    assert out.split() == ["True", "False"]


def test_outside_the_main_thread_no_handler_is_set():
    before = signal.getsignal(signal.SIGTERM), signal.getsignal(signal.SIGINT)
    worker = threading.Thread(target=in_snakemake.stop_on_signals)
    worker.start()
    worker.join()
    assert (signal.getsignal(signal.SIGTERM), signal.getsignal(signal.SIGINT)) == before


class _Scheduler:
    """Starts a timer as Snakemake's job scheduler does after each round of scheduling."""

    def _schedule_reevalutation(self, delay):
        timer = threading.Timer(delay, lambda: None)
        timer.start()
        return timer


def test_the_end_of_a_run_cancels_the_schedulers_timers_and_no_other():
    scheduler_timer = _Scheduler()._schedule_reevalutation(60.0)
    other = threading.Timer(60.0, lambda: None)
    other.start()
    try:
        in_snakemake.end_of_run()
        scheduler_timer.join(10.0)
        assert not scheduler_timer.is_alive() and other.is_alive()
    finally:
        other.cancel()
        scheduler_timer.cancel()

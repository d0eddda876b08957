"""The workflow's rules that run inside the Snakemake process: the run contract, the
signature pass, the stored series (every series too, under ``store_series: all``) and
their signature, the tables and the figures.

The light steps are ``run:`` rules calling :func:`calibrate` and :func:`step` in threads of
the Snakemake process (``force-use-threads``), so NumPy, numba and xarray load once a run;
the signature pass (:func:`signatures`) runs there on its rule's Dask threads, and the
figure rules call :func:`draw`, which hands each figure to a worker process
(:mod:`rockdec.pipeline.figure_workers`); :func:`campaign` runs a campaign's steps. The
other compute rules stay scripts (:mod:`rockdec.pipeline.job`). :func:`stop_on_signals`
makes SIGTERM and SIGINT stop the pass (:class:`Stopped`) as they stop a script job;
:func:`calibrate` imports what the pass and the steps start with (:data:`STARTS`) before
they start, and the tables' libraries beside the pass (:data:`PRELOAD`), so no two threads
import Dask at once; :func:`end_of_run` ends the run without delay.

Explanation: docs/development/benchmarks.md (the run inside the Snakemake process);
docs/how-to/paper.md (stopping a run).
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
import time
import traceback

from rockdec import locks
from rockdec.validate import InputError

__all__ = ["Stopped", "calibrate", "campaign", "draw", "end_of_run", "signatures", "step", "stop_on_signals"]

#: What the signature pass and the light steps import as they start (Dask, its threaded
#: scheduler and array, the pass's and the steps' modules): :func:`calibrate` imports them
#: once the run contract is written, before Snakemake starts any rule that reads the
#: contract, so that no two threads import them at once (two threads entering Dask's
#: circular imports at different modules see it half initialized).
STARTS = ("dask", "dask.array", "dask.threaded", "dask.callbacks", "rockdec.pipeline.replicates", "rockdec.pipeline.steps")

#: What the window curves at the end of the pass and the tables load on their first run and
#: nothing before them does: the tables' code, xarray's groupby engine (flox,
#: numpy_groupies) and the p-values' scipy.stats. :func:`calibrate` imports them in a thread
#: of their own beside the signature pass, instead of on the path after it.
PRELOAD = ("rockdec.report.tables", "flox", "scipy.stats")

#: Held while a thread of this process imports :data:`STARTS` or :data:`PRELOAD`
#: (:func:`_load`): the pass and the steps wait for an import under way instead of entering it.
_IMPORTS = threading.Lock()

#: Set by SIGTERM or SIGINT once :func:`stop_on_signals` ran: the signature pass stops.
_STOP = threading.Event()


class Stopped(Exception):
    """The signature pass stopped on a signal (:data:`_STOP`) before writing anything."""


def stop_on_signals() -> None:
    """Make SIGTERM and SIGINT set :data:`_STOP`, then do what they did before (Snakemake's
    handling: a graceful stop after the running jobs, or a ``KeyboardInterrupt``). Called
    in Snakemake's main thread once its scheduler has set its handlers (the Snakefile's
    ``onstart``); clears :data:`_STOP` first. A signal the process ignores stays ignored.
    Snakemake run from another thread (its API) sets no handler, and neither does this."""
    _STOP.clear()
    if threading.current_thread() is not threading.main_thread():
        return
    for number in (signal.SIGTERM, signal.SIGINT):
        previous = signal.getsignal(number)
        if previous == signal.SIG_IGN:
            continue

        def handler(signum, frame, previous=previous):
            _STOP.set()
            if callable(previous):
                previous(signum, frame)
            else:  # the default action: end the process as the signal does
                signal.signal(signum, signal.SIG_DFL)
                os.kill(os.getpid(), signum)

        signal.signal(number, handler)


def end_of_run() -> None:
    """Cancel the re-evaluation timers Snakemake's scheduler left running (the Snakefile's
    ``onsuccess`` and ``onerror``, once the scheduler has stopped). Its job rate limiter
    (``--max-jobs-per-timespan``, 100 a second by default) starts a non-daemon
    :class:`threading.Timer` of its timespan at each round of scheduling; the last one
    would keep the process alive for up to that second after the last job. Other timers
    are left alone."""
    for thread in threading.enumerate():
        function = getattr(thread, "function", None)
        if isinstance(thread, threading.Timer) and "_schedule_reevalutation" in getattr(function, "__qualname__", ""):
            thread.cancel()


def _check_stop(*_) -> None:
    """Raise :class:`Stopped` once :data:`_STOP` is set."""
    if _STOP.is_set():
        raise Stopped("stopped by a signal before the pass ended; nothing written")


#: One :func:`step` at a time in a process: the HDF5 library under netCDF4 is not safe to
#: use from two threads at once (:data:`rockdec.locks.HDF5`).
_STEP_LOCK = locks.HDF5


def step(rule: str, log: str, *args) -> None:
    """Run rule ``rule`` as the :mod:`rockdec.pipeline.steps` function of that name, on ``*args``,
    inside the Snakemake process. Steps run one at a time (:data:`_STEP_LOCK`); the
    compute rules' scripts and :func:`calibrate` run beside them.

    The log (``log``) gets a line at the start and at the end; an error the user can fix
    (:class:`rockdec.validate.InputError`) is written there as its one sentence and raised
    again for Snakemake to report; any other exception leaves its traceback there too.
    Standard error is left alone: the Snakemake process and its other threads share it.
    """

    def work():
        _load(STARTS + PRELOAD)
        from rockdec.pipeline import steps

        getattr(steps, rule)(*args)

    with _STEP_LOCK:
        _logged(rule, log, work)


#: What the campaign's steps import as they start (the estimate's engine, the calibration's
#: Dask, the campaign's steps): :func:`campaign` imports them once, holding :data:`_IMPORTS`.
CAMPAIGN_STARTS = ("dask", "dask.array", "dask.threaded", "rockdec.estimation", "rockdec.pipeline.campaign", "xarray")


def campaign(rule: str, log: str, *args, api=None) -> None:
    """Rules ``campaign_simulate``, ``campaign_first_plan``, ``campaign_plan``, ``campaign_calibration``,
    ``campaign_record`` and ``campaign_block``: the :mod:`rockdec.pipeline.campaign` step of
    that name (``campaign_first_plan`` and ``campaign_plan`` run ``plan_step``; the record and
    block rules ``estimate_step``) on ``*args``, inside the Snakemake process: a record's plan and estimate
    take a fraction of a second once the estimate's modules are loaded, which a script would
    load again for each. Steps run side by side on Snakemake's threads (the numba kernels
    and the calibration's Dask threads release the GIL) and hold the HDF5 locks only to read
    and write files. Logged as :func:`step` logs. ``api``: the package's front door (the
    ``rockdec`` module), which the estimate steps call and the workflow hands in; its modules
    load on first use, here one thread at a time (:data:`_IMPORTS`)."""
    name = {"campaign_record": "estimate", "campaign_block": "estimate", "campaign_first_plan": "plan"}.get(rule, rule.removeprefix("campaign_"))

    def work():
        _load(CAMPAIGN_STARTS)
        from rockdec.pipeline import campaign as steps

        if api is None:
            return getattr(steps, f"{name}_step")(*args)
        with _IMPORTS:
            getattr(api, "estimate"), getattr(api, "read_record")
        return getattr(steps, f"{name}_step")(*args, api=api)

    _logged(rule, log, work)


def draw(rule: str, log: str, *args) -> None:
    """Run figure rule ``rule`` as the :mod:`rockdec.pipeline.steps` function of that name, on
    ``*args``, in a worker process (:mod:`rockdec.pipeline.figure_workers`): the figure's
    Python holds no GIL of the Snakemake process, and two figures draw at once. Logged as
    :func:`step` logs; it takes no :data:`_STEP_LOCK`."""
    from rockdec.pipeline import figure_workers

    _logged(rule, log, lambda: figure_workers.draw(rule, *args))


def signatures(rule: str, log: str, inputs, outputs, records: dict, settings: dict, first_replicate: int, threads: int) -> None:
    """Rules ``signatures`` and ``signature_part``: one pass over the series of ``records``,
    the scene's cube (``outputs.cube``) and every compared reading's window curves
    (``outputs.readings``), under ``settings`` (:func:`rockdec.pipeline.replicates.scene_cubes`
    on ``threads`` Dask threads, the readings not written as sums only, then
    :func:`rockdec.pipeline.replicates.reading_curves` on as many threads). The
    series are simulated from their seeds under ``inputs.run`` or read from ``inputs.series``;
    a scene split into jobs (``inputs.cubes``, ``inputs.curves``) is gathered instead
    (:func:`rockdec.pipeline.replicates.gathered`). ``first_replicate`` numbers a part's
    replicates as the whole scene does; ``inputs`` (every input) go into the files' provenance.

    The log has a labelled line at the start and at the end of the pass (and Dask's progress
    bar on Snakemake's terminal); errors are logged as :func:`step` logs them. The pass takes
    :data:`_STEP_LOCK` only to read and write files, so the light steps go on beside its
    computation from seeds.
    """
    if inputs.cubes:
        label = f"{rule}: gathering {len(inputs.cubes)} signature jobs"
    else:
        label = f"{rule}: {records['replicates']} replicates x {records['series_per_replicate']} series"

    def work():
        _load(STARTS)
        from dask.callbacks import Callback

        from rockdec import console, io
        from rockdec.pipeline import replicates
        from rockdec.physics.run import Run

        if inputs.cubes:
            with _STEP_LOCK:
                loaded = {}
                for path in [*inputs.cubes, *inputs.curves]:
                    with io.open_dataset(path) as ds:
                        loaded[path] = ds.load()
            cube, curves = replicates.gathered([loaded[p] for p in inputs.cubes], [loaded[p] for p in inputs.curves])
        else:
            reads_files = _STEP_LOCK if len(inputs.series) else contextlib.nullcontext()
            with reads_files, console.progress(label, stream=sys.__stderr__), Callback(start=_check_stop, pretask=_check_stop):
                cubes = replicates.scene_cubes(
                    Run.read(inputs.run), records, settings["signatures"], settings["readings"], inputs.series,
                    threads=threads, first_replicate=first_replicate, sums_only=settings["readings"][1:],
                )
            cube = cubes[settings["readings"][0]]
            _load(PRELOAD)
            curves = replicates.reading_curves(cubes, settings["fit_points"], threads)
        cube.attrs.update(io.provenance(rule, settings["signatures"], inputs=inputs))
        curves.attrs.update(io.provenance("readings", settings, inputs=inputs))
        _check_stop()
        with _STEP_LOCK:
            io.write_netcdf(cube, outputs.cube)
            io.write_netcdf(curves, outputs.readings)

    _logged(label, log, work)


def calibrate(log: str, physics: dict, output: str) -> None:
    """Rule ``calibrate``: the run contract of a scene's ``physics`` (its ``model``, ``system``
    and ``excitation`` sections; :func:`rockdec.physics.run.from_scene`) written to ``output``
    (``run.json``), logged as :func:`step` logs, with the contract on a line of its own.

    Pilot simulations and a JSON file: no HDF5, so it takes no :data:`_STEP_LOCK`. Then the
    modules of :data:`STARTS` load, and those of :data:`PRELOAD` in a thread beside the
    signature pass (:func:`_load`).
    """

    def work():
        from rockdec.physics import run

        contract = run.from_scene(physics)
        contract.write(output)
        return f"run: {contract}"

    _logged("calibrate", log, work)
    _load(STARTS)
    threading.Thread(target=_load, args=(PRELOAD,), name="rockdec-preload", daemon=True).start()


#: The modules :func:`_load` has imported (a module is in ``sys.modules`` from the start of
#: its import, so that does not say it is whole).
_LOADED: set = set()


def _load(names) -> None:
    """Import the modules ``names`` holding :data:`_IMPORTS`; nothing to wait for when
    :func:`_load` has imported them all."""
    import importlib

    if _LOADED.issuperset(names):
        return
    with _IMPORTS:
        for name in names:
            importlib.import_module(name)
            _LOADED.add(name)


def _logged(label: str, log: str, work) -> None:
    """``work()`` with the log of :func:`step`: a start line, what ``work`` returns (a line of
    text, or ``None``), an end line, each led by ``label`` (the rule's name); a user error's
    sentence or a traceback on failure."""
    with open(log, "w") as out:
        start = time.perf_counter()
        print(f"{label}: started", file=out, flush=True)
        try:
            note = work()
        except InputError as exc:
            print(f"rockdec: error: {exc}", file=out, flush=True)
            raise
        except Stopped as exc:
            print(f"{label}: {exc}", file=out, flush=True)
            raise
        except Exception:
            traceback.print_exc(file=out)
            raise
        if note is not None:
            print(note, file=out, flush=True)
        print(f"{label}: done in {time.perf_counter() - start:.1f} s", file=out, flush=True)

"""The processes that draw the workflow's figures beside the Snakemake process.

Drawing a figure is Python (matplotlib's layout, text and rendering) that holds the GIL
for its whole second; in a thread of the Snakemake process it would share one core with the
signature pass and the tables. So the figure rules (:func:`rockdec.pipeline.in_snakemake.draw`)
hand their :mod:`rockdec.pipeline.steps` function to one of :data:`PROCESSES` worker
processes, started at the first figure of a run (fig. 1b, which needs no data, starts with
the run). One Python process starts, loads matplotlib, xarray, netCDF4 and the figures'
code (:data:`LOADS`), reads a small NetCDF file as a figure step reads its products and
renders a figure with text and mathematics once (:func:`_warm`), then forks the other
workers, which find all of it loaded: the loading costs one process's CPU, on the core
``calibrate`` leaves free. After the signature pass the figures that read its products
are drawn two at once.

A worker reads ``(rule, args)`` requests from a pipe and answers each on another
(pickles): ``("done", None)``, ``("input", sentence)`` for a
:class:`rockdec.validate.InputError` (raised again as one in the Snakemake process) or
``("error", traceback)``. Anything the drawing prints goes to standard error. A worker
ignores SIGINT, so a Ctrl-C lets a figure finish, as the light steps do; it ends when its
request pipe closes (at once, without tearing down its interpreter): :func:`close`, which
the process that started the workers calls as it exits (it waits for them, so their CPU
counts as its children's), or that process ending however it ends. A worker that ends before answering (killed, crashed) is replaced by a
newly started one, which gets the request once more.
"""

from __future__ import annotations

import atexit
import os
import pickle
import queue
import signal
import subprocess
import sys
import threading
from pathlib import Path

from rockdec.validate import InputError

__all__ = ["PROCESSES", "WorkerError", "close", "draw"]

#: Worker processes: two cores draw the figures that wait for the signature pass (the
#: workflow sets one under ``--cores 1``, workflow/rules/common.smk).
PROCESSES = 2

#: What the first worker loads before it forks the others.
LOADS = ("rockdec.pipeline.steps", "rockdec.report.figures", "rockdec.report.tables", "rockdec.rdd.signatures")


class WorkerError(RuntimeError):
    """A figure failed in its worker process (the worker's traceback is the message), or
    its worker ended before answering, twice."""


class _Worker:
    """The Snakemake process's ends of one worker's pipes, and the process it started (the
    first worker, or a replacement; ``None`` for a worker forked by the first)."""

    def __init__(self, requests, answers, process: subprocess.Popen | None) -> None:
        self.requests, self.answers, self.process = requests, answers, process

    def run(self, rule: str, args: tuple):
        """Send one request, wait for its answer; ``None`` when the worker has ended."""
        try:
            pickle.dump((rule, args), self.requests)
            self.requests.flush()
            return pickle.load(self.answers)
        except (OSError, EOFError, pickle.UnpicklingError):
            return None

    def close(self) -> None:
        """Close the request pipe: the worker ends."""
        for pipe in (self.requests, self.answers):
            try:
                pipe.close()
            except OSError:
                pass


def _start(count: int) -> list[_Worker]:
    """Start a Python process that serves ``count`` workers (it forks ``count - 1``)."""
    pipes = [(os.pipe(), os.pipe()) for _ in range(count)]
    ends = [(requests[0], answers[1]) for requests, answers in pipes]  # the workers' ends
    # this process's module path, so that the worker imports the rockdec this process runs
    code = f"import sys; sys.path[:] = {sys.path!r}; from {__name__} import serve; serve({ends!r})"
    env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}  # no BLAS threads: the first worker forks
    process = subprocess.Popen(
        [sys.executable, "-c", code], pass_fds=[fd for pair in ends for fd in pair], env=env, stdin=subprocess.DEVNULL,
    )
    for fd in (fd for pair in ends for fd in pair):
        os.close(fd)
    return [
        _Worker(os.fdopen(requests[1], "wb"), os.fdopen(answers[0], "rb"), process if k == 0 else None)
        for k, (requests, answers) in enumerate(pipes)
    ]


_started = threading.Lock()
_workers: list[_Worker] = []
_processes: list[subprocess.Popen] = []
_idle: queue.SimpleQueue = queue.SimpleQueue()


def draw(rule: str, *args) -> None:
    """Run the :mod:`rockdec.pipeline.steps` function ``rule`` on ``*args`` in a worker
    process (the workers start at the first call of a process), waiting for it. Raises
    :class:`rockdec.validate.InputError` with the worker's sentence, or :class:`WorkerError`
    with its traceback, or when a worker ended before answering and its replacement did
    too."""
    with _started:
        if not _workers:
            _workers.extend(_start(PROCESSES))
            _processes.append(_workers[0].process)
            atexit.register(close)
            for worker in _workers:
                _idle.put(worker)
    worker = _idle.get()
    for _ in range(2):
        answer = worker.run(rule, args)
        if answer is not None:
            break
        worker = _replaced(worker)  # ended: a new worker, and the request once more
    else:
        _idle.put(worker)
        raise WorkerError(f"the process drawing {rule} ended before it finished, twice")
    _idle.put(worker)
    status, payload = answer
    if status == "input":
        raise InputError(payload)
    if status == "error":
        raise WorkerError(payload)


def _replaced(worker: _Worker) -> _Worker:
    """A newly started worker in the place of ``worker``, which has ended."""
    worker.close()
    (replacement,) = _start(1)
    with _started:
        _workers[_workers.index(worker)] = replacement
        _processes.append(replacement.process)
    return replacement


def close() -> None:
    """End the worker processes of this process and wait for them (none started: nothing)."""
    with _started:
        for worker in _workers:
            worker.close()
        for process in _processes:
            process.wait()
        _workers.clear()
        _processes.clear()
        while not _idle.empty():
            _idle.get()


def _warm() -> None:
    """Load :data:`LOADS`; write, read and reduce a small NetCDF file as a figure step reads
    its products (xarray loads its NetCDF backend, Dask and SciPy at its first such use);
    render a figure with text and mathematics as PNG and PDF into memory (the fonts,
    mathtext's parser, both backends). All of it before the first figure, and before the
    first worker forks the others."""
    import importlib
    import io
    import tempfile

    for name in LOADS:
        importlib.import_module(name)
    import numpy as np
    import xarray as xr
    from matplotlib.figure import Figure

    from rockdec import io as rockdec_io

    with tempfile.TemporaryDirectory(prefix="rockdec-figure-worker-") as folder:
        path = Path(folder) / "warm.nc"
        rockdec_io.write_netcdf(xr.Dataset({"x": (("replicate", "window"), np.ones((2, 2)))}, coords={"window": [0.5, 1.0]}), path)
        with rockdec_io.open_dataset(path) as ds:
            x = ds.load()["x"].sel(window=1.0)
            (x.std("replicate", ddof=1, skipna=True) / x.notnull().sum("replicate")).values
    fig = Figure(figsize=(2.0, 2.0), layout="constrained")
    ax = fig.subplots()
    ax.plot([0.0, 1.0], [0.0, 1.0], label=r"$\hat e_v$, τ")
    ax.set_title("(a) title")
    ax.legend()
    for fmt in ("png", "pdf"):
        fig.savefig(io.BytesIO(), format=fmt, dpi=150)


def serve(ends: list[tuple[int, int]]) -> None:
    """The workers of one process (module docstring): ``ends`` holds the file descriptors
    ``(requests, answers)`` of each; this process serves the first and forks one process
    for each of the others, once :func:`_warm` has loaded what they draw with."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    os.dup2(sys.stderr.fileno(), sys.stdout.fileno())  # what the drawing prints goes to standard error
    _warm()
    forked = []
    for k in range(1, len(ends)):
        pid = os.fork()
        if pid == 0:
            for fd in (fd for j, pair in enumerate(ends) if j != k for fd in pair):
                os.close(fd)
            _serve_one(*ends[k])
            _exit()
        forked.append(pid)
    for fd in (fd for pair in ends[1:] for fd in pair):
        os.close(fd)
    _serve_one(*ends[0])
    for pid in forked:
        os.waitpid(pid, 0)
    _exit()


def _exit() -> None:
    """End a worker at once: its figures are written and closed, its answers flushed, and
    tearing down its interpreter (matplotlib, xarray, Dask) would only keep :func:`close`,
    and the run, waiting."""
    sys.stderr.flush()
    os._exit(0)


def _serve_one(requests_fd: int, answers_fd: int) -> None:
    """Answer the requests of one pipe until it closes."""
    import traceback

    from rockdec.pipeline import steps

    with os.fdopen(requests_fd, "rb") as requests, os.fdopen(answers_fd, "wb") as answers:
        while True:
            try:
                rule, args = pickle.load(requests)
            except EOFError:
                return
            try:
                getattr(steps, rule)(*args)
                answer = ("done", None)
            except InputError as exc:
                answer = ("input", str(exc))
            except Exception:
                answer = ("error", traceback.format_exc())
            pickle.dump(answer, answers)
            answers.flush()

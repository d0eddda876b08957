"""The processes that draw the workflow's figures beside the Snakemake process.

Drawing a figure is Python (matplotlib's layout, text and rendering) that holds the GIL
for its whole second; in a thread of the Snakemake process it would share one core with the
signature pass and the tables. So the figure rules (:func:`rockdec.pipeline.in_snakemake.draw`)
hand their :mod:`rockdec.pipeline.steps` function to one of :data:`PROCESSES` worker
processes, started together at the first figure of a run (fig. 1b, which needs no data,
starts with the run). Each loads matplotlib, xarray, netCDF4 and the figures' code
(:data:`LOADS`) and renders a figure with text and mathematics once (the fonts and
mathtext's parser), on the core ``calibrate`` leaves free, then draws one figure at a time;
after the signature pass the figures that read its products are drawn on two cores at
once.

A worker reads ``(rule, args)`` requests from its standard input and answers each on its
standard output (pickles): ``("done", None)``, ``("input", sentence)`` for a
:class:`rockdec.validate.InputError` (raised again as one in the Snakemake process) or
``("error", traceback)``. Anything the drawing prints goes to standard error. A worker
ignores SIGINT, so a Ctrl-C lets a figure finish, as the light steps do; it ends when its
standard input closes: :func:`close`, which the process that started it calls as it exits
(so it waits for its workers, and their CPU counts as its children's), or that process
ending however it ends.
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

#: Worker processes: two cores draw the three figures that wait for the signature pass.
PROCESSES = 2

#: What a worker loads before its first request.
LOADS = ("rockdec.pipeline.steps", "rockdec.report.figures", "rockdec.report.tables", "rockdec.rdd.signatures")


class WorkerError(RuntimeError):
    """A figure failed in its worker process (the worker's traceback is the message), or
    the worker ended before answering."""


class _Worker:
    """One worker process and its pipes."""

    def __init__(self) -> None:
        package_root = str(Path(__file__).resolve().parents[2])  # the directory that holds rockdec
        path = os.environ.get("PYTHONPATH")
        env = {**os.environ, "PYTHONPATH": package_root if not path else os.pathsep.join([package_root, path])}
        self.process = subprocess.Popen(
            [sys.executable, "-c", f"from {__name__} import serve; serve()"],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, env=env,
        )

    def run(self, rule: str, args: tuple):
        """Send one request, wait for its answer."""
        try:
            pickle.dump((rule, args), self.process.stdin)
            self.process.stdin.flush()
            return pickle.load(self.process.stdout)
        except (OSError, EOFError, pickle.UnpicklingError):
            self.process.kill()
            self.process.wait()
            raise WorkerError(f"the process drawing {rule} ended (exit code {self.process.returncode}) before it finished") from None

    def close(self) -> None:
        """Close the worker's input (it ends) and wait for it."""
        try:
            self.process.stdin.close()
        except OSError:
            pass
        self.process.wait()


_started = threading.Lock()
_workers: list[_Worker] = []
_idle: queue.SimpleQueue = queue.SimpleQueue()


def draw(rule: str, *args) -> None:
    """Run the :mod:`rockdec.pipeline.steps` function ``rule`` on ``*args`` in a worker
    process (started with the others at the first call of a process; one that has ended
    meanwhile is replaced), waiting for it. Raises :class:`rockdec.validate.InputError` with
    the worker's sentence, or :class:`WorkerError` with its traceback, or when the worker
    ends before answering (it is then replaced)."""
    with _started:
        if not _workers:
            _workers.extend(_Worker() for _ in range(PROCESSES))
            atexit.register(close)
            for worker in _workers:
                _idle.put(worker)
    worker = _idle.get()
    if worker.process.poll() is not None:
        worker = _replaced(worker)
    try:
        status, payload = worker.run(rule, args)
    except WorkerError:
        _idle.put(_replaced(worker))
        raise
    _idle.put(worker)
    if status == "input":
        raise InputError(payload)
    if status == "error":
        raise WorkerError(payload)


def _replaced(worker: _Worker) -> _Worker:
    """A new worker in the place of ``worker``, which has ended."""
    worker.process.wait()
    replacement = _Worker()
    with _started:
        _workers[_workers.index(worker)] = replacement
    return replacement


def close() -> None:
    """End the worker processes of this process and wait for them (none started: nothing)."""
    with _started:
        for worker in _workers:
            worker.close()
        _workers.clear()
        while not _idle.empty():
            _idle.get()


def _warm() -> None:
    """Load :data:`LOADS`, then render a figure with text and mathematics as PNG and PDF into
    memory: the fonts, mathtext's parser and both backends load before the first figure."""
    import importlib
    import io

    for name in LOADS:
        importlib.import_module(name)
    from matplotlib.figure import Figure

    fig = Figure(figsize=(2.0, 2.0), layout="constrained")
    ax = fig.subplots()
    ax.plot([0.0, 1.0], [0.0, 1.0], label=r"$\hat e_v$, τ")
    ax.set_title("(a) title")
    ax.legend()
    for fmt in ("png", "pdf"):
        fig.savefig(io.BytesIO(), format=fmt, dpi=150)


def serve() -> None:
    """A worker's loop (module docstring): requests from standard input until it closes."""
    import traceback

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    answers = os.fdopen(os.dup(sys.stdout.fileno()), "wb")
    os.dup2(sys.stderr.fileno(), sys.stdout.fileno())  # what the drawing prints goes to standard error
    requests = sys.stdin.buffer
    _warm()
    from rockdec.pipeline import steps

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

"""What every workflow script does around its rule's work: the log, user errors, progress.

A workflow script (``workflow/scripts/*.py``) is a thin adapter: its work sits in a
function of the ``snakemake`` object, called as ``job.run(main, snakemake)`` under an
``if __name__ == "__main__":`` guard. The guard matters for the ``processes:N`` engine
(:mod:`rockdec.engine`): Dask's worker processes are spawned, and a spawned process
re-runs the script file as a module named ``__mp_main__``, without the ``snakemake``
object Snakemake's preamble defines; guarded, the re-run defines the function and does
nothing.

:func:`run` sends the script's standard error to the rule's log. An error the user can fix
(:class:`rockdec.validate.InputError`: a bad setting, an output that exists) is written
as its one sentence both to the log and to the console Snakemake runs in, and the job
exits with code 2; any other exception leaves its traceback in the log and a line on the
console that says where it is.

Recovery after ``kill -9`` of Snakemake alone (docs/how-to/paper.md, "If a run was killed"): the job
Snakemake had started goes on as an orphan. Each job records its process, and the processes
between it and Snakemake (Snakemake included), in ``<log>.pid`` while it runs; a rerun of the same rule
that finds a live job there whose Snakemake is gone stops that orphan (and its worker
processes) before it starts, and removes whatever outputs of the rule exist, so that a
file the orphan wrote never blocks the rerun. A live job whose Snakemake still runs is
refused in one sentence instead.
"""

from __future__ import annotations

import contextlib
import json
import os
import socket
import sys
import time
import traceback
from pathlib import Path

from rockdec.validate import InputError

__all__ = ["progress", "run"]

#: Seconds an orphaned job is given to stop after SIGTERM before it is killed.
STOP_WAIT_S = 10.0


def run(main, smk) -> None:
    """Call ``main(smk)`` with standard error sent to the rule's log (``smk.log[0]``)."""
    console = sys.stderr
    with open(smk.log[0], "w") as log:
        sys.stderr = log
        try:
            with _claimed(smk, console):
                main(smk)
        except InputError as exc:
            print(f"rockdec: error: {exc}", file=log, flush=True)
            print(f"rockdec: error in rule {smk.rule}: {exc}", file=console, flush=True)
            raise SystemExit(2) from None
        except Exception:
            traceback.print_exc(file=log)
            log.flush()
            print(
                f"rockdec: rule {smk.rule} failed with an internal error (this is a bug); "
                f"the traceback is in {smk.log[0]}",
                file=console,
                flush=True,
            )
            raise SystemExit(1) from None
        finally:
            sys.stderr = console


@contextlib.contextmanager
def progress(label: str, terminal=None):
    """Label the Dask computations of the block: a line in the log at its start and end.

    The progress bar (:func:`rockdec.console.progress`) is drawn only on a terminal
    (``terminal``, default the process's own standard error when it is a TTY): a log file
    gets the two labelled lines, never the bar's carriage-return frames.
    """
    from rockdec import console

    start = time.perf_counter()
    print(f"{label}: started", file=sys.stderr, flush=True)
    with console.progress(label, stream=terminal if terminal is not None else sys.__stderr__):
        yield
    print(f"{label}: done in {time.perf_counter() - start:.1f} s", file=sys.stderr, flush=True)


def _process(pid: int, created: float):
    """The running process ``pid`` started at ``created`` (a reused pid is another process), or ``None``."""
    import psutil

    try:
        proc = psutil.Process(pid)
        return proc if abs(proc.create_time() - created) < 1e-3 and proc.status() != psutil.STATUS_ZOMBIE else None
    except psutil.Error:
        return None


def _record() -> dict:
    """This job's process and the processes above it up to the nearest Snakemake (all of them,
    pid 1 left out, when none is a Snakemake), as ``<log>.pid`` keeps them."""
    import psutil

    me = psutil.Process()
    parents = []
    for p in me.parents():
        if p.pid == 1:
            break
        parents.append([p.pid, p.create_time()])
        with contextlib.suppress(psutil.Error):
            if any("snakemake" in part for part in p.cmdline()):
                break
    return {"host": socket.gethostname(), "pid": me.pid, "created": me.create_time(), "parents": parents}


def _stop(proc) -> None:
    """Stop ``proc`` and every process under it: SIGTERM, then SIGKILL after :data:`STOP_WAIT_S`."""
    import psutil

    family = [*proc.children(recursive=True), proc]
    for p in family:
        with contextlib.suppress(psutil.Error):
            p.terminate()
    _, alive = psutil.wait_procs(family, timeout=STOP_WAIT_S)
    for p in alive:
        with contextlib.suppress(psutil.Error):
            p.kill()
    psutil.wait_procs(alive, timeout=STOP_WAIT_S)


@contextlib.contextmanager
def _claimed(smk, console):
    """Hold ``<log>.pid`` while the job runs; first deal with a job an earlier run left running."""
    pid_file = Path(f"{smk.log[0]}.pid")
    try:
        earlier = json.loads(pid_file.read_text())
    except (OSError, ValueError):
        earlier = None
    if earlier and earlier.get("host") == socket.gethostname():
        proc = _process(earlier["pid"], earlier["created"])
        if proc is not None and proc.pid != os.getpid():
            if all(_process(pid, created) is not None for pid, created in earlier["parents"]):
                raise InputError(
                    f"rule {smk.rule} is running already for these outputs (process {proc.pid}, under a Snakemake "
                    "that still runs); wait for it to finish, or stop that Snakemake first."
                )
            note = (f"stopping process {proc.pid}, an orphaned job of rule {smk.rule} left running by a Snakemake "
                    "that was killed, before this rerun of it")
            print(f"rockdec: {note}", file=sys.stderr, flush=True)
            print(f"rockdec: {note}", file=console, flush=True)
            _stop(proc)
    for path in map(Path, smk.output):
        if path.is_file() or path.is_symlink():
            path.unlink()  # written by an orphan after Snakemake cleared it for this job
    pid_file.write_text(json.dumps(_record()))
    try:
        yield
    finally:
        pid_file.unlink(missing_ok=True)

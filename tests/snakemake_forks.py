"""A process that has imported Snakemake and forks one child per Snakemake run.

Started by tests/conftest.py (:class:`Forks`), once per test process: each ``python -m
snakemake`` a test runs costs about 1 s of CPU in imports before Snakemake reads the
Snakefile, and most runs of the tests are dry runs of a second. A forked child starts with
those imports done and then is what ``python -m snakemake ARGS`` in the folder is: its
working directory first on ``sys.path`` (so the rules' ``find_spec("rockdec....")`` finds a
package copied there), the caller's environment, ``sys.argv``, its standard output and
error in files. rockdec is never imported here, so each child imports it afresh, from
wherever its ``sys.path`` finds it; the third-party libraries its rules import are (:func:`preload`).

Protocol, one JSON line each way per request. A run: ``{"cwd", "args", "env", "out", "err",
"preload", "background"}`` in (``preload``: load the libraries of the rules that run inside
Snakemake first, :func:`preload`); out ``{"code", "cpu"}`` when it ends, ``cpu`` the user +
system seconds of the child and of every process it waited for (its jobs) -- or, with
``background``, ``{"pid"}`` at once, the child the leader of a process group of its own.
Then ``{"wait": pid, "timeout"}`` in, :func:`ended` out.
"""

import json
import os
import sys
import time

import snakemake.api  # noqa: F401  (the imports every run pays: Snakemake, SQLAlchemy, pydantic)
import snakemake.cli
from snakemake_interface_executor_plugins.registry import ExecutorPluginRegistry

ExecutorPluginRegistry()  # loads the installed executor plugins (the SLURM one imports pandas)


def preload() -> None:
    """Import the libraries the rules that run inside Snakemake (tables, figures:
    rockdec.pipeline.steps) import, once, before the first run that may run them (a dry
    run does not: it is not worth the ~2 s). None starts a thread on import (fork-safe)."""
    import dask.array  # noqa: F401
    import flox  # noqa: F401
    import matplotlib

    matplotlib.use("Agg")  # as rockdec.report.figures does
    import matplotlib.pyplot  # noqa: F401
    import netCDF4  # noqa: F401
    import numba  # noqa: F401
    import scipy.stats  # noqa: F401
    import xarray  # noqa: F401


def child(request: dict) -> None:
    """Become ``python -m snakemake ARGS`` in ``cwd``; never returns."""
    code = 1
    try:
        os.chdir(request["cwd"])
        os.environ.clear()
        os.environ.update(request["env"])
        sys.path[0] = request["cwd"]
        sys.argv = [snakemake.cli.__file__, *request["args"]]
        for fd, path in ((1, request["out"]), (2, request["err"])):
            target = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
            os.dup2(target, fd)
            os.close(target)
        try:
            snakemake.cli.main(request["args"])
            code = 0
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    except BaseException:
        import traceback

        traceback.print_exc()
    finally:
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except Exception:
                pass
        os._exit(code)


def ended(pid: int, timeout: float) -> dict:
    """``{"code", "cpu"}`` of child ``pid`` once it ends, waiting up to ``timeout`` s;
    ``{"code": None}`` if it still runs then."""
    deadline = time.monotonic() + timeout
    while True:
        done, status, usage = os.wait4(pid, os.WNOHANG)
        if done:
            return {"code": os.waitstatus_to_exitcode(status), "cpu": usage.ru_utime + usage.ru_stime}
        if time.monotonic() >= deadline:
            return {"code": None}
        time.sleep(0.01)


def serve() -> None:
    for line in sys.stdin:
        request = json.loads(line)
        if "wait" in request:  # a run started in the background: has it ended?
            reply = ended(request["wait"], request["timeout"])
        else:
            if request["preload"]:
                preload()
            pid = os.fork()
            if pid == 0:
                if request["background"]:
                    os.setsid()  # a process group of its own, with its jobs, as a killed run needs
                child(request)
            reply = {"pid": pid} if request["background"] else ended(pid, float("inf"))
        print(json.dumps(reply), flush=True)

if __name__ == "__main__":
    serve()

"""A process that has imported Snakemake and forks one child per Snakemake run; with
``--python``, one that has imported the rockdec command's libraries and forks one child per
``python -c SCRIPT ARGS``.

Started by tests/conftest.py (:class:`Forks`), once per test process: each ``python -m
snakemake`` a test runs costs about 1 s of CPU in imports before Snakemake reads the
Snakefile, and most runs of the tests are dry runs of a second. A forked child starts with
those imports done and then is what ``python -m snakemake ARGS`` in the folder is: its
working directory first on ``sys.path`` (so the rules' ``find_spec("rockdec....")`` finds a
package copied there), the caller's environment, ``sys.argv``, its standard output and
error in files. rockdec is never imported by the Snakemake server, so each child imports it
afresh, from wherever its ``sys.path`` finds it; the third-party libraries its rules import
are (:func:`preload`). The ``--python`` server (:func:`load_python`) is for the tests whose
subject is a second process (a lock between two runs, a file-size limit): a ``python -c``
script that runs the rockdec command pays about 2 s of CPU in imports before it computes.

Protocol, one JSON line each way per request, on standard input and output. A run:
``{"cwd", "args", "env", "out", "err", "background"}`` in (and ``"python": true`` for a
script, ``args`` its text and arguments); out ``{"code", "cpu"}`` when it ends, ``cpu`` the
user + system seconds of the child and of every process it waited for (its jobs) -- or, with
``background``, ``{"pid"}`` at once, the child the leader of a process group of its own.
Then ``{"wait": pid, "timeout"}`` in, :func:`ended` out. ``{"collect": true}`` in:
``{"cpu"}`` out, the CPU of the runs asked for on the socket since the last answer on
standard output. Every answer's ``cpu`` also holds the server's own CPU since the last
answer (its start-up, :func:`preload`).

The socket (``python snakemake_forks.py SOCKET``): a command a shell runs
(``snakemake ARGS`` with ``PATH`` leading to a script that runs ``python snakemake_forks.py
--client SOCKET ARGS``, :func:`client`) asks for a run there, ``{"cwd", "args", "env",
"out", "err"}``, and gets ``{"code"}``; the client prints the run's output and exits with
its code, as ``snakemake ARGS`` would.
"""

import json
import os
import resource
import sys
import time

#: What a run imports after Snakemake's command-line module (a dry run of the tiny scene, its
#: ``sys.modules`` before and after): the report's and the profiles' code, the source cache's
#: URI parsing (smart_open, requests), the script rules' language detection (nbformat), the
#: config's YAML templating and validation. About 0.15 s of CPU a run.
RUN_IMPORTS = (
    "snakemake.report.html_reporter", "snakemake.profiles", "snakemake.storage", "smart_open", "nbformat",
    "requests", "docutils.core", "jinja2", "yte", "dpath", "fastjsonschema", "jsonschema", "PIL.Image",
    "argparse_dataclass", "graphlib", "packaging.version", "platformdirs",
)


def load_snakemake() -> None:
    """The imports every run pays: Snakemake, SQLAlchemy, pydantic, :data:`RUN_IMPORTS`, and
    the installed plugins of every kind (the SLURM executor imports pandas), whose registries
    (singletons) collect them once here instead of in every run's argument parser."""
    import importlib

    import snakemake.api  # noqa: F401
    import snakemake.cli  # noqa: F401
    from snakemake_interface_executor_plugins.registry import ExecutorPluginRegistry
    from snakemake_interface_logger_plugins.registry import LoggerPluginRegistry
    from snakemake_interface_report_plugins.registry import ReportPluginRegistry
    from snakemake_interface_scheduler_plugins.registry import SchedulerPluginRegistry
    from snakemake_interface_storage_plugins.registry import StoragePluginRegistry

    for name in RUN_IMPORTS:
        importlib.import_module(name)
    for registry in (ExecutorPluginRegistry, StoragePluginRegistry, ReportPluginRegistry, LoggerPluginRegistry, SchedulerPluginRegistry):
        registry()


def warm_numba() -> None:
    """Load numba's CPU target with every registry of its implementations, which the first
    compiled kernel a process calls (loaded from numba's cache) would load first: about
    0.3 s of CPU once here, instead of in each forked child that simulates."""
    from numba.core.registry import cpu_target

    cpu_target.target_context.refresh()


def preload() -> None:
    """Import the libraries the rules that run inside Snakemake (tables, figures:
    rockdec.pipeline.steps) import, once, before the first run, and :func:`warm_numba`. A dry
    run needs most of them too (the Snakefile imports rockdec's workflow code, which imports
    NumPy and xarray): loaded here once, a dry run of the tests costs about 0.5 s of CPU
    instead of 1.1 s. None starts a thread on import (fork-safe)."""
    import dask.array  # noqa: F401
    import flox  # noqa: F401
    import matplotlib

    matplotlib.use("Agg")  # as rockdec.report.figures does
    import matplotlib.pyplot  # noqa: F401
    import netCDF4  # noqa: F401
    import scipy.stats  # noqa: F401
    import xarray  # noqa: F401

    warm_numba()


def load_python() -> None:
    """The imports a ``python -c`` script of the tests pays before the rockdec command
    computes: NumPy, xarray, Dask, netCDF4, numba (:func:`warm_numba`) and rockdec's
    command and its numerical modules (rockdec from the server's ``sys.path``: the tests'
    scripts run the installed package). None starts a thread on import (fork-safe)."""
    import dask.array  # noqa: F401
    import netCDF4  # noqa: F401
    import xarray  # noqa: F401

    import rockdec.estimation  # noqa: F401
    import rockdec.cli  # noqa: F401
    import rockdec.io  # noqa: F401
    import rockdec.physics.simulate  # noqa: F401

    warm_numba()


#: What a process's forkserver imports before it forks Dask's workers, besides Dask's own
#: list (distributed, NumPy, pandas): the module the workers' tasks run, and so xarray, numba
#: and rockdec (about 0.8 s of CPU a worker).
DASK_WORKER_PRELOAD = ("rockdec.pipeline.replicates",)


def fork_dask_workers() -> None:
    """Before this process starts a Dask cluster of worker processes (the test process,
    tests/conftest.py; a Snakemake run on the ``processes:N`` engine, :func:`child`): its
    forkserver (:data:`DASK_WORKER_PRELOAD` added to what ``distributed`` asks it to load,
    from this process's ``sys.path``) forks each worker with those imports done, where a
    worker started afresh pays about 1.3 s of CPU in imports. Stopped with the process
    (:func:`stop_forkserver`)."""
    import multiprocessing.forkserver

    from distributed.utils import get_mp_context

    get_mp_context()  # distributed's own preload list, set once
    server = multiprocessing.forkserver._forkserver
    missing = [name for name in DASK_WORKER_PRELOAD if name not in server._preload_modules]
    if missing:
        server.set_forkserver_preload([*server._preload_modules, *missing])


def stop_forkserver() -> None:
    """End this process's multiprocessing forkserver (Dask's worker processes are forked by
    one, tests/conftest.py) if it runs, and wait for it: its CPU and that of the workers it
    forked then count as this process's children's, as a spawned worker's do. Called once
    its workers have ended (their clusters closed): SIGTERM ends it at once, where closing
    its pipe alone has it tear its interpreter down (distributed, pandas and rockdec loaded:
    about 0.5 s that the caller would wait for)."""
    import signal

    server = sys.modules.get("multiprocessing.forkserver")
    if server is not None and server._forkserver._forkserver_pid is not None:
        os.kill(server._forkserver._forkserver_pid, signal.SIGTERM)
        server._forkserver._stop()


def child(request: dict) -> None:
    """Become ``python -m snakemake ARGS`` in ``cwd`` (``python -c ARGS[0] ARGS[1:]`` for a
    request with ``"python"``); never returns."""
    code = 1
    try:
        os.chdir(request["cwd"])
        os.environ.clear()
        os.environ.update(request["env"])
        sys.path[0] = request["cwd"]
        for fd, path in ((1, request["out"]), (2, request["err"])):
            target = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
            os.dup2(target, fd)
            os.close(target)
        if request["env"].get("ROCKDEC_DASK_SCHEDULER", "").startswith("processes:") and not request.get("python"):
            fork_dask_workers()  # the run's cluster: its workers forked with rockdec loaded, from the run's sys.path
        try:
            if request.get("python"):
                script, *args = request["args"]
                sys.argv = ["-c", *args]
                exec(compile(script, "<string>", "exec"), {"__name__": "__main__"})
            else:
                import snakemake.cli

                sys.argv = [snakemake.cli.__file__, *request["args"]]
                snakemake.cli.main(request["args"])
            code = 0
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    except BaseException:
        import traceback

        traceback.print_exc()
    finally:
        stop_forkserver()
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


def fork(request: dict) -> int:
    """A child forked for the run ``request`` (:func:`child`), the libraries of the rules loaded
    first (:func:`preload`); its process id."""
    if not request.get("python"):
        preload()
    pid = os.fork()
    if pid == 0:
        if request.get("background"):
            os.setsid()  # a process group of its own, with its jobs, as a killed run needs
        child(request)
    return pid


def serve(socket_path: str | None = None, python: bool = False) -> None:
    """Answer the requests on standard input, and those on ``socket_path`` if given, until
    standard input closes; Snakemake's imports loaded first, or with ``python`` those of
    :func:`load_python`."""
    import selectors
    import socket

    if python:
        load_python()
    else:
        load_snakemake()
    reported = 0.0  # the server's own CPU reported so far (start-up, preload)
    events = selectors.DefaultSelector()
    events.register(sys.stdin, selectors.EVENT_READ)
    if socket_path:
        listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        listener.bind(socket_path)
        listener.listen()
        events.register(listener, selectors.EVENT_READ)
    elsewhere = 0.0  # CPU of the socket's runs not yet reported on standard output
    while True:
        for key, _ in events.select():
            if key.fileobj is sys.stdin:
                line = sys.stdin.readline()
                if not line:
                    return
                request = json.loads(line)
                if "wait" in request:  # a run started in the background: has it ended?
                    reply = ended(request["wait"], request["timeout"])
                elif "collect" in request:
                    reply, elsewhere = {"cpu": elsewhere}, 0.0
                else:
                    pid = fork(request)
                    reply = {"pid": pid} if request["background"] else ended(pid, float("inf"))
                own = resource.getrusage(resource.RUSAGE_SELF)
                reply["cpu"] = (reply.get("cpu") or 0.0) + own.ru_utime + own.ru_stime - reported
                reported = own.ru_utime + own.ru_stime
                print(json.dumps(reply), flush=True)
            else:
                connection, _ = listener.accept()
                with connection, connection.makefile("rw") as stream:
                    done = ended(fork(json.loads(stream.readline())), float("inf"))
                    elsewhere += done["cpu"]
                    stream.write(json.dumps({"code": done["code"]}) + "\n")


def client(socket_path: str, args: list[str]) -> None:
    """``snakemake ARGS`` as the fork server on ``socket_path`` runs it in this folder with this
    environment: its output printed, its exit code this process's."""
    import socket
    import tempfile

    with tempfile.TemporaryDirectory() as folder:
        out, err = os.path.join(folder, "out"), os.path.join(folder, "err")
        request = {"cwd": os.getcwd(), "args": args, "env": dict(os.environ), "out": out, "err": err}
        with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as connection:
            connection.connect(socket_path)
            with connection.makefile("rw") as stream:
                stream.write(json.dumps(request) + "\n")
                stream.flush()
                code = json.loads(stream.readline())["code"]
        with open(out) as text:
            sys.stdout.write(text.read())
        with open(err) as text:
            sys.stderr.write(text.read())
    sys.exit(code)


if __name__ == "__main__":
    if sys.argv[1:2] == ["--client"]:
        client(sys.argv[2], sys.argv[3:])
    elif sys.argv[1:2] == ["--python"]:
        serve(python=True)
    else:
        serve(*sys.argv[1:2])
    # standard input closed, every answer flushed: end without tearing down the interpreter
    # (Snakemake, Dask, matplotlib loaded: about a second that conftest.Forks.close waits for)
    os._exit(0)

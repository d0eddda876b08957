"""What several test modules share: one build of the tiny workflow per test session, the
Snakemake runs (forked from one process, :class:`Forks`), Dask's worker processes (forked
by a forkserver, :func:`fork_dask_workers`), the steps their records are simulated at
(:func:`calibrated_step`), the hypothesis profile, how xdist shares the tests among its
workers, and ``--cpu-durations`` (the CPU each test costs, with the subprocesses it waited
for and its Snakemake runs).

``tests/`` is on ``sys.path`` (pytest's rootdir-relative imports), so the test modules also
import their helpers from one another (``cf_check``, ``test_hostile``).
"""

from __future__ import annotations

import contextlib
import functools
import json
import os
import resource
import select
import shutil
import signal
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest
import yaml
from hypothesis import settings

from snakemake_forks import fork_dask_workers, stop_forkserver

# Property tests draw the same examples on every run (CI included): a failure is reproducible
# and a passing suite cannot turn red by the luck of a draw. Explore with
# HYPOTHESIS_PROFILE=explore (random draws, the example database on).
settings.register_profile("rockdec", derandomize=True, database=None)
settings.register_profile("explore", derandomize=False)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "rockdec"))

REPO = Path(__file__).resolve().parents[1]

# Dask's worker processes (the ``processes:N`` engine, :class:`SharedScheduler`, and those of
# the Snakemake runs, which inherit the variable) are forked by multiprocessing's forkserver,
# as Dask's own tests have them, instead of each started afresh: :func:`fork_dask_workers`.
os.environ["DASK_DISTRIBUTED__WORKER__MULTIPROCESSING_METHOD"] = "forkserver"

TINY = "tiny"
"""The default scene of the built copy."""


def calibrated_step(e: float, g: float, sigma_p: float, points_per_cycle: float = 75.0) -> dict:
    """:func:`rockdec.physics.simulate.calibrate_dt` with its default pilots (a copy of its
    result), computed once per test process for each set of arguments: several modules place
    their records at the same ``e``, ``g``, ``sigma_p`` and samples per cycle, and the pilots
    (fixed seeds, so the same step every time) cost 0.7-0.9 s of CPU."""
    return dict(_calibrated_step(e, g, sigma_p, points_per_cycle))


@contextlib.contextmanager
def capped_calibration_sets():
    """Calibrations of :data:`~rockdec.calibrate.calibration.SETS_PER_E_CAPPED` sets per ``e``
    (a fourth of the default's cost) for tests whose claims do not rest on the number of
    sets; the sets are in the calibration's cache key, so these never meet a default one.
    The number of sets is measured by the coverage study and
    ``benchmarks/calibration_replicates.py``."""
    from rockdec.calibrate import calibration

    with pytest.MonkeyPatch.context() as monkeypatch:
        monkeypatch.setattr(calibration, "SETS_PER_E", calibration.SETS_PER_E_CAPPED)
        yield


@pytest.fixture
def capped_sets():
    """:func:`capped_calibration_sets` for one test."""
    with capped_calibration_sets():
        yield


@functools.cache
def _calibrated_step(e: float, g: float, sigma_p: float, points_per_cycle: float) -> dict:
    from rockdec.physics.simulate import calibrate_dt

    return calibrate_dt(e=e, g=g, sigma_p=sigma_p, points_per_cycle=points_per_cycle)


class Forks:
    """The Snakemake runs of this test process, each a child forked by one process that has
    imported Snakemake (tests/snakemake_forks.py), started at the first run: a run then
    costs what Snakemake does, not its ~1 s of imports; a shell's ``snakemake`` commands
    too (:meth:`shell`). With ``python``, the ``python -c`` scripts of this process instead
    (:meth:`script`, :meth:`start_script`), forked by one that has imported the rockdec
    command's libraries (the Snakemake server forks them too: a worker that runs no
    :data:`SCRIPT_MODULES` starts no second server for one script). ``cpu``: the CPU seconds of every run so far and of the server
    itself (start-up, preloads; the children are the fork server's, not this process's)."""

    SERVER = Path(__file__).with_name("snakemake_forks.py")

    def __init__(self, python: bool = False):
        self.python = python
        self.proc = None
        self.cpu = 0.0
        self.folder = None  # the server's socket, and bin/snakemake that a shell finds (:meth:`shell`)

    def _ask(self, request: dict, timeout: float) -> dict:
        """One request to the fork server (started at the first), its answer within ``timeout`` s."""
        if self.proc is None or self.proc.poll() is not None:
            if self.python:
                command = [sys.executable, str(self.SERVER), "--python"]
            else:
                self.folder = Path(tempfile.mkdtemp(prefix="snakemake-forks-"))
                socket = self.folder / "socket"
                (self.folder / "bin").mkdir()
                script = self.folder / "bin" / "snakemake"
                script.write_text(f'#!/bin/sh\nexec "{sys.executable}" "{self.SERVER}" --client "{socket}" "$@"\n')
                script.chmod(0o755)
                command = [sys.executable, str(self.SERVER), str(socket)]
            self.proc = subprocess.Popen(command, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        self.proc.stdin.write(json.dumps(request) + "\n")
        self.proc.stdin.flush()
        ready, _, _ = select.select([self.proc.stdout], [], [], timeout)
        if not ready:
            self.proc.kill()
            raise TimeoutError(f"the Snakemake fork server gave no answer to {request} in {timeout} s")
        reply = json.loads(self.proc.stdout.readline())
        self.cpu += reply.get("cpu") or 0.0
        return reply

    def _request(self, workdir, args, env, out, err, background: bool) -> dict:
        return {"cwd": str(Path(workdir).resolve()), "args": [str(a) for a in args], "env": dict(os.environ if env is None else env),
                "out": str(out), "err": str(err), "background": background}

    def run(self, workdir, args, timeout: float = 900.0, env: dict | None = None) -> tuple[int, str, str]:
        """``python -m snakemake *args`` in ``workdir`` with environment ``env`` (default this
        process's): exit code, standard output and standard error."""
        with tempfile.TemporaryDirectory() as folder:
            out, err = Path(folder) / "out", Path(folder) / "err"
            reply = self._ask(self._request(workdir, args, env, out, err, background=False), timeout)
            return reply["code"], out.read_text(), err.read_text()

    def shell(self, workdir, command: str, env: dict | None = None, timeout: float = 900.0) -> tuple[int, str, str]:
        """``bash -c command`` in ``workdir`` with environment ``env`` (default this process's),
        ``snakemake`` on its ``PATH`` a client of the fork server (each run forked, as
        :meth:`run`; ``python -m snakemake ARGS`` for ``snakemake ARGS``): exit code, standard
        output and standard error."""
        self._ask({"collect": True}, 60.0)  # the server runs and listens
        env = dict(os.environ if env is None else env)
        env["PATH"] = f"{self.folder / 'bin'}{os.pathsep}{env.get('PATH', '')}"
        done = subprocess.run(["bash", "-c", command], cwd=workdir, env=env, capture_output=True, text=True, timeout=timeout)
        self._ask({"collect": True}, 60.0)  # the CPU of the runs, into self.cpu
        return done.returncode, done.stdout, done.stderr

    def start(self, workdir, args, env: dict | None = None) -> "Forked":
        """``python -m snakemake *args`` in ``workdir`` in the background, the leader of a
        process group of its own (with its jobs), its output discarded."""
        return Forked(self, self._ask(self._request(workdir, args, env, os.devnull, os.devnull, background=True), 60.0)["pid"])

    def script(self, script: str, *args, timeout: float = 300.0) -> tuple[int, str, str]:
        """``python -c script *args`` (:meth:`start_script`), waited for: exit code, standard
        output and standard error. Killed if it runs longer than ``timeout`` s."""
        with tempfile.TemporaryDirectory() as folder:
            proc = self.start_script(script, *args, output=Path(folder) / "script")
            try:
                out, err = proc.communicate(timeout)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait(60.0)
                raise
            return proc.returncode, out, err

    def start_script(self, script: str, *args, output: Path) -> "Forked":
        """``python -c script *args`` in this process's folder and environment, in the
        background, the leader of a process group of its own; its standard output and error
        in ``output``.out and ``output``.err (:meth:`Forked.communicate`). Forked with the
        server's imports done: a server made with ``python``, the rockdec command's libraries;
        the Snakemake server, Snakemake's (and, after a run of rules, the rules' libraries)."""
        out, err = output.with_suffix(".out"), output.with_suffix(".err")
        reply = self._ask({**self._request(os.getcwd(), [script, *args], None, out, err, background=True), "python": True}, 60.0)
        return Forked(self, reply["pid"], out, err)

    def close(self):
        if self.proc is not None:
            self.proc.stdin.close()
            self.proc.wait(timeout=60)
            self.proc.stdout.close()
            if self.folder is not None:
                shutil.rmtree(self.folder, ignore_errors=True)


class Forked:
    """A run started by :meth:`Forks.start` or :meth:`Forks.start_script`: what a test reads
    of a ``Popen``."""

    def __init__(self, forks: Forks, pid: int, out: Path | None = None, err: Path | None = None):
        self.forks, self.pid, self.returncode = forks, pid, None
        self.out, self.err = out, err

    def wait(self, timeout: float | None = None) -> int:
        """Its exit code (minus the signal that ended it), waiting up to ``timeout`` s."""
        if self.returncode is None:
            wait = 3600.0 if timeout is None else timeout
            self.returncode = self.forks._ask({"wait": self.pid, "timeout": wait}, wait + 60.0)["code"]
            if self.returncode is None:
                raise subprocess.TimeoutExpired(f"snakemake (process {self.pid})", wait)
        return self.returncode

    def poll(self) -> int | None:
        """Its exit code if it has ended, else ``None``."""
        try:
            return self.wait(0.0)
        except subprocess.TimeoutExpired:
            return None

    def communicate(self, timeout: float | None = None) -> tuple[str, str]:
        """Its standard output and error (:meth:`Forks.start_script`), once it has ended."""
        self.wait(timeout)
        return self.out.read_text(), self.err.read_text()


FORKS = Forks()

PYTHON_FORKS = Forks(python=True)
"""The ``python -c`` scripts of the tests whose subject is a second process (:data:`SCRIPT_MODULES`)."""


def pytest_sessionfinish(session):
    FORKS.close()
    PYTHON_FORKS.close()
    SCHEDULER.close()
    stop_forkserver()


def snakemake(workdir, *args) -> tuple[int, str]:
    """``python -m snakemake --cores 2 *args`` in ``workdir`` (:class:`Forks`): exit code and output."""
    code, out, err = FORKS.run(workdir, ["--cores", "2", *args])
    return code, out + err


def copy_workflow(root: Path) -> Path:
    """The repository's workflow in ``root``, its default scene the tiny scene shrunk to 2
    replicates of 10 series (the fewest the groups_of_10 reading accepts), every series
    stored (``store_series: all``, so the archive holds them) and a fixed step."""
    shutil.copy(REPO / "Snakefile", root)
    for folder in ("workflow", "config", "profiles"):
        shutil.copytree(REPO / folder, root / folder)  # resolves config/schema.yaml
    config = yaml.safe_load((REPO / "config" / "config.yaml").read_text())
    config["default_scene"] = TINY
    scene = config["scenes"][TINY]
    scene["records"].update(replicates=2, series_per_replicate=10, store_series="all", chunk_seeds=10)
    scene["excitation"]["dt"] = 0.0034
    (root / "config" / "config.yaml").write_text(yaml.safe_dump(config, sort_keys=False))
    return root


@pytest.fixture(scope="session")
def tiny_workflow(tmp_path_factory) -> dict:
    """A copy of the workflow (:func:`copy_workflow`), dry-run, then built once with the
    archive of its scene (``snakemake --cores 2 all archive``): ``root`` and ``dry_run``
    (the dry run's output, before the build) and ``log`` (the build's). Tests that change it put it back."""
    root = copy_workflow(tmp_path_factory.mktemp("workflow"))
    code, dry = snakemake(root, "-n")
    assert code == 0, dry
    code, log = snakemake(root, "all", "archive")
    assert code == 0, log
    return {"root": root, "dry_run": dry, "log": log}


class SharedScheduler:
    """A Dask scheduler on loopback with two worker processes, started for the first test
    that asks for :func:`dask_scheduler` and closed after the last test of the session marked
    ``dask_scheduler`` (those that ask for it), since an idle cluster costs about 0.08 CPU s
    a second in heartbeats: a cluster costs about 1 s to start and its workers 1 to 2 s each
    to import what the first tasks need, once."""

    def __init__(self):
        self.cluster = None
        self.users = 0  # tests of the session that ask for it and have not run yet

    def address(self) -> str:
        if self.cluster is None:
            from dask.distributed import LocalCluster

            fork_dask_workers()
            self.cluster = LocalCluster(n_workers=2, threads_per_worker=1, host="127.0.0.1", dashboard_address=None)
        return self.cluster.scheduler_address

    def done(self, item) -> None:
        """After ``item``: close the cluster once no test left of the session uses it."""
        if item.get_closest_marker("dask_scheduler"):
            self.users -= 1
            if self.users <= 0:
                self.close()

    def close(self) -> None:
        if self.cluster is not None:
            self.cluster.close()
            self.cluster = None


SCHEDULER = SharedScheduler()


def pytest_collection_finish(session):
    SCHEDULER.users = sum(bool(item.get_closest_marker("dask_scheduler")) for item in session.items)


@pytest.fixture
def dask_scheduler(request) -> str:
    """The address of :data:`SCHEDULER`'s running Dask scheduler, for a test marked
    ``dask_scheduler`` (test_engine.py and test_workflow.py give it to the engine; one worker
    runs both, :data:`WORKFLOW_MODULES`)."""
    assert request.node.get_closest_marker("dask_scheduler"), f"{request.node.nodeid} asks for dask_scheduler unmarked"
    return SCHEDULER.address()


def pytest_runtest_teardown(item, nextitem):
    SCHEDULER.done(item)


#: The test modules one worker runs, in this order: those that use :func:`tiny_workflow` (one
#: build, and no two tests change it at once), :func:`dask_scheduler` (one cluster) or
#: :data:`FORKS` (one fork server, about 1.4 s of CPU to start).
WORKFLOW_MODULES = (
    "tests/pipeline/test_workflow.py",
    "tests/pipeline/test_campaign_workflow.py",
    "tests/test_engine.py",
    "tests/pipeline/test_archive.py",
    "tests/pipeline/test_workflow_rules.py",
    "tests/pipeline/test_config.py",
)

#: The test modules one worker runs, in this order: those that fork scripts from
#: :data:`PYTHON_FORKS` (one server, about 1.3 s of CPU to start).
SCRIPT_MODULES = (
    "tests/test_hostile.py",
    "tests/pipeline/test_in_snakemake.py",
)

#: The modules whose tests cost the most CPU (``--cpu-durations``), costliest first; the
#: other modules (about 1 s or less each) follow in their collection order.
COSTLIEST_FIRST = (
    *WORKFLOW_MODULES,
    *SCRIPT_MODULES,
    "tests/calibrate/test_estimate.py",
    "tests/studies/test_coverage.py",
    "tests/pipeline/test_figure_workers.py",
    "tests/test_cli.py",
    "tests/report/test_figures.py",
    "tests/record/test_diagnostics.py",
    "tests/rdd/test_signatures.py",
    "tests/physics/test_load_spectrum.py",
    "tests/test_io.py",
    "tests/calibrate/test_estimate_model.py",
    "tests/physics/test_housner.py",
    "tests/pipeline/test_replicates.py",
    "tests/physics/test_record_model.py",
    "tests/physics/test_simulate.py",
    "tests/rdd/test_estimators.py",
    "tests/rdd/test_estimator_checks.py",
    "tests/studies/test_diagnostics_study.py",
    "tests/record/test_record_measure.py",
)


def pytest_collection_modifyitems(config, items):
    """The modules of :data:`COSTLIEST_FIRST` first, each module's tests in their order:
    xdist hands out modules in this order as workers run short, so the last ones are short
    and both workers end together (the suite lasts as long as its busiest worker). The tests
    marked ``dask_scheduler`` run one after the other (:class:`SharedScheduler` idles in
    between): last in the first module that has some, first in the next ones."""
    rank = {module: i for i, module in enumerate(COSTLIEST_FIRST)}

    def module(item) -> str:
        return item.nodeid.split("::")[0]

    def order(item) -> tuple[int, int]:
        place = rank.get(module(item), len(rank))
        if not item.get_closest_marker("dask_scheduler"):
            return place, 0
        return place, 1 if place == first else -1

    first = min((rank.get(module(i), len(rank)) for i in items if i.get_closest_marker("dask_scheduler")), default=None)
    items.sort(key=order)


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config, log):
    """With pytest-xdist (``-n``, pyproject.toml): a worker runs every test of a module, so
    each module-scoped fixture is built once, one worker runs :data:`WORKFLOW_MODULES` and
    one :data:`SCRIPT_MODULES`; modules are handed out in collection order
    (:func:`pytest_collection_modifyitems`), not by their number of tests."""
    from xdist.scheduler import LoadFileScheduling

    config.option.loadscopereorder = False

    class ByModule(LoadFileScheduling):
        def _split_scope(self, nodeid: str) -> str:
            module = super()._split_scope(nodeid)
            for group in (WORKFLOW_MODULES, SCRIPT_MODULES):
                if module in group:
                    return group[0]
            return module

    return ByModule(config, log)


# --------------------------------------------------------------------------- CPU per test


def pytest_addoption(parser):
    parser.addoption(
        "--cpu-durations", type=int, default=None, metavar="N",
        help="list the N tests that cost the most CPU seconds (user + sys of the test process and of every "
        "subprocess it waited for, setup to teardown) and each worker's sum: on a shared machine CPU, unlike "
        "the wall time --durations lists, does not grow with the load.",
    )


def _forkserver_cpu() -> float:
    """User + system CPU of this process's running forkserver (:func:`fork_dask_workers`) and
    of the Dask workers it forked and reaped, in s (0 when none runs)."""
    server = sys.modules.get("multiprocessing.forkserver")
    pid = server and server._forkserver._forkserver_pid
    if not pid:
        return 0.0
    try:
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
    except OSError:
        return 0.0
    return sum(int(x) for x in fields[11:15]) / os.sysconf("SC_CLK_TCK")  # utime, stime, cutime, cstime


def _cpu_seconds() -> float:
    """User + system CPU of this process, of its waited-for children, of its forked runs
    (:class:`Forks`, with the fork servers' own) and of its forkserver's (Dask's workers), in s."""
    own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime + FORKS.cpu + PYTHON_FORKS.cpu + _forkserver_cpu()


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    item._cpu_start = _cpu_seconds()
    yield


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    if call.when == "teardown" and item.config.getoption("cpu_durations") is not None:
        worker = os.environ.get("PYTEST_XDIST_WORKER", "main")  # the report travels to the xdist controller
        outcome.get_result().user_properties += [("cpu_s", _cpu_seconds() - item._cpu_start), ("worker", worker)]


_CPU_ROWS: list[tuple[float, str, str]] = []
"""(CPU s, worker, test) of every test run, gathered where the reports arrive (the xdist controller)."""


def pytest_runtest_logreport(report):
    found = dict(report.user_properties)
    if report.when == "teardown" and "cpu_s" in found:
        _CPU_ROWS.append((found["cpu_s"], found["worker"], report.nodeid))


def pytest_terminal_summary(terminalreporter, config):
    count = config.getoption("cpu_durations")
    if count is None:
        return
    per_worker: dict[str, float] = {}
    for seconds, worker, _ in _CPU_ROWS:
        per_worker[worker] = per_worker.get(worker, 0.0) + seconds
    shown = sorted(_CPU_ROWS, reverse=True)[: count or None]
    terminalreporter.write_sep("=", f"CPU seconds of the {len(shown)} costliest tests (--cpu-durations)")
    for seconds, worker, nodeid in shown:
        terminalreporter.write_line(f"{seconds:8.2f} {worker:>5} {nodeid}")
    totals = ", ".join(f"{worker} {seconds:.1f}" for worker, seconds in sorted(per_worker.items()))
    terminalreporter.write_line(f"CPU s per worker (the tests, without start-up and collection): {totals}; all {sum(per_worker.values()):.1f}")

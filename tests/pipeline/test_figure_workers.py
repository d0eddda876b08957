"""The worker processes that draw the workflow's figures (rockdec.pipeline.figure_workers),
through the figure rules' entry point (rockdec.pipeline.in_snakemake.draw), without Snakemake."""

import os
import re
import signal
import threading

import pytest

from rockdec.pipeline import figure_workers, in_snakemake, steps
from rockdec.validate import InputError

#: Worker processes started, killed and replaced: the slow tier (docs/development/testing.md).
pytestmark = pytest.mark.slow


@pytest.fixture(scope="module", autouse=True)
def workers():
    """One set of workers for the module (each loads matplotlib), ended after it."""
    yield
    figure_workers.close()


def test_a_figure_drawn_by_a_worker_is_the_figure_drawn_here_byte_for_byte_and_logged(tmp_path):
    here = [tmp_path / "here.png", tmp_path / "here.pdf"]
    steps.fig1b(here)
    there = [tmp_path / "there.png", tmp_path / "there.pdf"]
    log = tmp_path / "fig1b.log"
    in_snakemake.draw("fig1b", str(log), [str(p) for p in there])
    assert [p.read_bytes() for p in there] == [p.read_bytes() for p in here]
    lines = log.read_text().splitlines()
    assert lines[0] == "fig1b: started" and re.fullmatch(r"fig1b: done in [\d.]+ s", lines[1]) and len(lines) == 2
    assert len(figure_workers._workers) == figure_workers.PROCESSES and len(figure_workers._processes) == 1  # the others forked


def test_two_figures_draw_at_once_in_the_two_workers(tmp_path):
    errors = []

    def one(k):
        try:
            figure_workers.draw("fig1b", [str(tmp_path / f"{k}.png"), str(tmp_path / f"{k}.pdf")])
        except Exception as exc:  # reported below
            errors.append(exc)

    threads = [threading.Thread(target=one, args=(k,)) for k in range(3)]  # one more than the workers: it waits
    for t in threads:
        t.start()
    for t in threads:
        t.join(120)
    assert not errors
    assert len({(tmp_path / f"{k}.png").read_bytes() for k in range(3)}) == 1
    assert len(figure_workers._workers) == figure_workers.PROCESSES


def test_a_users_error_in_a_worker_is_raised_here_as_its_sentence_and_logged(tmp_path):
    log = tmp_path / "fig3.log"
    missing = tmp_path / "estimates.nc"
    with pytest.raises(InputError) as err:
        in_snakemake.draw("fig3", str(log), str(missing), [str(tmp_path / "f.png"), str(tmp_path / "f.pdf")])
    assert str(err.value) == f"input '{missing}' does not exist; run the step that makes it first."
    assert log.read_text().splitlines() == ["fig3: started", f"rockdec: error: {err.value}"]


def answered() -> bool:
    """A request that a worker answers at once, with the traceback of a step it lacks."""
    with pytest.raises(figure_workers.WorkerError, match=r"(?s)Traceback.*AttributeError.*no_such_step"):
        figure_workers.draw("no_such_step")
    return True


def test_another_error_in_a_worker_brings_its_traceback_from_the_rockdec_this_process_runs():
    with pytest.raises(figure_workers.WorkerError) as err:
        figure_workers.draw("no_such_step")
    assert f'File "{figure_workers.__file__}"' in str(err.value)  # the worker's module path is this process's


class _Exit:
    """Unpickled by a worker, ends it at once (as a crash would) before it answers."""

    def __reduce__(self):
        return os._exit, (3,)


def test_workers_ignore_ctrl_c_and_one_that_ends_is_replaced_and_gets_the_figure_again():
    every = figure_workers.PROCESSES
    assert answered()  # started
    first = figure_workers._processes[0]
    for pid in _worker_pids(first.pid):
        os.kill(pid, signal.SIGINT)
    assert all(answered() for _ in range(every))
    first.kill()  # the first worker, while idle; the one it forked goes on
    first.wait()
    assert all(answered() for _ in range(2 * every))  # the killed one's turn among them: asked again of a new one
    assert len(figure_workers._workers) == every and len(figure_workers._processes) == 2
    with pytest.raises(figure_workers.WorkerError, match=r"the process drawing fig1b ended before it finished, twice"):
        figure_workers.draw("fig1b", _Exit())  # ends its worker, and the new one
    assert all(answered() for _ in range(every))


def _worker_pids(first: int) -> list[int]:
    """The first worker's pid and those of the workers it forked (its children)."""
    with open(f"/proc/{first}/task/{first}/children") as f:
        return [first, *map(int, f.read().split())]


def test_close_ends_the_workers_and_waits_for_them():
    figure_workers.close()
    assert answered()  # a new set
    started = list(figure_workers._processes)
    forked = _worker_pids(started[0].pid)[1:]
    assert len(started) == 1 and len(forked) == figure_workers.PROCESSES - 1
    figure_workers.close()
    assert not figure_workers._workers and [p.returncode for p in started] == [0] * len(started)
    for pid in forked:
        with pytest.raises(ProcessLookupError):
            os.kill(pid, 0)  # ended and reaped by the first worker

"""The worker processes that draw the workflow's figures (rockdec.pipeline.figure_workers),
through the figure rules' entry point (rockdec.pipeline.in_snakemake.draw), without Snakemake."""

import os
import re
import signal
import threading

import pytest

from rockdec.pipeline import figure_workers, in_snakemake, steps
from rockdec.validate import InputError


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
    assert len(figure_workers._workers) == figure_workers.PROCESSES
    assert all(w.process.pid != os.getpid() for w in figure_workers._workers)


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


def test_another_error_in_a_worker_brings_its_traceback():
    assert answered()


class _Exit:
    """Unpickled by a worker, ends it at once (as a crash would) before it answers."""

    def __reduce__(self):
        return os._exit, (3,)


def test_a_worker_ignores_ctrl_c_one_ended_while_idle_is_replaced_and_one_that_ends_fails_its_figure():
    every = figure_workers.PROCESSES
    assert answered()  # started
    for worker in list(figure_workers._workers):
        os.kill(worker.process.pid, signal.SIGINT)
    assert all(answered() for _ in range(every))
    killed = figure_workers._workers[0]
    killed.process.kill()
    killed.process.wait()
    assert all(answered() for _ in range(every))  # one of them the killed one's turn
    with pytest.raises(figure_workers.WorkerError, match=r"the process drawing fig1b ended \(exit code 3\)"):
        figure_workers.draw("fig1b", _Exit())
    assert all(answered() for _ in range(every))
    assert len(figure_workers._workers) == every and killed not in figure_workers._workers
    assert all(w.process.poll() is None for w in figure_workers._workers)


def test_close_ends_the_workers_and_waits_for_them():
    assert answered()
    started = list(figure_workers._workers)
    figure_workers.close()
    assert not figure_workers._workers and [w.process.returncode for w in started] == [0] * len(started)

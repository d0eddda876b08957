"""The workflow's rules that run inside the Snakemake process: the run contract, the stored
series and their signature, the tables and the figures.

``calibrate`` (a second of pilot simulations), ``stored_series``, ``stored_signature``,
``estimates``, ``table_readings`` and the paper's figure rules take a fraction of a second
to a few seconds each once NumPy, numba, xarray and matplotlib are loaded, so they are
``run:`` rules calling :func:`calibrate` and :func:`step` (the workflow's default profile
runs those in threads of the Snakemake process, ``force-use-threads``) and load those
libraries once a run instead of starting Python for each. The signature pass and the other
compute rules stay scripts (:mod:`rockdec.pipeline.job`); this module is apart from that one
so that the scripts' code inputs (:func:`rockdec.sources.package_sources`) do not reach
:mod:`rockdec.pipeline.steps` and the figures through it.
"""

from __future__ import annotations

import threading
import time
import traceback

from rockdec.validate import InputError

#: What the steps after the signature pass load on their first run and nothing before them
#: does: the tables' code, xarray's groupby engine (flox, numpy_groupies) and the
#: p-values' scipy.stats. :func:`calibrate` imports them in a thread of their own once the
#: run contract is written, while the signature pass starts Python (one core idle), instead
#: of on the path after the pass, where the tables and figures run one at a time.
PRELOAD = ("rockdec.pipeline.replicates", "rockdec.report.tables", "flox", "scipy.stats")

#: One :func:`step` at a time in a process: matplotlib (its fonts) and the HDF5 library
#: under netCDF4 are not safe to use from two threads at once.
_STEP_LOCK = threading.Lock()


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
        from rockdec.pipeline import steps

        getattr(steps, rule)(*args)

    with _STEP_LOCK:
        _logged(rule, log, work)


def calibrate(log: str, physics: dict, output: str) -> None:
    """Rule ``calibrate``: the run contract of a scene's ``physics`` (its ``model``, ``system``
    and ``excitation`` sections; :func:`rockdec.physics.run.calibrate`) written to ``output``
    (``run.json``), logged as :func:`step` logs, with the contract on a line of its own.

    Pilot simulations and a JSON file: neither matplotlib nor HDF5, so it takes no
    :data:`_STEP_LOCK` and a figure that needs no data (fig. 1b) draws meanwhile. Then the
    modules of :data:`PRELOAD` load beside the signature pass.
    """

    def work():
        from rockdec.physics import run

        contract = run.calibrate(physics)
        contract.write(output)
        return f"run: {contract}"

    _logged("calibrate", log, work)
    threading.Thread(target=_preload, name="rockdec-preload", daemon=True).start()


def _preload() -> None:
    """Import the modules of :data:`PRELOAD`."""
    import importlib

    for name in PRELOAD:
        importlib.import_module(name)


def _logged(rule: str, log: str, work) -> None:
    """``work()`` with the log of :func:`step`: a start line, what ``work`` returns (a line of
    text, or ``None``), an end line; a user error's sentence or a traceback on failure."""
    with open(log, "w") as out:
        start = time.perf_counter()
        print(f"{rule}: started", file=out, flush=True)
        try:
            note = work()
        except InputError as exc:
            print(f"rockdec: error: {exc}", file=out, flush=True)
            raise
        except Exception:
            traceback.print_exc(file=out)
            raise
        if note is not None:
            print(note, file=out, flush=True)
        print(f"{rule}: done in {time.perf_counter() - start:.1f} s", file=out, flush=True)

"""The workflow's rules that run inside the Snakemake process: the tables and figures.

``estimates``, ``table_readings`` and the paper's figure rules read finished products and
take a fraction of a second each once xarray, matplotlib and the estimators' kernels are
loaded, so they are ``run:`` rules calling :func:`step` (the workflow's default profile
runs those in threads of the Snakemake process, ``force-use-threads``) and load those
libraries once a run instead of starting Python for each. The compute rules stay scripts
(:mod:`rockdec.pipeline.job`); this module is apart from that one so that the scripts' code inputs
(:func:`rockdec.sources.package_sources`) do not reach :mod:`rockdec.pipeline.steps` and the
figures through it.
"""

from __future__ import annotations

import threading
import time
import traceback

from rockdec.validate import InputError

#: One :func:`step` at a time in a process: matplotlib (its fonts) and the HDF5 library
#: under netCDF4 are not safe to use from two threads at once.
_STEP_LOCK = threading.Lock()


def step(rule: str, log: str, *args) -> None:
    """Run rule ``rule`` as the :mod:`rockdec.pipeline.steps` function of that name, on ``*args``,
    inside the Snakemake process. Steps run one at a time (:data:`_STEP_LOCK`); the
    compute rules' scripts run beside them.

    The log (``log``) gets a line at the start and at the end; an error the user can fix
    (:class:`rockdec.validate.InputError`) is written there as its one sentence and raised
    again for Snakemake to report; any other exception leaves its traceback there too.
    Standard error is left alone: the Snakemake process and its other threads share it.
    """
    with _STEP_LOCK, open(log, "w") as out:
        start = time.perf_counter()
        print(f"{rule}: started", file=out, flush=True)
        try:
            from rockdec.pipeline import steps

            getattr(steps, rule)(*args)
        except InputError as exc:
            print(f"rockdec: error: {exc}", file=out, flush=True)
            raise
        except Exception:
            traceback.print_exc(file=out)
            raise
        print(f"{rule}: done in {time.perf_counter() - start:.1f} s", file=out, flush=True)

"""Where Dask computes: one setting for every compute path of the package and the workflow.

``ROCKDEC_DASK_SCHEDULER`` (environment variable; a caller may pass ``scheduler=`` instead)
names the engine:

``threads`` (the default)
    Dask's local threads, as many as the caller's ``threads`` (a Snakemake rule's
    ``threads``, so concurrent jobs never exceed ``--cores``). The numba kernels release
    the GIL, so threads run them in parallel.
``processes:N``
    a ``dask.distributed`` cluster of ``N`` single-threaded worker processes on this
    machine (loopback), started for the computation and closed after it.
``tcp://host:port``
    a running ``dask.distributed`` scheduler (for instance one started on a cluster by
    ``dask scheduler`` with workers on other nodes); the computation is sent there.

Results do not depend on the engine: every series depends on its seed only and every
reduction runs over the same chunks in the same order, so the numbers are equal bit for
bit (tested with a two-worker local cluster). Timing studies that measure a
configuration's CPU seconds by thread time stay on threads and say so.
"""

from __future__ import annotations

import contextlib
import contextvars
import os
import sys

from rockdec.validate import InputError

__all__ = ["SchedulerError", "VARIABLE", "compute", "compute_in_place", "session", "setting"]

#: The environment variable that names the engine.
VARIABLE = "ROCKDEC_DASK_SCHEDULER"

#: The engine when nothing is set.
DEFAULT = "threads"


class SchedulerError(InputError):
    """A scheduler setting that names no engine; the message says what is accepted."""


def setting(scheduler: str | None = None) -> tuple[str, int | str | None]:
    """The engine named by ``scheduler`` or, when ``None``, by ``ROCKDEC_DASK_SCHEDULER``.

    Returns ``("threads", None)``, ``("processes", N)`` or ``("address", "tcp://...")``.
    """
    source = "the Dask engine" if scheduler is not None else VARIABLE
    text = (scheduler if scheduler is not None else os.environ.get(VARIABLE, DEFAULT)).strip()
    if text == "threads":
        return "threads", None
    if text.startswith("processes:"):
        count = text.split(":", 1)[1]
        if count.isascii() and count.isdigit() and int(count) >= 1:  # ASCII: '²' is a digit to str.isdigit, not to int
            return "processes", int(count)
    elif text.startswith("tcp://") and len(text) > len("tcp://"):
        return "address", text
    raise SchedulerError(
        f"{source} {text!r} names no Dask engine; use 'threads', 'processes:N' (N >= 1 local worker "
        "processes) or a scheduler address 'tcp://host:port'."
    )


#: Seconds to reach a ``tcp://`` scheduler before giving up.
CONNECT_S = 5.0


def _probe(address: str) -> None:
    """Refuse at once a ``tcp://`` address that nothing listens on, or whose listener does
    not greet like a Dask scheduler (its first 8 bytes are the little-endian length of a
    small handshake message); the Dask client would wait, or read garbage as a length."""
    import socket
    import struct
    from urllib.parse import urlsplit

    where = urlsplit(address)
    try:
        with socket.create_connection((where.hostname, where.port), timeout=CONNECT_S) as sock:
            head = b""
            while len(head) < 8:
                chunk = sock.recv(8 - len(head))
                if not chunk:
                    break
                head += chunk
    except (OSError, ValueError) as exc:
        raise SchedulerError(f"the Dask scheduler {address!r} cannot be reached ({exc}); start it, or use 'threads'.") from None
    if len(head) < 8 or not 0 < struct.unpack("<Q", head)[0] < 2**20:
        raise SchedulerError(f"{address!r} answers, but not as a Dask scheduler; give the address of a running 'dask scheduler'.")


_active = contextvars.ContextVar("rockdec_engine_active", default=False)


@contextlib.contextmanager
def session(threads: int | None = None, scheduler: str | None = None):
    """Run the Dask computations inside the block on the configured engine.

    ``threads``: workers of the ``threads`` engine (``None``: Dask's own setting, all
    cores unless the caller set ``num_workers``); the other engines size themselves. A
    session inside a session uses the outer one's engine (no second cluster).
    """
    if _active.get():
        yield
        return
    kind, value = setting(scheduler)
    token = _active.set(True)
    try:
        if kind == "threads":
            options = {"scheduler": "threads"} if threads is None else {"scheduler": "threads", "num_workers": max(1, int(threads))}
            with _dask_config(options):
                yield
        elif kind == "processes":
            import dask
            from dask.distributed import Client, LocalCluster

            with LocalCluster(n_workers=value, threads_per_worker=1, processes=True, host="127.0.0.1",
                              dashboard_address=None) as cluster, Client(cluster) as client:
                with dask.config.set(scheduler=client):
                    yield
        else:
            import dask
            from dask.distributed import Client

            _probe(value)
            with Client(value, timeout=f"{CONNECT_S}s") as client, dask.config.set(scheduler=client):
                yield
    finally:
        _active.reset(token)


@contextlib.contextmanager
def _dask_config(options: dict):
    """Dask's configuration ``options`` inside the block. While Dask is not loaded, they go
    to the environment variables Dask reads when it loads (``DASK_SCHEDULER``,
    ``DASK_NUM_WORKERS``), so a command that computes nothing with Dask (``rockdec
    estimate`` with its calibration cached) never loads it; the variables are restored after
    the block and Dask, if it was loaded meanwhile, reads its configuration again."""
    if "dask" in sys.modules:
        with sys.modules["dask"].config.set(options):
            yield
        return
    names = {f"DASK_{key.upper()}": str(value) for key, value in options.items()}
    before = {name: os.environ.get(name) for name in names}
    os.environ.update(names)
    try:
        yield
    finally:
        for name, text in before.items():
            if text is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = text
        if "dask" in sys.modules:
            sys.modules["dask"].config.refresh()


def compute(*collections, threads: int | None = None, scheduler: str | None = None):
    """``dask.compute(*collections)`` on the configured engine (:func:`session`).

    On the ``threads`` engine outside a session, the threads are given to the call itself
    instead of to Dask's configuration, which the whole process shares: computations in two
    threads of one process (the workflow's signature pass and a light step inside Snakemake,
    :mod:`rockdec.pipeline.in_snakemake`) each keep their own number of threads. The call
    names Dask's threaded scheduler by its function (``dask.threaded.get``), not by the name
    ``"threads"``, whose lookup imports ``dask.distributed`` to look for a client.
    """
    import dask

    own = _own_threads(threads, scheduler)
    if own is not None:
        return dask.compute(*collections, **own)
    with session(threads, scheduler):
        return dask.compute(*collections)


def _own_threads(threads: int | None, scheduler: str | None) -> dict | None:
    """Dask's keywords for a call on threads of its own (the ``threads`` engine outside a
    session, :func:`compute`): Dask's threaded scheduler by its function and ``threads``
    workers; None on any other engine or inside a session."""
    if _active.get() or setting(scheduler)[0] != "threads":
        return None
    from dask import threaded

    return {"scheduler": threaded.get, **({} if threads is None else {"num_workers": max(1, int(threads))})}


def compute_in_place(*datasets, threads: int | None = None, scheduler: str | None = None) -> tuple:
    """:func:`compute` of xarray ``datasets``. On the ``threads`` engine outside a session, each
    Dask variable is written into one NumPy array allocated up front, a chunk at a time as
    each chunk is computed, in the worker threads (``dask.array.store``), instead of its
    chunks being concatenated in one thread after the last one: the same numbers, without
    that serial copy at the end. On the other engines the results cross processes anyway:
    :func:`compute`.
    """
    own = _own_threads(threads, scheduler)
    if own is None:
        return compute(*datasets, threads=threads, scheduler=scheduler)
    import dask.array as da
    import numpy as np

    sources, targets, filled = [], [], []
    for ds in datasets:
        out = ds.copy()
        for var in out.variables.values():
            if isinstance(var.data, da.Array):
                sources.append(var.data)
                targets.append(np.empty(var.shape, var.dtype))
                var.data = targets[-1]
        filled.append(out)
    if sources:
        da.store(sources, targets, lock=False, **own)  # chunks write disjoint regions
    return tuple(filled)

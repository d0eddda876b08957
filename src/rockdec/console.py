"""What a run shows on the terminal: its messages (``logging``) and its progress bars.

Messages go through the ``rockdec`` logger (``logging.getLogger("rockdec")`` and its
children); :func:`configured` sends them to stderr at the level ``-q``/``-v`` choose. A
progress bar (:func:`progress`) is drawn only on a terminal: redirected to a file (a
Snakemake log, a batch job's output) it would be a stream of carriage-return frames, so
there the message the caller logs before the computation is all that is written.
"""

from __future__ import annotations

import contextlib
import logging
import sys

__all__ = ["about", "configured", "duration", "progress"]

#: The logger every module of the package writes its messages to (children: rockdec.<module>).
LOGGER = "rockdec"

#: Levels of ``-q`` (warnings only), the default (progress messages) and ``-v`` (details).
LEVELS = {-1: logging.WARNING, 0: logging.INFO, 1: logging.DEBUG}

#: A computation shorter than this many seconds draws no progress bar.
BAR_AFTER_S = 2.0


class _Handler(logging.Handler):
    """Writes each message to the ``sys.stderr`` of the moment (a test or a caller may have
    replaced it since the handler was made)."""

    def emit(self, record):
        try:
            sys.stderr.write(self.format(record) + "\n")
            sys.stderr.flush()
        except Exception:
            self.handleError(record)


@contextlib.contextmanager
def configured(verbosity: int = 0):
    """Inside the block, send the package's messages to stderr as ``rockdec: <message>``:
    ``verbosity`` -1 (``-q``: warnings and errors), 0 (progress messages) or 1 (``-v``:
    details). The logger is left as it was found afterwards."""
    log = logging.getLogger(LOGGER)
    before = log.level, log.propagate
    handler = _Handler()
    handler.setFormatter(logging.Formatter("rockdec: %(message)s"))
    log.addHandler(handler)
    log.setLevel(LEVELS[max(-1, min(1, verbosity))])
    log.propagate = False
    try:
        yield
    finally:
        log.removeHandler(handler)
        log.setLevel(before[0])
        log.propagate = before[1]


class _Labelled:
    """A stream that starts each frame of a Dask progress bar (``\\r[###  ] | ...``) with a label."""

    def __init__(self, stream, label: str):
        self.stream, self.label = stream, label

    def write(self, text: str) -> None:
        self.stream.write(text.replace("\r", f"\r{self.label} "))

    def flush(self) -> None:
        self.stream.flush()


def progress(label: str, stream=None):
    """A context in which Dask computations longer than :data:`BAR_AFTER_S` draw a progress
    bar, each frame starting with ``label``, on ``stream``: by default stderr, and only while
    the package's messages are shown (not under ``-q``).

    No bar when the stream is not a terminal (a log file never gets the bar's frames).
    """
    if stream is None:
        if not logging.getLogger(LOGGER).isEnabledFor(logging.INFO):
            return contextlib.nullcontext()
        stream = sys.stderr
    if stream is None or not stream.isatty():
        return contextlib.nullcontext()
    from dask.diagnostics import ProgressBar

    return ProgressBar(out=_Labelled(stream, label), minimum=BAR_AFTER_S)


def duration(seconds: float) -> str:
    """``seconds`` as a rounded duration: ``"40 s"``, ``"15 min"``, ``"3.2 h"``, ``"12 days"``."""
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 7200:
        return f"{seconds / 60:.0f} min"
    if seconds < 2 * 86400:
        return f"{seconds / 3600:.2g} h"
    return f"{seconds / 86400:.2g} days"


def about(seconds: float) -> str:
    """An estimated time in words: ``"under a second"``, else ``"about"`` and :func:`duration`."""
    return "under a second" if seconds < 0.5 else f"about {duration(seconds)}"

"""Stage 1 of the estimate: the records checked and analysed (their signatures and every
estimator's raw value, :func:`rockdec.rdd.measured.analyse`), or refused in one sentence.
"""

from __future__ import annotations

import logging
import math
from typing import NamedTuple

import numpy as np

from rockdec import console
from rockdec.calibrate import consistency
from rockdec.estimation.cost_model import stage_seconds
from rockdec.estimation.notes import Note
from rockdec.rdd import measured
from rockdec.record.records import Record, RecordError, distinct, held, same_step
from rockdec.record.sameness import same_data

__all__ = ["Analysed", "G_FACTOR", "SPIKE_SIGMAS", "analyse", "own_scales", "refuse_held", "transient_decline"]

log = logging.getLogger(__name__)

#: A given ``g`` off the records' own by more than this factor is refused before any
#: calibration (the calibrated 95 % spread of ``g`` is a few per cent).
G_FACTOR = 2.0

#: Peaks beyond this many ``sigma_Y`` are named as the cause when the analysis refuses the
#: records (a spike that inflates ``sigma_Y`` leaves too few triggers).
SPIKE_SIGMAS = 15.0


class Analysed(NamedTuple):
    """The records and their analysis (stage 1 of :func:`rockdec.estimation.estimate`).

    ``own``: the analysis with the records' own ``g`` (``None`` when it cannot be read and
    ``g`` is given); ``analysis``: the one the estimates come from (with the given ``g``,
    else ``own``); ``g``: as given (rad/s^2) or ``None``; ``notes``: :class:`~rockdec.estimation.notes.Note` s so far;
    ``scales_apart``: why records given together, their own ``g`` too far apart for one block,
    are declined (:func:`rockdec.calibrate.consistency.scales_apart`), else ``None``."""

    records: tuple
    dt: float
    samples: int
    settings: dict
    own: measured.Analysis | None
    analysis: measured.Analysis
    g: float | None
    notes: tuple
    scales_apart: str | None = None

    @property
    def own_points_per_cycle(self) -> float:
        """Samples per cycle the analysis reads with the records' own ``g`` (NaN when unread)."""
        return self.own.points_per_cycle if self.own is not None else math.nan


def analyse(records: list[Record], *, g: float | None = None, settings: dict | None = None, length_grid: bool = False) -> Analysed:
    """Stage 1 of :func:`rockdec.estimation.estimate`: check the records and analyse them (signatures, every
    estimator extrapolated to a zero window, :func:`rockdec.rdd.measured.analyse`), saying how
    long it and the calibration take (:func:`~rockdec.estimation.cost_model.stage_seconds`, ``length_grid`` as it takes it).

    Refuses (:class:`RecordError`) records given twice (also in disguise: an offset, a sign, a
    scale or an overlap, :func:`rockdec.record.sameness.same_data`), records at different steps, a
    record that holds each value for several samples (:func:`rockdec.record.records.held`), records
    given together in different units (their own ``g``, :func:`own_scales`, apart by
    :data:`rockdec.calibrate.consistency.UNITS_RATIO` or more), records
    the analysis cannot read, records that do not look like rocking
    (:func:`rockdec.rdd.measured.rocking_shape`; either refusal says so when a record's load is
    a transient, :func:`transient_decline`) and a given ``g`` off the records' own by
    more than :data:`G_FACTOR`.
    """
    settings = {**measured.DEFAULT_SETTINGS, **(settings or {})}
    records = distinct(records)
    dt = same_step(records)
    refuse_held(records)
    copied = same_data(records)
    if copied:
        raise RecordError(copied)
    apart = consistency.scales_apart([r.source for r in records], *own_scales(records, dt, settings)) if len(records) > 1 else None
    if apart is not None and apart.kind == "units":
        raise RecordError(f"{apart.message}.")
    names = ", ".join(r.source for r in records)
    samples = int(sum(r.theta.size for r in records))
    stages = stage_seconds(samples, False, g is not None, records=len(records), length_grid=length_grid)
    log.info(
        f"analysing {samples} samples: {console.about(stages['analysing'])} "
        f"({console.about(stages['analysing'] + stages['calibrating'])} in all when the calibration must be built)"
    )
    notes = []
    try:
        own = _analyse(records, dt, settings, None)
    except RecordError as exc:
        shaken = transient_decline(records, dt)
        if shaken:
            raise RecordError(f"{names} cannot be analysed ({str(exc).rstrip('.')}): {shaken}.") from exc
        if g is None:
            raise
        own = None
        notes.append(Note("g_unreadable", "g cannot be read off the records, so the given `g` could not be checked against them"))
    if g is not None:
        _check_given_g(g, own, names)
    analysis = _analyse(records, dt, settings, g) if g is not None else own
    shape = measured.rocking_shape(own if own is not None else analysis)
    if shape:
        shaken = transient_decline(records, dt)
        if shaken:
            raise RecordError(f"{names} does not look like a rocking record ({shape}): {shaken}.")
        raise RecordError(f"{names} does not look like a rocking record: {shape}; e is estimated only for rocking records.")
    return Analysed(tuple(records), dt, samples, settings, own, analysis, g, tuple(notes), None if apart is None else apart.message)


def refuse_held(records: list[Record]) -> None:
    """Refuse (:class:`RecordError`) the first record that holds each value for several samples
    (:func:`rockdec.record.records.held`): its signatures read the hold as rocking, and the
    repair's high-pass, which smooths the hold away, does not give back the samples the logger
    did not take."""
    for r in records:
        hold = held(r)
        if hold:
            raise RecordError(hold)


def own_scales(records: list[Record], dt: float, settings: dict) -> tuple[list[float], list[float]]:
    """Each record's ``sigma_Y`` and its own ``g``, read alone
    (:func:`rockdec.rdd.measured.analyse` without a given ``g``), for
    :func:`rockdec.calibrate.consistency.scales_apart`: NaN for a record whose analysis alone
    fails, has fewer than three triggers of a kind or does not look like rocking
    (:func:`rockdec.rdd.measured.rocking_shape`), whose ``g`` is then not its block's."""
    sigmas, gs = [], []
    for r in records:
        sigmas.append(float(np.nanstd(r.theta)))
        try:
            alone = measured.analyse([r.theta], dt, settings)
        except ValueError:
            gs.append(math.nan)
            continue
        readable = min(int(alone.count["a"][-1]), int(alone.count["v"][-1])) >= 3 and measured.rocking_shape(alone) is None
        gs.append(float(alone.raw[measured.G_NAME]) if readable else math.nan)
    return sigmas, gs


def _analyse(records: list[Record], dt: float, settings: dict, g: float | None) -> measured.Analysis:
    """:func:`rockdec.rdd.measured.analyse`, its refusals as :class:`RecordError` naming the
    records (a spike, when there is one, is named as the cause)."""
    names = ", ".join(r.source for r in records)
    try:
        analysis = measured.analyse([r.theta for r in records], dt, settings, g=g)
    except ValueError as exc:
        raise RecordError(f"{names}: {_spike(records) or exc}.") from None
    n_a, n_v = int(analysis.count["a"][-1]), int(analysis.count["v"][-1])
    if n_v < 3 or n_a < 3:
        spike = _spike(records)
        if spike:
            raise RecordError(f"{names}: only {n_a} extremum and {n_v} zero-crossing triggers: {spike}.")
        raise RecordError(
            f"{names}: only {n_a} extremum and {n_v} zero-crossing triggers, too few for the fits; give a longer record."
        )
    return analysis


def _check_given_g(g: float, own: measured.Analysis | None, names: str) -> None:
    """Refuse a given ``g`` off the records' own (read off their free response) by more
    than :data:`G_FACTOR`."""
    if own is None or not np.isfinite(own.raw[measured.G_NAME]):
        return
    ratio = g / own.raw[measured.G_NAME]
    if not 1.0 / G_FACTOR <= ratio <= G_FACTOR:
        raise RecordError(
            f"`g` {g:g} is {ratio:.3g} times the g the records show ({own.raw[measured.G_NAME]:.3g} rad/s^2, read off the "
            f"free response of {names}); give `g` = nu^2 theta_cr in rad/s^2 (theta_cr in rad, not degrees), or leave it out."
        )


def _spike(records: list[Record]) -> str | None:
    """A sentence on the largest spike of the records (beyond :data:`SPIKE_SIGMAS` times their
    rms), or ``None``."""
    y = np.concatenate([r.theta - np.nanmean(r.theta) for r in records])
    rms = float(np.sqrt(np.nanmean(y**2)))
    where = int(np.nanargmax(np.abs(y)))
    peak = float(np.abs(y[where])) / rms
    if not peak > SPIKE_SIGMAS:
        return None
    return (
        f"a spike of {peak:.0f} times the rms (sample {where}) inflates sigma_Y and with it the trigger levels; "
        "remove the spikes or mark them as gaps (NaN)"
    )


def transient_decline(records: list[Record], dt: float) -> str | None:
    """Why ``e`` is declined, before any calibration, for records whose load is a transient (an
    earthquake or a shake-table test: :attr:`rockdec.record.transient.Envelope.transient`), in one
    sentence naming the first such record, its strongest stretch's share of its energy and what
    to do instead; else ``None``."""
    from rockdec.record import transient

    for r in records:
        found = transient.envelope(r.theta, dt)
        if found is not None and found.transient:
            return (
                f"the record's amplitude builds up and dies away ({r.source}: its strongest {found.seconds:.3g} s hold "
                f"{100.0 * found.share:.0f} % of its energy, its strongest stretch more than {transient.DECADES:g} decades "
                "of variance above both its ends): the load is a transient, an earthquake or a shake-table test, not the "
                "stationary random load the random test assumes; estimate e with the shake-table test (`--test shake --base "
                "FILE`, rockdec.shake_table), which finds the free decay after the shaking from the base acceleration"
            )
    return None

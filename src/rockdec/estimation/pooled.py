"""Stage 6 of the estimate: whether records given together agree on one ``e``
(:func:`rockdec.calibrate.consistency.check`); ``e`` is declined when they do not.
"""

from __future__ import annotations

import logging
import math
from typing import NamedTuple

import numpy as np

from rockdec import console
from rockdec.calibrate import belt, consistency
from rockdec.estimation.analysed import Analysed
from rockdec.estimation.calibrated import Calibrated
from rockdec.estimation.cost_model import ANALYSIS_SECONDS
from rockdec.estimation.model_choice import ModelChoice
from rockdec.estimation.notes import Note
from rockdec.estimation.selected import Selection
from rockdec.rdd import measured
from rockdec.record import diagnostics

__all__ = ["Pooled", "check_pooled"]

log = logging.getLogger(__name__)


class Pooled(NamedTuple):
    """What :func:`check_pooled` (a stage of :func:`rockdec.estimation.estimate`) makes of records given
    together: the :class:`~rockdec.estimation.selected.Selection`, its estimator and reason replaced when
    the records disagree on one ``e``; its :class:`~rockdec.estimation.notes.Note` s; its check
    (``{"pooled_consistency": rockdec.record.diagnostics.Outcome}``, empty for a single
    record)."""

    selection: Selection
    notes: tuple
    checks: dict


def check_pooled(analysed: Analysed, choice: ModelChoice, calibrated: Calibrated, selection: Selection) -> Pooled:
    """The stage of :func:`rockdec.estimation.estimate` after :func:`rockdec.estimation.selected.select`: whether records given together
    agree on one ``e`` (:func:`rockdec.calibrate.consistency.check`: Cochran's ``Q`` of
    each record's own raw value of the reported estimator (:func:`_alone`) about their
    weighted mean, each with the spread of the calibration's belt scaled to its length). A
    single record passes unchanged. A record that cannot be analysed alone is left out of
    the test with a ``pooled_unchecked`` :class:`~rockdec.estimation.notes.Note`.

    Records that disagree decline ``e`` (``reason`` names what each reads alone) with a
    ``pooled_disagree`` :class:`~rockdec.estimation.notes.Note`, rather than print the pooled interval beside a
    warning. The pooled interval is a claim about one ``e`` that the test rejects: for
    records of ``e`` 0.80 and 0.90 it holds neither, and an interval beside a warning is
    still copied into a paper; a record-by-record estimate is always valid and costs a
    pool of one block little, which the test declines on few pools
    (:data:`rockdec.calibrate.consistency.LEVEL`; ``benchmarks/pooled_consistency.py``).
    """
    records = analysed.records
    chosen = selection.chosen
    if len(records) < 2:
        return Pooled(selection, (), {})
    if chosen is None:  # no e to check the records against
        return Pooled(selection, (), {"pooled_consistency": diagnostics.Outcome(math.nan, math.nan, False, "")})
    raws, unread = _alone(analysed, chosen)
    b = calibrated.simulated_belts[chosen]
    outcome = consistency.check(raws, [r.theta.size for r in records], b.e, b.mean, b.spread, sum(choice.cal_settings["lengths"]))
    checks = {"pooled_consistency": diagnostics.Outcome(float(outcome.statistic), float(outcome.threshold), bool(outcome.fired), "")}
    notes = []
    if unread:
        rest = "the other records were checked against each other" if outcome.dof >= 1 else "whether the records agree on one e was not checked"
        notes.append(Note("pooled_unchecked", f"{'; '.join(unread)} could not be analysed alone: {rest}"))
    if not outcome.fired:
        return Pooled(selection, tuple(notes), checks)
    alone = ", ".join(f"{r.source} {_reads(b, x)}" for r, x in zip(records, raws) if np.isfinite(x))
    test = (f"Cochran's Q of their {chosen} {outcome.statistic:.3g} is above {outcome.threshold:.3g}, the "
            f"{consistency.LEVEL * 100:g} % point of chi-square with {outcome.dof} degree{'s' if outcome.dof > 1 else ''} of freedom")
    notes.append(Note("pooled_disagree", f"the records given together disagree on one e ({test}): alone, {alone}; e is declined"))
    why = (f"the records given together disagree on one e (alone, {alone}; {test}), so no e holds for them all; "
           "estimate each record alone, or pool only records of one block")
    return Pooled(selection._replace(chosen=None, reason=why), tuple(notes), checks)


def _alone(analysed: Analysed, name: str) -> tuple[list[float], list[str]]:
    """Each record's raw value of estimator ``name`` analysed alone
    (:func:`rockdec.rdd.measured.analyse` with the ``g`` of the pooled analysis, so that every
    record is read with the lag range of the same block), NaN for a record that cannot be;
    and for those, the record and why."""
    g = analysed.g if analysed.g is not None else analysed.analysis.raw[measured.G_NAME]
    log.info(f"checking that the {len(analysed.records)} records agree on one e: each analysed alone, "
             f"{console.about(analysed.samples * ANALYSIS_SECONDS)}")
    raws, unread = [], []
    for r in analysed.records:
        try:
            raw = measured.analyse([r.theta], analysed.dt, analysed.settings, g=g if np.isfinite(g) else None).raw[name]
        except ValueError as exc:
            raw, why = math.nan, str(exc).rstrip(".")
        else:
            why = f"no value of {name}"
        raws.append(raw)
        if not np.isfinite(raw):
            unread.append(f"{r.source} ({why})")
    return raws, unread


def _reads(b: belt.Belt, raw: float) -> str:
    """Where a record's raw value alone places ``e`` on the belt ``b``'s mean curve
    (:func:`rockdec.calibrate.consistency.reads`), in words."""
    e = consistency.reads(b.e, b.mean, raw)
    if np.isfinite(e):
        return f"about {e:.3f}"
    return f"beyond the calibrated range {b.e[0]:.3f}-{b.e[-1]:.3f} (raw {raw:.3f})"

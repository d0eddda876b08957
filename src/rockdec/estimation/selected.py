"""Stage 5 of the estimate: the reported estimator, the trusted candidate whose belt is
narrowest at the candidates' common ``e``, and each candidate's row of the selection.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from rockdec.calibrate import belt
from rockdec.estimation.corrected import Reading
from rockdec.rdd import registry

__all__ = ["Candidate", "Selection", "coverage_floor", "declined_rows", "select"]


def coverage_floor(n_sets: int) -> float:
    """Lowest calibrated coverage (:func:`rockdec.calibrate.belt.calibration_coverage`) at which an
    interval is taken to hold 95 %: the lower end of the binomial band
    ``0.95 - 1.96 sqrt(0.95 x 0.05 / n)`` of ``n`` calibration sets (what a belt that covers
    exactly 95 % shows on its own sets 97.5 % of the time)."""
    return 0.95 - belt.Z95 * math.sqrt(0.95 * 0.05 / max(n_sets, 1))


class Candidate(NamedTuple):
    """One candidate's row of the selection (:func:`~rockdec.estimation.selected.select`): its 95 % ``width``, its width
    at the candidates' common ``e`` (NaN unless it holds), its calibrated ``coverage``
    (NaN when none), whether it ``holds`` and, when not, why (``why_not``)."""

    estimator: str
    width: float
    width_at_common_e: float
    coverage: float
    holds: bool
    why_not: str | None


class Selection(NamedTuple):
    """What :func:`~rockdec.estimation.selected.select` gives: the ``chosen`` estimator (``None`` when none can be
    trusted), each candidate's row (:class:`Candidate`) and, without one, the ``reason``
    (one sentence)."""

    chosen: str | None
    rows: tuple
    reason: str | None


def select(per: dict[str, Reading], n_sets: int, belts: dict[str, belt.Belt]) -> Selection:
    """The reported estimator among :data:`rockdec.rdd.registry.CANDIDATES`: of those with a
    value (``per``, :func:`rockdec.estimation.corrected.correct`), an interval narrower
    than the calibrated range, and a calibrated coverage that holds (:func:`coverage_floor`),
    the one whose belt gives the narrowest 95 % interval at a common ``e``, the median of
    the candidates' corrected values (:func:`rockdec.calibrate.belt.width_at`). Each
    record's own intervals are not compared: an estimator whose scatter put its interval
    against an end of the calibrated range, where the interval is cut short, would be picked
    for that scatter, and the picked interval would then miss more often than each
    candidate's own (``benchmarks/selection_rule.py``)."""
    floor = coverage_floor(n_sets)
    values = [per[name].e for name in registry.CANDIDATES if per[name].has_value]
    common = float(np.median(values)) if values else math.nan
    rows = []
    for name in registry.CANDIDATES:
        est = per[name]
        width = est.high - est.low if est.has_value and math.isfinite(est.low) else math.nan
        if est.beyond is not None:
            why = f"its raw value lies beyond what any calibrated e gives ({est.beyond})"
        elif not math.isfinite(width):
            why = "; ".join(est.notes) or "it gave no value on these records"
        elif est.calibrated_range and est.low <= est.calibrated_range[0] and est.high >= est.calibrated_range[1]:
            why = "its 95 % interval spans the whole calibrated range: the record does not tell e"
        elif not est.coverage >= floor:
            why = f"its calibrated coverage {'-' if math.isnan(est.coverage) else f'{est.coverage:.1%}'} is below {floor:.1%}"
        else:
            why = None
        rows.append(Candidate(name, width, float(belt.width_at(belts[name], common)) if why is None else math.nan,
                              est.coverage, why is None, why))
    trusted = [row for row in rows if row.holds]
    if trusted:
        return Selection(min(trusted, key=lambda row: row.width_at_common_e).estimator, tuple(rows), None)
    reason = "no estimator can be trusted on these records: " + "; ".join(f"{row.estimator}: {row.why_not}" for row in rows)
    return Selection(None, tuple(rows), reason)


def declined_rows(why: str) -> tuple:
    """The selection's rows of records declined before any calibration: no candidate holds, for ``why``."""
    return tuple(Candidate(name, math.nan, math.nan, math.nan, False, why) for name in registry.CANDIDATES)

"""Stage 8 of the estimate: the checks of :mod:`rockdec.record.diagnostics` on the records,
their thresholds read off the calibration's own simulated records near the estimate.
"""

from __future__ import annotations

import numpy as np

from rockdec.estimation.corrected import Reading
from rockdec.estimation.notes import Note
from rockdec.rdd import measured, registry
from rockdec.record import diagnostics
from rockdec.record.records import Record

__all__ = ["checks_place", "diagnose", "unresolved_impacts"]


def checks_place(per: dict[str, Reading], shown: Reading | None) -> tuple[float | None, list | None]:
    """Where the checks read their null (:func:`rockdec.record.diagnostics.thresholds`): the
    reported corrected ``e`` and its interval (``shown``, the reported estimator's
    :class:`~rockdec.estimation.corrected.Reading`; ``None`` or without a value when none is
    reported); else the median of the candidates' corrected values (``per``), a raw value
    beyond what any calibrated ``e`` gives taken at the end of the calibrated range it lies
    beyond (the record's ``e`` lies there, as at high ``e`` under sensor noise), without an
    interval; ``(None, None)`` when no candidate gives one."""
    if shown is not None and shown.has_value:
        return shown.e, [shown.low, shown.high]
    values = []
    for name in registry.CANDIDATES:
        est = per[name]
        if est.has_value:
            values.append(est.e)
        elif est.beyond in ("below", "above") and est.calibrated_range:
            values.append(est.calibrated_range[1 if est.beyond == "above" else 0])
    return (float(np.median(values)), None) if values else (None, None)


def diagnose(
    records: list[Record], analysis: measured.Analysis, settings: dict, cal, e: float | None, interval, length_ratio: float = 1.0,
    replaced=None,
) -> tuple[list, dict]:
    """The checks of :mod:`rockdec.record.diagnostics` on the records, against thresholds from the
    calibration ``cal`` near ``e`` and its 95 % ``interval`` (:func:`checks_place`;
    ``length_ratio``: the records' length over the calibration's records'; ``replaced``: the
    samples the repair replaced, per record, which the spikes statistic leaves out): a :class:`~rockdec.estimation.notes.Note`
    (its code the check's name) for each check that fired and the ``filtered_unchecked`` ones of
    :func:`unresolved_impacts`, and per check its :class:`rockdec.record.diagnostics.Outcome`."""
    level = settings.get("level", measured.DEFAULT_SETTINGS["level"])
    outcomes = diagnostics.evaluate([r.theta for r in records], analysis, cal, e, interval, level, length_ratio, replaced)
    notes = [Note(name, o.message) for name, o in outcomes.items() if o.fired]
    notes.extend(unresolved_impacts(records))
    return notes, outcomes


def unresolved_impacts(records: list[Record]) -> list:
    """A ``filtered_unchecked`` :class:`~rockdec.estimation.notes.Note` for each record quantised so coarsely that the
    check ``filtered`` cannot read its impacts (its one-sample velocities at the fast zero
    crossings fewer than :data:`rockdec.record.diagnostics.IMPACT_MIN_STEPS` steps of its
    resolution, :func:`rockdec.record.diagnostics.impact_steps`), which the check leaves out."""
    notes = []
    for r in records:
        steps = diagnostics.impact_steps(r.theta)
        if steps < diagnostics.IMPACT_MIN_STEPS:
            notes.append(Note("filtered_unchecked", (
                f"{r.source} is quantised to steps of {diagnostics.resolution(r.theta):.4g}, and its impacts' one-sample velocities "
                f"span {steps:.0f} of them, fewer than the {diagnostics.IMPACT_MIN_STEPS} the check `filtered` needs to read an "
                "impact's cut of the velocity (a ratio of a few counts): it was not checked for a low-pass filter after the block; "
                "declare the logger's filter if it has one (`sensor_filter`), or record at a finer resolution"
            )))
    return notes

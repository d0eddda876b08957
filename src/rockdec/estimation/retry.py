"""The estimate of ``e`` from measured records (:func:`estimate`): the records' repair
(spikes replaced, drift high-passed) and the retry it decides, around :func:`rockdec.estimation.stages.estimate_once`.
"""

from __future__ import annotations

import logging
import math

from rockdec.estimation.analysed import refuse_held
from rockdec.estimation.stages import Outcome, Repaired, Verdict, estimate_once
from rockdec.physics.record_model import Load, RecordModel, SensorFilter, SensorNoise
from rockdec.rdd import measured
from rockdec.record import repair
from rockdec.record.records import Record, RecordError, same_step

__all__ = ["DECLINING_CHECKS", "REPAIRING_CHECKS", "blunted_cause", "decline_unrepaired", "declining_fired", "estimate"]

log = logging.getLogger(__name__)

#: Checks whose defect moves ``e`` by more than half its interval and which the repair
#: (:mod:`rockdec.record.repair`) did not remove when they still fire after it: a load whose
#: strength changes, a block that leans, drift or spikes the repair left, a filter after the
#: block that was not declared or a soft contact (``filtered``). Any of them fired declines ``e`` (:func:`decline_unrepaired`),
#: rather than print an interval beside a warning that the record is broken (evidence:
#: ``benchmarks/repair_study.py``, ``benchmarks/filter_study.py``, docs/explanation/constants.md).
DECLINING_CHECKS = ("filtered", "nonstationary", "drift", "spikes", "asymmetry")

#: Checks that start the high-pass (:mod:`rockdec.record.repair`) when they fire on the
#: records as given: a drifting zero moves the block means (``drift``), the level the sides
#: are read about (``asymmetry``: a drift of a few ``sigma_Y`` fires it on a symmetric block)
#: and the largest distances off the neighbours' line (``spikes``). Spikes are replaced
#: before any analysis (:func:`rockdec.record.repair.find_spikes`), since spikes of tens of
#: ``sigma_Y`` leave the analysis too few triggers.
REPAIRING_CHECKS = ("drift", "asymmetry", "spikes")


def declining_fired(verdict: Verdict, unfiltered: bool = False) -> list[str]:
    """The checks of :data:`DECLINING_CHECKS` that fired (``verdict``, :class:`Verdict`) and
    decline ``e``: all but a ``filtered`` whose records' filter (or its absence, in a record
    model declared whole) was declared, which only warns. ``unfiltered``: the records were
    declared unfiltered (``sensor_filter`` none), where ``filtered`` declines too: a soft
    contact blunts the impacts as a filter does and no declaration models it
    (:data:`rockdec.record.diagnostics.BLUNTED_HELP`)."""
    declared = verdict.filter_declared and not unfiltered
    return [name for name in DECLINING_CHECKS if name in verdict.fired and not (name == "filtered" and declared)]


def blunted_cause(verdict: Verdict, unfiltered: bool = False) -> str:
    """What the reason says first when ``filtered`` declines ``e`` (else ``""``): on records
    declared unfiltered (``unfiltered``), that none does not model a soft contact; and when
    the record model measured the load white (no colour detected), that the blunting points
    to a soft contact: a first-order filter after the block, gentle enough to pass the
    roll-off check, makes a white load read low-pass, while a soft contact leaves the load as
    it is (tests/calibrate/test_soft_contact.py)."""
    if "filtered" not in declining_fired(verdict, unfiltered):
        return ""
    return (("`sensor_filter` none was declared, but the impacts are blunted and none does not model a soft contact, which "
             "rockdec cannot calibrate; " if unfiltered else "")
            + ("the load measures white, which a low-pass filter after the block would make read low-pass, so the blunted "
               "impacts point to a soft contact; " if verdict.white else ""))


def decline_unrepaired(outcome: Outcome, unfiltered: bool = False) -> Outcome:
    """``outcome`` with ``e`` declined (its ``declined`` set) when a check of
    :data:`DECLINING_CHECKS` fired on the records as estimated (after any repair): the reason
    names the check and its message, after what :func:`blunted_cause` says of a fired
    ``filtered``. A ``filtered`` that fired warns only when the records' filter (or its
    absence, in a record model declared whole) was declared; ``unfiltered``:
    :func:`declining_fired`."""
    verdict = outcome.verdict
    fired = declining_fired(verdict, unfiltered)
    if outcome.shown is None or not fired:
        return outcome
    defects = "; ".join(f"{name}: {verdict.fired[name]}" for name in fired)
    repaired = " after the repair" if verdict.repaired else ""
    reason = (f"{blunted_cause(verdict, unfiltered)}the records show a defect that moves e by more than its interval and that{repaired} "
              f"is still there ({defects}); e is declined rather than given with an interval that does not hold")
    return outcome._replace(declined=reason)


def estimate(
    records: list[Record], *, cache_dir, g: float | None = None, settings: dict | None = None, model: RecordModel | None = None,
    load: Load | str | None = None, sensor: SensorNoise | None = None, rocking: str | None = None, theta_cr: float | None = None,
    sensor_filter: SensorFilter | str | None = "auto",
    repair_records: bool = True, available=None, length_grid: bool = False,
) -> Outcome:
    """Calibrated estimates of ``e`` from ``records`` of one block (pooled), in named stages,
    after the records' repair.

    A record that holds each value for several samples is refused first
    (:func:`~rockdec.estimation.analysed.refuse_held`). Repair (``repair_records``, :mod:`rockdec.record.repair`): spikes are replaced before
    anything else (:func:`rockdec.record.repair.find_spikes`); when a check of :data:`REPAIRING_CHECKS` fires (or the
    record model measures drift) the records are high-passed and estimated again. Each
    repaired estimate has a calibration whose simulated sets were repaired alike. Records
    the analysis refuses, or declines before any calibration while their record model
    measures drift, are high-passed and tried again too (a drift of a few ``sigma_Y`` can
    hide the rocking); when that does not help, the first refusal or decline stands. A check of
    :data:`DECLINING_CHECKS` that fires on the records as estimated declines ``e``
    (:func:`decline_unrepaired`); ``filtered`` (a filter after the block or a soft contact; with ``sensor_filter`` none too) fired on
    the records as given declines ``e`` without the high-pass, which cannot remove a filter
    and moves the zero crossings off the impacts that the check reads, unless the records
    drift (the ``drift`` check fired, or the record model measures drift): a drifting zero
    moves the crossings off the impacts too and fires ``filtered`` on unfiltered records, so
    those are high-passed and the check is read again on the repaired records.

    Each estimate runs the stages of :func:`rockdec.estimation.stages.estimate_once`.
    ``model`` declares the whole record model (:mod:`rockdec.physics.record_model`); else
    ``load``, ``sensor``, ``rocking`` and ``sensor_filter`` (``"auto"``: checked for, none
    simulated; ``None``: none) declare their parts and the rest is measured. Housner's
    model (eq. 2) needs the block's ``theta_cr`` (rad). Returns the typed
    :class:`~rockdec.estimation.stages.Outcome`, whose report (the JSON document, with the
    keys the schema ``estimate.schema.json`` lists) is
    :func:`rockdec.report.estimate_report.document`.

    ``available``: the settings hashes of the calibrations the estimate may read (``None``:
    any, built when absent); the first it asks for outside them raises
    :class:`~rockdec.estimation.calibrated.CalibrationNeeded`. The estimate reads at most two: that of the records as given
    (spikes replaced) and, when the repair decides on the high-pass, that of the high-passed
    records.

    ``length_grid``: calibrations shared by records of nearby lengths (:func:`~rockdec.estimation.model_choice.choose_model`),
    their spread scaled to the records' length; a campaign of many lengths builds few.
    """
    options = dict(cache_dir=cache_dir, g=g, settings=settings, model=model, load=load, sensor=sensor, rocking=rocking, theta_cr=theta_cr,
                   sensor_filter=sensor_filter, available=available, length_grid=length_grid)
    records = list(records)
    refuse_held(records)  # before the repair, whose high-pass would hide the hold
    if not repair_records:
        return estimate_once(records, Repaired(None, False), **options)
    thetas = [r.theta for r in records]
    cleaned, done = repair.apply(thetas, repair.settings(True, False), math.nan)  # no high-pass: no rocking frequency needed
    found = done.removed
    despiked = [r._replace(theta=y) for r, y in zip(records, cleaned)] if found else records
    repaired = repair.settings(True, False) if found else None
    why = f"{found} isolated sample{'s' if found > 1 else ''} off {repair.SPIKE_Z:g} robust scales of the second differences" if found else None
    try:
        first, refusal = estimate_once(despiked, Repaired(done if found else None, True, why), repaired, **options), None
    except RecordError as exc:  # drift can leave a record the analysis refuses until it is filtered
        first, refusal = None, exc
    verdict = first.verdict if first is not None else None
    failed = verdict is None or not verdict.calibrated  # refused, or declined before any calibration
    drifting = verdict is not None and verdict.drift
    fired = [] if failed else [name for name in REPAIRING_CHECKS if name in verdict.fired]
    # a filter after the block is not what a high-pass mends, and the high-pass moves the zero crossings off the impacts
    # that the check reads: the records as given decide it (its ringing can fire spikes too); but a drifting zero moves
    # the crossings off the impacts as well and fires it on unfiltered records, so drift is high-passed first
    unfiltered = model is None and sensor_filter is None  # declared none: filtered declines (a soft contact)
    filter_shown = not failed and "filtered" in declining_fired(verdict, unfiltered) and not (drifting or "drift" in fired)
    if filter_shown or not (fired or drifting or verdict is None):  # a decline for the load or the instrument is not retried unless drift is measured
        return decline_unrepaired(first, unfiltered)
    log.info("estimating again after a high-pass well below the rocking frequency (drift)")
    hp = repair.settings(bool(found), True)
    ppc = float(first.analysis.points_per_cycle) if first is not None else math.nan
    if not (math.isfinite(ppc) and ppc):
        ppc = repair.cycle_samples([r.theta for r in despiked])
    filtered, done = repair.apply(thetas, hp, ppc)
    try:  # the rocking frequency read off the filtered records places the corner
        ppc = measured.analyse(filtered, same_step(records), {**measured.DEFAULT_SETTINGS, **(settings or {})}, g=g).points_per_cycle
        filtered, done = repair.apply(thetas, hp, ppc)
    except ValueError:
        pass
    why = f"the check{'s' if len(fired) > 1 else ''} {', '.join(fired)} fired" if fired else ("the record model measured drift" if drifting else "the records as given could not be estimated")
    if found:
        why = f"{why}; {found} isolated samples off {repair.SPIKE_Z:g} robust scales of the second differences"
    try:
        second = estimate_once([r._replace(theta=y) for r, y in zip(records, filtered)], Repaired(done, True, why), hp, **options)
    except RecordError:
        second = None
    if failed and (second is None or not second.verdict.calibrated):  # the high-pass did not help: as given
        if first is None:
            raise refusal
        return decline_unrepaired(first, unfiltered)
    if second is None:
        return decline_unrepaired(first, unfiltered)
    return decline_unrepaired(second, unfiltered)

"""One estimate of ``e`` from records as they are, in its stages (:func:`estimate_once`),
and what it gives (:class:`Outcome`), read by the repair-and-retry and by the report.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from rockdec.estimation import corrected, selected
from rockdec.estimation.analysed import Analysed, analyse
from rockdec.estimation.calibrated import Calibrated, get_calibration
from rockdec.estimation.diagnosed import checks_place, diagnose
from rockdec.estimation.g_read import GReading, long_record_note, read_g, uncalibrated_g
from rockdec.estimation.model_choice import ModelChoice, choose_model
from rockdec.estimation.pooled import check_pooled
from rockdec.physics.record_model import Load, RecordModel, SensorFilter, SensorNoise
from rockdec.rdd import measured
from rockdec.record import repair
from rockdec.record.records import Record

__all__ = ["Outcome", "Repaired", "Verdict", "estimate_once"]


class Verdict(NamedTuple):
    """What the repair-and-retry of :func:`rockdec.estimation.estimate` decides on, read off one estimate's
    stages (never off its report): whether a calibration was read (``calibrated``; ``False``:
    declined before one), whether the record model measured ``drift`` and a ``white`` load,
    whether the sensor filter (or its absence) was declared (``filter_declared``), the checks
    that ``fired`` with their messages, and whether the records were ``repaired``."""

    calibrated: bool
    drift: bool
    white: bool
    filter_declared: bool
    fired: dict
    repaired: bool

    @classmethod
    def of(cls, choice: ModelChoice, calibrated: bool, fired: dict, done: repair.Repair | None) -> Verdict:
        """The verdict of an estimate whose model is ``choice``, with the message of each
        check that ``fired`` (``{name: message}``) and its repair ``done``."""
        m = choice.measurement
        return cls(calibrated, bool(m is not None and m.drifting), bool(m is not None and not m.coloured),
                   choice.sources.get("sensor_filter") == "declared", fired,
                   done is not None and done.repaired)


class Repaired(NamedTuple):
    """What the repair (:mod:`rockdec.record.repair`) did to the records before an estimate:
    ``done`` (its :class:`rockdec.record.repair.Repair`, ``None`` when nothing was done),
    whether the repair was ``enabled``, and ``why`` it was done, in words."""

    done: repair.Repair | None
    enabled: bool
    why: str | None = None


class Outcome(NamedTuple):
    """One estimate, stage by stage (:func:`estimate_once`): the ``analysed`` records, the
    ``choice`` of record model, the ``calibrated`` belts (``None``: declined before any
    calibration), every estimator's :class:`~rockdec.estimation.corrected.Reading`, the
    :class:`~rockdec.estimation.selected.Selection` (after the pooled check), the
    :class:`~rockdec.estimation.g_read.GReading`, the
    ``notes`` (:class:`~rockdec.estimation.notes.Note`), every check's
    :class:`rockdec.record.diagnostics.Outcome`, what the repair did (:class:`Repaired`),
    the :class:`Verdict` the repair-and-retry reads, and ``declined``: why ``e`` is declined
    after all (:func:`rockdec.estimation.retry.decline_unrepaired`), else ``None``. Its
    report is :func:`rockdec.report.estimate_report.document`."""

    analysed: Analysed
    choice: ModelChoice
    calibrated: Calibrated | None
    readings: dict
    selection: selected.Selection
    g_reading: GReading
    notes: tuple
    checks: dict
    repaired: Repaired
    verdict: Verdict
    declined: str | None = None

    @property
    def analysis(self) -> measured.Analysis:
        """The records' analysis (:class:`rockdec.rdd.measured.Analysis`), for plots."""
        return self.analysed.analysis

    @property
    def belts(self) -> dict:
        """Every estimator's belt at the records' length (empty when declined before any calibration)."""
        return {} if self.calibrated is None else self.calibrated.belts

    @property
    def shown(self) -> corrected.Reading | None:
        """The reported estimator's :class:`~rockdec.estimation.corrected.Reading`, ``None`` when none is reported."""
        chosen = self.selection.chosen
        return None if chosen is None or self.declined else self.readings[chosen]


def estimate_once(
    records: list[Record], repaired: Repaired, simulated_repair: dict | None = None, *, cache_dir, g: float | None = None,
    settings: dict | None = None, model: RecordModel | None = None, load: Load | str | None = None, sensor: SensorNoise | None = None,
    rocking: str | None = None, theta_cr: float | None = None, sensor_filter: SensorFilter | str | None = "auto", available=None,
    length_grid: bool = False,
) -> Outcome:
    """One estimate of ``e`` on ``records`` as they are (``repaired``: what the repair did to
    them), in its stages: :func:`~rockdec.estimation.analysed.analyse` →
    :func:`~rockdec.estimation.model_choice.choose_model` (declined when no calibration
    fits) → :func:`~rockdec.estimation.calibrated.get_calibration` (its sets repaired as
    ``simulated_repair`` says, :func:`rockdec.record.repair.settings`; ``available``: the
    calibrations it may read) → :func:`~rockdec.estimation.corrected.correct` →
    :func:`~rockdec.estimation.selected.select` (none when the impacts gain speed) →
    :func:`~rockdec.estimation.pooled.check_pooled` →
    :func:`~rockdec.estimation.g_read.read_g` →
    :func:`~rockdec.estimation.diagnosed.diagnose`. ``length_grid``: calibrations shared by
    records of nearby lengths (:func:`~rockdec.estimation.model_choice.choose_model`)."""
    analysed = analyse(records, g=g, settings=settings, length_grid=length_grid)
    choice = choose_model(analysed, model=model, load=load, sensor=sensor, rocking=rocking, theta_cr=theta_cr, sensor_filter=sensor_filter,
                          repaired=simulated_repair, length_grid=length_grid)
    if choice.declined:
        rows = selected.declined_rows("not calibrated: the records are declined (see the reason)")
        return Outcome(analysed, choice, None, corrected.uncalibrated(analysed), selected.Selection(None, rows, choice.declined),
                       uncalibrated_g(analysed.g), (*analysed.notes, *choice.notes), {}, repaired, Verdict.of(choice, False, {}, repaired.done))
    calibrated = get_calibration(analysed, choice, cache_dir, available)
    per = corrected.correct(analysed, calibrated)
    selection = selected.select(per, calibrated.n_sets, calibrated.belts)
    impossible = corrected.gains_speed(analysed, calibrated)
    if impossible:
        selection = selection._replace(chosen=None, reason=impossible)
    pooled = check_pooled(analysed, choice, calibrated, selection)
    shown = per[pooled.selection.chosen] if pooled.selection.chosen else None
    g_reading = read_g(analysed, choice, calibrated, pooled.selection.chosen, math.nan if shown is None else shown.e)
    fired, checks = diagnose(list(analysed.records), analysed.analysis, analysed.settings, calibrated.cal, *checks_place(per, shown),
                             1.0 / calibrated.scale**2, None if repaired.done is None else repaired.done.spikes)
    checks = {**checks, **pooled.checks}
    notes = (*analysed.notes, *choice.notes, *calibrated.notes, *g_reading.notes, *long_record_note(analysed, choice), *pooled.notes, *fired)
    verdict = Verdict.of(choice, True, {name: o.message for name, o in checks.items() if o.fired}, repaired.done)
    return Outcome(analysed, choice, calibrated, per, pooled.selection, g_reading, notes, checks, repaired, verdict)

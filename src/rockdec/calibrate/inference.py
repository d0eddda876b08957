"""From measured records to a calibrated ``e``: what ``rockdec estimate`` computes.

:func:`estimate` analyses the records (:func:`rockdec.rdd.measured.analyse`), checks that they
look like rocking (:func:`rockdec.rdd.measured.rocking_shape`) and that a given ``g`` agrees
with the records' own, measures the records' own model (sensor noise, load colour,
drift: :func:`rockdec.record.record_measure.measure`) unless it is declared, fetches or builds
the calibration for their lengths, sampling and model (:func:`record_model`,
:mod:`rockdec.calibrate.calibration`), corrects every estimator and gives its 95 % interval,
reports the trusted candidate whose belt is narrowest at their common ``e`` (:func:`select`),
declines it when records given together disagree on one ``e`` (:func:`check_pooled`,
:mod:`rockdec.calibrate.consistency`), corrects ``g`` the same way,
and lists what looks wrong with the records (:func:`diagnose`: the checks of
:mod:`rockdec.record.diagnostics`, their thresholds from the calibration's own simulated
records). When no ``e`` can be given, ``reason`` says why.

The calibration simulates records as long as the measured ones up to
:data:`rockdec.calibrate.calibration.LENGTH_CAP` samples; longer records get the belt of
that length on a denser grid of ``e``, its spread scaled by the square root of the length
ratio (:func:`rockdec.calibrate.calibration.spread_scale`), so the cost of a calibration
stops growing with the records' length (:func:`cost`, :func:`stage_seconds`); the command
line refuses, before reading the records, a run the machine cannot finish soon. Each
stage logs what it does and the time it is estimated to take.
"""

from __future__ import annotations

import logging
import math
import time
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from rockdec import console
from rockdec._version import __version__
from rockdec.calibrate import belt, calibration, consistency
from rockdec.record import diagnostics, repair
from rockdec.rdd import measured, registry
from rockdec.physics.record_model import NO_NOISE, WHITE, Load, RecordModel, SensorFilter, SensorNoise, check_filter_declared_with_model, parse_load
from rockdec.record.records import Record, RecordError, distinct, held, same_step
from rockdec.record.sameness import same_data
from rockdec.validate import InputError, json_number

from rockdec.rdd.registry import DEFAULT_ESTIMATOR

if TYPE_CHECKING:
    from rockdec.record import record_measure

__all__ = [
    "ANALYSIS_SECONDS", "Analysed", "CALIBRATION_SECONDS", "COLOUR_CORNER_FLOOR", "COLOUR_CORNER_Z",
    "CalibrationNeeded", "LONG_RATIO", "NOTE_CODES", "NO_NOISE", "Outcome", "PAIR_SECONDS",
    "RECORD_SECONDS", "SIDE_G_SHARE", "analyse", "beyond", "calibration_sets", "check_pooled",
    "checks_place", "choose_model", "colour_decline", "cost", "coverage_floor", "declared_contradictions", "diagnostics_report",
    "decline_unrepaired", "diagnose", "estimate", "filter_decline", "measure_model", "own_scales",
    "Verdict", "record_model", "select", "stage_seconds", "transient_decline", "unresolved_impacts",
]

log = logging.getLogger(__name__)

#: Records more than this many times as long as the calibration's simulated records are warned
#: that their interval's coverage was not measured at their length (evidence:
#: docs/explanation/constants.md, from ``benchmarks/long_coverage.py``).
LONG_RATIO = 20.0

#: A given ``g`` off the records' own by more than this factor is refused before any
#: calibration (the calibrated 95 % spread of ``g`` is a few per cent).
G_FACTOR = 2.0

#: Peaks beyond this many ``sigma_Y`` are named as the cause when the analysis refuses the
#: records (a spike that inflates ``sigma_Y`` leaves too few triggers).
SPIKE_SIGMAS = 15.0

#: A load measured as low-pass with its corner below this many rocking frequencies
#: ``1/T(sigma_Y)`` (eq. 5) at the samples per cycle the analysis reads is declined before
#: any calibration (:func:`colour_decline`): below it records read at one sampling are no
#: longer alike. Evidence: docs/explanation/constants.md (``benchmarks/colour_calibration.py``,
#: ``benchmarks/corner_floor_cells.py``, the coverage study).
COLOUR_CORNER_FLOOR = 2.0

#: A measured corner counts as above :data:`COLOUR_CORNER_FLOOR` only when it lies this many
#: standard errors above it (evidence: docs/explanation/constants.md, the coverage study).
COLOUR_CORNER_Z = 2.0

#: A measured load is declined when ``g`` read off the record's side means is less than this
#: share of the ``g`` its signature reads
#: (:meth:`~rockdec.record.record_measure.MeasuredModel.side_g_share`): the block's side then
#: follows the load, which the fitted pole does not describe (evidence:
#: docs/explanation/constants.md, the coverage study's coloured cells).
SIDE_G_SHARE = 0.7

#: A declared part of the record model (``sensor_noise``, ``load``) is said to be contradicted
#: by the records' own measurement when the two differ by more than ``DECLARED_Z`` of the
#: measurement's standard errors and by more than the factor ``DECLARED_FACTOR`` (sensor noise,
#: or the load's corner); a noise difference below
#: :data:`rockdec.record.record_measure.NOISE_FLOOR` never is (:func:`declared_contradictions`).
#: Evidence: the false alarms on right declarations, ``benchmarks/filter_study.py``.
DECLARED_Z, DECLARED_FACTOR = 4.0, 2.0

#: Cost model of :func:`cost`: seconds per sample to read a CSV and to do all but the
#: calibration, seconds per simulated and analysed calibration sample on one core, and
#: bytes held per sample while reading and analysing (measured by
#: ``benchmarks/long_record.py``; docs/explanation/constants.md).
CSV_SECONDS, ANALYSIS_SECONDS, CALIBRATION_SECONDS, BYTES_PER_SAMPLE = 5e-7, 1.0e-6, 1.3e-7, 160.0

#: Seconds each record of a pooled set adds besides its samples, on one core (its own pass
#: of signatures and checks in every simulated set of the calibration), and each pair of
#: records the check for copies in disguise compares (:mod:`rockdec.record.sameness`):
#: measured by ``benchmarks/pooled_cost.py`` (many short records against one long record
#: of as many samples, in one run).
RECORD_SECONDS, PAIR_SECONDS = 4e-4, 7e-5


def stage_seconds(samples: int, csv: bool, g_given: bool, cores: int = 2, records: int = 1,
                  length_grid: bool = False) -> dict[str, float]:
    """Seconds each stage of :func:`estimate` takes on ``records`` records of ``samples`` in all:
    ``reading`` (a CSV), ``analysing`` (twice with a given ``g``) and ``calibrating``
    (building the calibration: :func:`calibration_sets` records, of the records' length up to
    :data:`rockdec.calibrate.calibration.LENGTH_CAP` in all, or of the length grid's length
    with ``length_grid``, :func:`rockdec.calibrate.calibration.simulated_lengths`, and beyond
    the cap the step search's pilot sets of that length), from :data:`CSV_SECONDS` and the other constants of the
    model; each record beyond the first adds :data:`RECORD_SECONDS` in every simulated set
    and each pair of records :data:`PAIR_SECONDS`; several records are analysed twice more,
    each alone (:func:`own_scales`, :func:`check_pooled`)."""
    simulated = sum(calibration.simulated_lengths([samples], length_grid))
    sets = calibration_sets(samples)
    return {
        "reading": samples * CSV_SECONDS * csv,
        "analysing": samples * ANALYSIS_SECONDS * (1 + g_given + 2 * (records > 1)) + records * (records - 1) / 2 * PAIR_SECONDS,
        "calibrating": simulated * sets * CALIBRATION_SECONDS / cores + (records - 1) * sets * RECORD_SECONDS,
    }


def calibration_sets(samples: int) -> int:
    """How many records a calibration for records of ``samples`` in all simulates:
    :data:`rockdec.calibrate.calibration.SETS_PER_E` at each ``e`` of its grid, and beyond
    :data:`rockdec.calibrate.calibration.LENGTH_CAP`
    :data:`rockdec.calibrate.calibration.SETS_PER_E_CAPPED` and the step search's pilot sets
    (as long as the sets, :func:`rockdec.calibrate.calibration.step_for`) on the longer grid
    (:func:`rockdec.calibrate.calibration.sets_per_e`)."""
    if sum(calibration.simulated_lengths([samples])) == samples:
        return len(calibration.E_GRID) * calibration.SETS_PER_E
    from rockdec.physics.simulate import STEP_ITERATIONS

    sets = calibration.SETS_PER_E_CAPPED + calibration.PILOT_SETS * STEP_ITERATIONS["white"]
    return len(calibration.E_GRID_LONG) * sets


def cost(samples: int, csv: bool, g_given: bool, cores: int = 2, records: int = 1, length_grid: bool = False) -> tuple[float, float]:
    """``(seconds, bytes)`` that :func:`estimate` needs for ``records`` records of ``samples``
    in all, calibration included (:func:`stage_seconds`)."""
    return sum(stage_seconds(samples, csv, g_given, cores, records, length_grid).values()), samples * BYTES_PER_SAMPLE


def checks_place(per: dict, shown: dict) -> tuple[float | None, list | None]:
    """Where the checks read their null (:func:`rockdec.record.diagnostics.thresholds`): the
    reported corrected ``e`` and its interval (``shown``); when none is reported, the median
    of the candidates' corrected values (``per``, :func:`estimate`), a raw value beyond what
    any calibrated ``e`` gives taken at the end of the calibrated range it lies beyond (the
    record's ``e`` lies there, as at high ``e`` under sensor noise), without an interval; ``(None, None)`` when no candidate gives one."""
    if shown["e"] is not None:
        return shown["e"], shown["interval"]
    values = []
    for name in registry.CANDIDATES:
        est = per[name]
        if est["e"] is not None:
            values.append(est["e"])
        elif est["beyond"] in ("below", "above") and est["calibrated_range"]:
            values.append(est["calibrated_range"][1 if est["beyond"] == "above" else 0])
    return (float(np.median(values)), None) if values else (None, None)


def diagnose(
    records: list[Record], analysis: measured.Analysis, settings: dict, cal, e: float | None, interval, length_ratio: float = 1.0,
    replaced=None,
) -> tuple[list, dict]:
    """The checks of :mod:`rockdec.record.diagnostics` on the records, against thresholds from the
    calibration ``cal`` near ``e`` and its 95 % ``interval`` (:func:`checks_place`;
    ``length_ratio``: the records' length over the calibration's records'; ``replaced``: the
    samples the repair replaced, per record, which the spikes statistic leaves out): a :class:`Note`
    (its code the check's name) for each check that fired and the ``filtered_unchecked`` ones of
    :func:`unresolved_impacts`, and per check its :class:`rockdec.record.diagnostics.Outcome`."""
    level = settings.get("level", measured.DEFAULT_SETTINGS["level"])
    outcomes = diagnostics.evaluate([r.theta for r in records], analysis, cal, e, interval, level, length_ratio, replaced)
    notes = [Note(name, o.message) for name, o in outcomes.items() if o.fired]
    notes.extend(unresolved_impacts(records))
    return notes, outcomes


def unresolved_impacts(records: list[Record]) -> list:
    """A ``filtered_unchecked`` :class:`Note` for each record quantised so coarsely that the
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


def measure_model(records: list[Record], dt: float) -> tuple[record_measure.MeasuredModel | None, str | None]:
    """:func:`rockdec.record.record_measure.measure` of the records, or ``None`` and why it could not
    be measured (too few triples on one side of zero, say)."""
    from rockdec.record import record_measure

    try:
        return record_measure.measure([r.theta for r in records], dt), None
    except InputError as exc:
        return None, str(exc).rstrip(".")


def record_model(
    measurement, analysis: measured.Analysis, *, model: RecordModel | None = None, load: Load | str | None = None,
    sensor: SensorNoise | None = None, rocking: str | None = None, sensor_filter: SensorFilter | str | None = "auto",
) -> tuple[RecordModel, dict]:
    """The record model the calibration simulates (before :func:`rockdec.calibrate.calibration.binned_model`)
    and where each part came from.

    ``model`` declares every part; else ``load``, ``sensor`` and ``rocking`` declare theirs
    (the rocking model is the simplified one, eq. 4, unless declared) and the rest is
    measured (``measurement``, a :class:`rockdec.record.record_measure.MeasuredModel`, or ``None``
    when the records could not be measured; then the part is the paper's). A
    measured low-pass load (colour detected, :attr:`~rockdec.record.record_measure.MeasuredModel.coloured`)
    is stated by its pole per sample ``alpha``, as a corner ``-ln(alpha) N / (2 pi)`` in
    rocking frequencies at the ``N`` samples per cycle the analysis reads
    (``analysis.points_per_cycle``), so that the calibration, which simulates at that
    ``N``, simulates that pole; measured sensor noise (detected,
    :attr:`~rockdec.record.record_measure.MeasuredModel.noisy`) in units of ``sigma_Y``. A
    declared noise in rad is expressed in the records' ``sigma_Y``; a declared load given as
    text (:func:`rockdec.physics.record_model.parse_load`) is read with the records'
    ``dt`` and samples per cycle, which place a spectrum table in Hz and a base record
    against their rocking frequency ``1/(dt N)``. ``sensor_filter``: a declared
    :class:`~rockdec.physics.record_model.SensorFilter` (a corner in Hz placed at the records'
    rocking frequency ``1/(dt N)``), ``None`` (declared none) or ``"auto"`` (none; the records
    are checked for one by :func:`filter_decline`). Returns
    ``(model, sources)``, ``sources`` naming ``load``, ``sensor_noise``, ``sensor_filter`` and ``rocking`` as
    ``"declared"``, ``"measured"`` or ``"paper (not measured)"``.
    """
    if isinstance(load, str):
        load = parse_load(load, dt=analysis.dt, points_per_cycle=analysis.points_per_cycle)
    if model is not None:
        load, sensor, rocking, sensor_filter, how = model.load, model.sensor, model.rocking, model.filter, "declared"
        sources = {"load": how, "sensor_noise": how, "rocking": how, "sensor_filter": how}
    else:
        sources = {"rocking": "paper (the simplified model, eq. 4)" if rocking is None else "declared"}
        rocking = rocking or "simplified"
        missing = "paper (not measured)" if measurement is None else "measured"
        sources["load"] = "declared" if load is not None else missing
        sources["sensor_noise"] = "declared" if sensor is not None else missing
        sources["sensor_filter"] = "measured (none shown)" if isinstance(sensor_filter, str) else "declared"
        sensor_filter = None if isinstance(sensor_filter, str) else sensor_filter
        if load is None:
            load = WHITE
            if measurement is not None and measurement.coloured:
                load = Load("lowpass", -math.log(measurement.pole.value) * analysis.points_per_cycle / (2.0 * math.pi))
        if sensor is None:
            sensor = NO_NOISE
            if measurement is not None and measurement.noisy:
                sensor = SensorNoise(measurement.noise_ratio.value, "sigma_y")
    if sensor.units == "rad":
        sensor = SensorNoise(sensor.std / analysis.sigma_y, "sigma_y")
    if sensor_filter is not None:
        sensor_filter = sensor_filter.in_rocking(1.0 / (analysis.dt * analysis.points_per_cycle))
        sensor_filter.cycles_per_sample(analysis.points_per_cycle)  # refuses a corner at or above the Nyquist frequency
    return RecordModel(rocking, load, sensor, sensor_filter), sources


def _quantity(q, scale: float = 1.0) -> dict:
    """A measured quantity and its standard error for JSON (``scale`` multiplies both)."""
    return {"value": json_number(q.value * scale), "se": json_number(q.se * scale)}


def model_report(measurement, why_not: str | None, analysis: measured.Analysis, sources: dict, simulated: RecordModel, cal_settings: dict,
                 own_points_per_cycle: float, rolloff=None) -> dict:
    """The ``record_model`` of :func:`estimate`'s JSON: what was measured (each quantity
    with its standard error), what was detected, what the calibration simulated (the
    binned model, :func:`rockdec.calibrate.calibration.binned_model`) and where each part
    came from; ``g_side_share`` at ``own_points_per_cycle`` (:func:`colour_decline`);
    ``filter_rolloff``: the roll-off check (:func:`rockdec.record.record_measure.rolloff`,
    ``None`` when not made: a declared filter, or too few samples per cycle), and whether a
    steep filter shows (:func:`filter_decline`; a gentle one is the calibrated check
    ``filtered`` of :mod:`rockdec.record.diagnostics`)."""
    cal_ppc = cal_settings["points_per_cycle"]
    ratio = cal_settings.get("sigma_y_over_theta_cr")
    out = {
        "sources": sources,
        "simulated": {
            **simulated.key(),
            "load": simulated.load.to_dict() if simulated.load.kind != "spectrum" else {
                "kind": "spectrum", "rows": len(simulated.load.frequency), "source": simulated.load.source,
            },
            "load_pole_per_sample": json_number(simulated.load.pole(cal_ppc)),
            "points_per_cycle": json_number(cal_ppc),
            "sigma_y_over_theta_cr": ratio,
            "described": f"{simulated.rocking} rocking" + (f" (sigma_Y/theta_cr {ratio:.3g})" if ratio else "") + f", {simulated.load.describe()} load, "
            + (f"sensor noise {simulated.sensor.std:.3g} sigma_Y" if simulated.sensor.std > 0 else "no sensor noise")
            + (f", {simulated.filter.describe()} sensor filter" if simulated.filter is not None else ""),
        },
        "measured": None,
        "not_measured": why_not,
        "filter_rolloff": None if rolloff is None else {
            "slope": _quantity(rolloff.slope), "band_rocking": list(rolloff.band), "z": json_number(rolloff.z),
            "detected": rolloff.filtered,
        },
    }
    if measurement is not None:
        m = measurement
        rate = analysis.points_per_cycle / (2.0 * math.pi)  # corner in rocking frequencies per unit of -ln(pole)
        corner = (
            {"value": json_number(-math.log(m.pole.value) * rate), "se": json_number(m.pole.se / m.pole.value * rate)}
            if 0.0 < m.pole.value < 1.0 else {"value": None, "se": None}
        )
        out["measured"] = {
            "kind": m.kind,
            "detected": {"sensor_noise": m.noisy, "colour": m.coloured, "drift": m.drifting},
            "sensor_noise_sigma_y": _quantity(m.noise_ratio),
            "sensor_noise_z": json_number(m.noise_var.z),
            "load_pole_per_sample": _quantity(m.pole),
            "load_pole_z": json_number(m.pole.z),
            "load_shape": _quantity(m.shape),
            "load_shape_z": json_number(m.shape_z),
            "load_corner_rocking": corner,
            "load_corner_hz": _quantity(m.corner_hz),
            "drift_rms_sigma_y": json_number(m.drift_rms),
            "drift_z": json_number(m.drift_z),
            "g": _quantity(m.g),
            "g_asymmetry": _quantity(m.asymmetry),
            "g_side_share": json_number(m.side_g_share(own_points_per_cycle)),
            "triples": m.triples,
        }
    return out


def colour_decline(model: RecordModel, sources: dict, measurement, points_per_cycle: float, own_points_per_cycle: float | None = None) -> str | None:
    """Why ``e`` is declined for a measured load whose corner is not shown to lie above
    :data:`COLOUR_CORNER_FLOOR` rocking frequencies, in one sentence naming the measured
    corner and what would help; else ``None``. Any measured load whose side means read ``g``
    below :data:`SIDE_G_SHARE` of the signature's
    (:meth:`~rockdec.record.record_measure.MeasuredModel.side_g_share` at
    ``own_points_per_cycle``, the samples per cycle the analysis reads with the records' own
    ``g``; ``points_per_cycle`` when not given, NaN when ``g`` could not be read: no share,
    no decline by it; a ``g`` the user gives is not the records' own). A low-pass load: its corner is below the
    floor, or less than :data:`COLOUR_CORNER_Z` standard errors above it. A load measured
    white beneath sensor noise: its shape ratio
    (:meth:`~rockdec.record.record_measure.MeasuredModel.shape_corner_low`, at the
    ``points_per_cycle`` the analysis reads) allows a corner below the floor within
    :data:`COLOUR_CORNER_Z` errors. A declared load is calibrated as declared: the selection
    (:func:`select`) then judges its belts."""
    if sources.get("load") != "measured":
        return None
    share = np.nan if measurement is None else measurement.side_g_share(points_per_cycle if own_points_per_cycle is None else own_points_per_cycle)
    if share < SIDE_G_SHARE:
        return (
            f"g read off the side means of these records is {share:.2f} of the g their signature reads (below "
            f"{SIDE_G_SHARE:g}): the block's side follows the load, a load too slow for the measured model (a first-order "
            "low-pass corner) to describe, where the coverage study finds the corner read too high and e not covered; if "
            "the load is known, declare it (`load` lowpass:CORNER, spectrum:FILE or base:FILE, a record of the base's "
            "acceleration) and the calibration simulates it, with its coverage checked"
        )
    if model.load.kind != "lowpass":
        if measurement is None or not measurement.noisy:
            return None
        low = measurement.shape_corner_low(points_per_cycle, COLOUR_CORNER_Z)
        if low >= COLOUR_CORNER_FLOOR:
            return None
        return (
            f"beneath the sensor noise measured on these records the load's colour is not ruled out: its shape allows a "
            f"low-pass corner down to {low:.2f} times the rocking frequency ({COLOUR_CORNER_Z:g} errors), below "
            f"{COLOUR_CORNER_FLOOR:g}, where the coverage study finds that no calibration tells such a load apart from e; if "
            "the load is known, declare it (`load` white, lowpass:CORNER, spectrum:FILE or base:FILE) and the calibration "
            "simulates it, with its coverage checked"
        )
    corner, se = model.load.corner, 0.0
    if measurement is not None and 0.0 < measurement.pole.value < 1.0:
        se = corner * measurement.pole.se / (measurement.pole.value * -math.log(measurement.pole.value))
    if corner - COLOUR_CORNER_Z * se >= COLOUR_CORNER_FLOOR:
        return None
    where = f"below {COLOUR_CORNER_FLOOR:g}" if corner < COLOUR_CORNER_FLOOR else f"not {COLOUR_CORNER_Z:g} errors above {COLOUR_CORNER_FLOOR:g}"
    return (
        f"the load measured on these records is low-pass with its corner at {corner:.2f}"
        + (f" +- {se:.2f}" if se > 0.0 else "")
        + f" times the rocking frequency, {where}, where the coverage study finds that no calibration tells such a load "
        "apart from e; if the load is known, declare it (`load` lowpass:CORNER, spectrum:FILE or base:FILE, a record of "
        "the base's acceleration) and the calibration simulates it, with its coverage checked"
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


def filter_decline(rolloff) -> str | None:
    """Why ``e`` is declined, before any calibration, for records whose second differences fall
    faster than any unfiltered rocking record's (:attr:`rockdec.record.record_measure.Rolloff.filtered`:
    a filter of order two or more), in one sentence naming the slope and the declaration that
    would help; else ``None``. A gentler filter is left to the calibrated check ``filtered``
    (:mod:`rockdec.record.diagnostics`), which compares the records with the calibration's."""
    if rolloff is None or not rolloff.filtered:
        return None
    from rockdec.record.record_measure import ROLLOFF_FLOOR

    lo, hi = rolloff.band
    return (
        f"the spectrum of these records' second differences falls as f^{rolloff.slope.value:.1f} (+- {rolloff.slope.se:.2f}) "
        f"between {lo:g} and {hi:g} times the rocking frequency, {-rolloff.z:.0f} errors steeper than the f^{ROLLOFF_FLOOR:g} "
        f"that no unfiltered rocking record reaches: {diagnostics.FILTER_HELP}"
    )


def declared_contradictions(measurement, model: RecordModel, sources: dict, points_per_cycle: float) -> tuple:
    """A :class:`Note` for each declared part of ``model`` that the records' own measurement
    (``measurement``, :func:`rockdec.record.record_measure.measure`) contradicts: they differ
    by more than :data:`DECLARED_Z` standard errors of the measurement and by more than the
    factor :data:`DECLARED_FACTOR` (``noise_contradicted``: the sensor noise in ``sigma_Y``, a
    difference below :data:`rockdec.record.record_measure.NOISE_FLOOR` aside;
    ``load_contradicted``: a white or low-pass load's pole per sample at ``points_per_cycle``,
    the factor on its corner). A declaration is the user's knowledge and the measurement has
    cells where it is misread (a load slow enough for the side to follow it, :func:`colour_decline`),
    so it warns and the estimate keeps the declared model."""
    if measurement is None:
        return ()
    from rockdec.record.record_measure import NOISE_FLOOR

    notes = []
    if sources.get("sensor_noise") == "declared":
        told, read = model.sensor.std, measurement.noise_ratio
        gap = abs(told - read.value)
        if gap > max(DECLARED_Z * read.se, NOISE_FLOOR) and max(told, read.value) > DECLARED_FACTOR * min(told, read.value):
            notes.append(Note("noise_contradicted", (
                f"the declared `sensor_noise` ({told:.3g} sigma_Y) is not what these records show ({read.value:.3g} +- {read.se:.2g} "
                f"sigma_Y, {gap / read.se if read.se > 0 else math.inf:.0f} errors apart): the calibration simulates the declared "
                "noise, which moves e; check it, or give `sensor_noise` auto to have it measured"
            )))
    if sources.get("load") == "declared" and model.load.kind in ("white", "lowpass"):
        from rockdec.record.record_measure import pole_of_shape, shape_of_pole

        told, read, shape = model.load.pole(points_per_cycle), measurement.pole, measurement.shape

        def corner(pole):
            return -math.log(pole) * points_per_cycle / (2.0 * math.pi) if 0.0 < pole < 1.0 else math.inf

        def errors(gap, se):
            return abs(gap) / se if se > 0 else math.inf if gap else 0.0

        # the fit's pole and the shape ratio (which sees the colour beneath noise and has the
        # smaller error near a white load): the declaration is contradicted when either lies
        # DECLARED_Z errors away and both read a corner beyond DECLARED_FACTOR of the declared
        apart = max(errors(told - read.value, read.se), errors(float(shape_of_pole(told)) - shape.value, shape.se))
        read_corners = [corner(read.value), corner(float(pole_of_shape(shape.value)))]
        beyond = all(not max(c, corner(told)) <= DECLARED_FACTOR * min(c, corner(told)) for c in read_corners)
        if apart > DECLARED_Z and beyond:
            shown = "white" if min(read_corners) == math.inf else f"low-pass with its corner near {min(read_corners):.3g} times the rocking frequency"
            notes.append(Note("load_contradicted", (
                f"the declared `load` ({model.load.describe()}) is not what these records show ({shown}; pole per sample "
                f"{read.value:.3f} +- {read.se:.2g}, shape ratio {shape.value:.2f} +- {shape.se:.2g} against the declared "
                f"{told:.3f} and {float(shape_of_pole(told)):.2f}, {apart:.0f} errors apart): the calibration simulates the "
                "declared load, which moves e; check it, or give `load` auto to have it measured"
            )))
    return tuple(notes)


def base_short(model: RecordModel, sources: dict, points_per_cycle: float) -> tuple:
    """A :class:`Note` (``base_short``) when the declared load is a base record's spectrum
    (:func:`rockdec.physics.record_model.read_base_record`) that stops below the rocking
    record's Nyquist frequency, ``points_per_cycle / 2`` rocking frequencies (the analysis's
    samples per cycle): the table ends at the base record's own Nyquist frequency, and the
    calibration, which simulates at the rocking record's sampling, draws no load above the
    table's last row (:func:`rockdec.physics.loading.spectral_gain`), a smoother load than the
    base gave if it moved faster than its record shows; an empty tuple otherwise. A spectrum
    table (``spectrum:FILE``) states where the power is and is not checked."""
    load = model.load
    if sources.get("load") != "declared" or load.kind != "spectrum" or not load.source.startswith(BASE_SOURCE):
        return ()
    top, needed = float(load.frequency[-1]), points_per_cycle / 2.0
    if top >= (1.0 - BASE_NYQUIST_TOLERANCE) * needed:
        return ()
    return (Note("base_short", (
        f"the base record's spectrum stops at its Nyquist frequency, {top:.3g} times the rocking frequency, below the rocking "
        f"record's {needed:.3g}: the calibration simulates no load above {top:.3g}, which makes the interval too narrow if "
        f"the base moved faster than its record shows; give a base record sampled {needed / top:.3g} times as finely (as the "
        "rocking record is), or the load's spectrum up to the rocking record's Nyquist frequency as a table (`load` spectrum:FILE)"
    )),)


#: How a base record's load reads its ``source`` (:func:`rockdec.physics.record_model.read_base_record`).
BASE_SOURCE = "base record"

#: Relative shortfall of a base record's last spectral row below the rocking record's Nyquist
#: frequency that :func:`base_short` lets pass: a base record at the rocking record's step ends
#: exactly at it, up to rounding.
BASE_NYQUIST_TOLERANCE = 1e-3


def coverage_floor(n_sets: int) -> float:
    """Lowest calibrated coverage (:func:`rockdec.calibrate.belt.calibration_coverage`) at which an
    interval is taken to hold 95 %: the lower end of the binomial band
    ``0.95 - 1.96 sqrt(0.95 x 0.05 / n)`` of ``n`` calibration sets (what a belt that covers
    exactly 95 % shows on its own sets 97.5 % of the time)."""
    return 0.95 - belt.Z95 * math.sqrt(0.95 * 0.05 / max(n_sets, 1))


def select(per: dict, n_sets: int, belts: dict[str, belt.Belt]) -> tuple[str | None, list[dict], str | None]:
    """The reported estimator among :data:`rockdec.rdd.registry.CANDIDATES`: of those with a
    value, an interval narrower than the calibrated range, and a calibrated coverage that
    holds (:func:`coverage_floor`), the one whose belt gives the narrowest 95 % interval at
    a common ``e``, the median of the candidates' corrected values
    (:func:`rockdec.calibrate.belt.width_at`). Each record's own intervals are not compared: an
    estimator whose scatter put its interval against an end of the calibrated range, where
    the interval is cut short, would be picked for that scatter, and the picked interval
    would then miss more often than each candidate's own (``benchmarks/selection_rule.py``). Returns ``(name or None, selection, reason)``:
    ``selection`` lists each candidate's width, its width at the common ``e``, coverage,
    whether it holds and why not; ``reason`` is one sentence when none can be trusted."""
    floor = coverage_floor(n_sets)
    values = [per[name]["e"] for name in registry.CANDIDATES if per[name]["e"] is not None]
    common = float(np.median(values)) if values else math.nan
    rows = []
    for name in registry.CANDIDATES:
        est = per[name]
        low, high = est["interval"]
        width = None if est["e"] is None or low is None else high - low
        cov = est["coverage"]
        if est["beyond"] is not None:
            why = f"its raw value lies beyond what any calibrated e gives ({est['beyond']})"
        elif width is None:
            why = "; ".join(est["notes"]) or "it gave no value on these records"
        elif est["calibrated_range"] and low <= est["calibrated_range"][0] and high >= est["calibrated_range"][1]:
            why = "its 95 % interval spans the whole calibrated range: the record does not tell e"
        elif cov is None or cov < floor:
            why = f"its calibrated coverage {'-' if cov is None else f'{cov:.1%}'} is below {floor:.1%}"
        else:
            why = None
        rows.append({
            "estimator": name, "width": json_number(width) if width is not None else None,
            "width_at_common_e": json_number(belt.width_at(belts[name], common)) if why is None else None,
            "coverage": cov, "holds": why is None, "why_not": why,
        })
    trusted = [row for row in rows if row["holds"]]
    if trusted:
        return min(trusted, key=lambda row: row["width_at_common_e"])["estimator"], rows, None
    reason = "no estimator can be trusted on these records: " + "; ".join(f"{row['estimator']}: {row['why_not']}" for row in rows)
    return None, rows, reason


class Note(NamedTuple):
    """A warning of :func:`estimate`: a stable ``code`` (the name of a check of
    :mod:`rockdec.record.diagnostics`, or one of :data:`NOTE_CODES`) and its sentence."""

    code: str
    message: str


#: Codes of the warnings :func:`estimate` gives besides the checks of
#: :mod:`rockdec.record.diagnostics`, with what each says.
NOTE_CODES = {
    "g_unreadable": "g cannot be read off the records, so a given g is not checked against them",
    "g_outside": "a given g lies outside the calibrated interval of the records' own g",
    "g_unchecked": "a given g is checked against the records' own only to within a factor",
    "long_record": "the records are far longer than the calibration's, beyond the lengths whose coverage was measured",
    "calibration": "the stored calibration was rebuilt, or a stopped run's lock was taken over",
    "pooled_disagree": "records given together disagree on one e; e is declined",
    "pooled_unchecked": "a record given with others could not be analysed alone, so it was not checked against them",
    "noise_contradicted": "the declared sensor noise is not what the records show, beyond the measurement's error",
    "load_contradicted": "the declared load is not what the records show, beyond the measurement's error",
    "base_short": "a declared base record's spectrum stops below the rocking record's Nyquist frequency",
    "filtered_unchecked": "a record is quantised too coarsely for the check filtered to read its impacts; it was not checked",
    "transient_load": "a record's amplitude builds up and dies away: its load is a transient, not a stationary random load; e is declined",
}


class Analysed(NamedTuple):
    """The records and their analysis (stage 1 of :func:`estimate`).

    ``own``: the analysis with the records' own ``g`` (``None`` when it cannot be read and
    ``g`` is given); ``analysis``: the one the estimates come from (with the given ``g``,
    else ``own``); ``g``: as given (rad/s^2) or ``None``; ``notes``: :class:`Note` s so far;
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
    """Stage 1 of :func:`estimate`: check the records and analyse them (signatures, every
    estimator extrapolated to a zero window, :func:`rockdec.rdd.measured.analyse`), saying how
    long it and the calibration take (:func:`stage_seconds`, ``length_grid`` as it takes it).

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


class ModelChoice(NamedTuple):
    """The record model the calibration simulates and where each part came from (stage 2
    of :func:`estimate`, :func:`choose_model`).

    ``measurement``: :func:`rockdec.record.record_measure.measure` of the records (``None``
    when declared whole or not measurable, ``why_not`` then says why); ``measuring``:
    whether a part was left to measure; ``model`` and ``sources``: :func:`record_model`;
    ``cal_settings``: the calibration's settings
    (:func:`rockdec.calibrate.calibration.calibration_settings`); ``declined``: why no
    calibration fits these records (one sentence), else ``None``; ``rolloff``: the roll-off
    check (:func:`rockdec.record.record_measure.rolloff`, ``None`` when not made); ``notes``:
    :class:`Note` s on declared parts the records contradict (:func:`declared_contradictions`)."""

    measurement: object
    why_not: str | None
    measuring: bool
    model: RecordModel
    sources: dict
    cal_settings: dict
    declined: str | None
    rolloff: object = None
    notes: tuple = ()

    def report(self, analysed: Analysed) -> dict:
        """The ``record_model`` of the JSON document (:func:`model_report`)."""
        simulated = RecordModel.from_key(self.cal_settings["record_model"])
        out = model_report(self.measurement, self.why_not if self.measuring else None, analysed.analysis, self.sources, simulated,
                           self.cal_settings, analysed.own_points_per_cycle, self.rolloff)
        if self.declined:
            out["simulated"]["described"] = f"nothing (declined; a calibration would simulate {out['simulated']['described']})"
        return out


def choose_model(
    analysed: Analysed, *, model: RecordModel | None = None, load: Load | str | None = None, sensor: SensorNoise | None = None,
    rocking: str | None = None, theta_cr: float | None = None, sensor_filter: SensorFilter | str | None = "auto",
    repaired: dict | None = None, length_grid: bool = False,
) -> ModelChoice:
    """Stage 2 of :func:`estimate`: measure the records' model (sensor noise, load colour,
    drift) unless declared, check them for a filter after the block unless one (or none) is
    declared (:func:`rockdec.record.record_measure.rolloff`), choose what the calibration
    simulates (:func:`record_model`), note declared parts the records contradict
    (:func:`declared_contradictions`) and a base record whose spectrum stops short
    (:func:`base_short`), and whether the records must be declined (a transient load,
    :func:`transient_decline`, first and with a ``transient_load`` :class:`Note`, its model
    not measured; records given together whose own ``g`` lie too far apart, :attr:`Analysed.scales_apart`;
    :func:`filter_decline`, :func:`colour_decline`, or a part left to measure that cannot
    be). Housner's model (eq. 2) needs ``theta_cr``, and only it. ``repaired``: the repair
    the records had (:func:`rockdec.record.repair.settings`), which the calibration's sets
    get too. ``length_grid``: the calibration simulates records of the length grid's length
    (:func:`rockdec.calibrate.calibration.simulated_lengths`), shared by records of nearby lengths."""
    from rockdec.record.record_measure import rolloff

    measuring = model is None and (load is None or sensor is None)
    if model is None:
        check_filter_declared_with_model(sensor_filter, load, sensor)
    filtered = isinstance(sensor_filter, SensorFilter) or (model is not None and model.filter is not None)
    shaken = transient_decline(list(analysed.records), analysed.dt)
    measured_here = model is None and not filtered and shaken is None  # a transient's model is not measured: it is declined
    measurement, why_not = measure_model(list(analysed.records), analysed.dt) if measured_here else (None, "declared" if shaken is None else "a transient load")
    checking = model is None and isinstance(sensor_filter, str)
    found = rolloff([r.theta for r in analysed.records], analysed.analysis.points_per_cycle) if checking else None
    model, sources = record_model(measurement, analysed.analysis, model=model, load=load, sensor=sensor, rocking=rocking, sensor_filter=sensor_filter)
    if checking and found is None:
        sources["sensor_filter"] = "not checked (too few samples per cycle or too short records)"
    if (model.rocking == "housner") != (theta_cr is not None):
        raise InputError("Housner's model (eq. 2) needs the block's critical angle `theta_cr`, and only it; give both or neither.")
    ratio = analysed.analysis.sigma_y / theta_cr if theta_cr is not None else None
    cal_settings = calibration.calibration_settings(
        [r.theta.size for r in analysed.records], analysed.analysis.points_per_cycle, analysed.settings, model, ratio, repaired,
        length_grid=length_grid,
    )
    if shaken:
        declined = shaken
    elif analysed.scales_apart:
        declined = analysed.scales_apart
    elif measuring and measurement is None:  # a part left to measure cannot be: no calibration is known to fit
        declined = (
            f"the record model could not be measured ({why_not}), so whether sensor noise or a coloured load moves e "
            "here is not known; declare them (`load` and `sensor_noise`; `load` white with `sensor_noise` 0 is the paper's "
            "model) to have e estimated under the declared model"
        )
    else:
        declined = filter_decline(found) or colour_decline(
            model, sources, measurement, analysed.analysis.points_per_cycle, analysed.own_points_per_cycle,
        )
    notes = ((Note("transient_load", shaken),) if shaken else ()) + (
        *declared_contradictions(measurement, model, sources, analysed.analysis.points_per_cycle),
        *base_short(model, sources, analysed.analysis.points_per_cycle))
    return ModelChoice(measurement, why_not, measuring, model, sources, cal_settings, declined, found, notes)


class CalibrationNeeded(Exception):
    """The estimate asks for a calibration outside those it may read (``available`` of
    :func:`estimate`); ``settings`` are that calibration's. What a planner catches to learn
    which calibrations an estimate reads, its repair's decisions included, before any is built
    (:func:`rockdec.pipeline.campaign.plan`)."""

    def __init__(self, settings: dict):
        super().__init__(f"calibration-{calibration.settings_hash(settings)}.nc")
        self.settings = settings


class Calibrated(NamedTuple):
    """The calibration of the records (stage 3 of :func:`estimate`): ``cal`` (the stored
    simulated sets), whether it came from the cache, the seconds it took, the factor on
    its spread (:func:`rockdec.calibrate.calibration.spread_scale`), ``belts`` at the
    records' length and ``simulated_belts`` at the simulated one, ``notes`` (:class:`Note`)."""

    cal: object
    cached: bool
    seconds: float
    scale: float
    belts: dict
    simulated_belts: dict
    notes: tuple

    @property
    def n_sets(self) -> int:
        """Simulated record sets in the calibration."""
        return int(self.cal["raw"].sizes["e_true"] * self.cal["raw"].sizes["set"])


def calibrate(analysed: Analysed, choice: ModelChoice, cache_dir, available=None) -> Calibrated:
    """Stage 3 of :func:`estimate`: get the calibration of ``choice`` from ``cache_dir``
    or build and store it (:func:`rockdec.calibrate.calibration.load_or_build`), and its
    belts. ``available``: the settings hashes of the calibrations it may read (``None``: any);
    one outside them raises :class:`CalibrationNeeded`, before the cache is read."""
    cal_settings = choice.cal_settings
    if available is not None and calibration.settings_hash(cal_settings) not in available:
        raise CalibrationNeeded(cal_settings)
    scale = calibration.spread_scale(cal_settings, analysed.samples)
    simulated = sum(cal_settings["lengths"])
    shortened = (
        f"; the records' {analysed.samples} samples are calibrated on simulated records of {simulated} samples, "
        f"the spread scaled by sqrt({simulated} / {analysed.samples}) = {scale:.3g}" if scale != 1.0 else ""
    )
    stages = stage_seconds(analysed.samples, False, analysed.g is not None, records=len(analysed.records),
                           length_grid="length_grid" in cal_settings)
    log.info(
        f"calibration {calibration.settings_hash(cal_settings)}: {console.about(stages['calibrating'])} to build when it is not stored"
        f"{shortened}"
    )
    started = time.perf_counter()
    messages: list[str] = []
    cal, cached = calibration.load_or_build(cal_settings, cache_dir, messages)
    seconds = time.perf_counter() - started
    belts = belt.belts(cal, scale)  # e's belts at the records' length
    simulated_belts = belts if scale == 1.0 else belt.belts(cal)  # at the simulated length: coverage on the sets, g's interval
    return Calibrated(cal, cached, seconds, scale, belts, simulated_belts, tuple(Note("calibration", m) for m in messages))


def correct(analysed: Analysed, calibrated: Calibrated) -> dict:
    """Stage 4 of :func:`estimate`: every estimator's raw value corrected for its bias and
    its 95 % interval, by inverting its belt (:func:`rockdec.calibrate.belt.correct`), with
    its calibrated coverage; a raw value beyond the belt's mean curve gives no value
    (:func:`beyond`). Returns the ``estimators`` of the JSON document."""
    analysis, belts = analysed.analysis, calibrated.belts
    per = {}
    for name in registry.ESTIMATORS:
        c = belt.correct(belts[name], analysis.raw[name])
        side = beyond(belts[name], analysis.raw[name], c)
        per[name] = {
            "raw": json_number(analysis.raw[name]),
            "e": None if side else json_number(c.value),
            "beyond": side,
            "calibrated_range": [json_number(belts[name].e[0]), json_number(belts[name].e[-1])] if belts[name].e.size else None,
            "interval": [json_number(c.low), json_number(c.high)],
            "coverage": json_number(belt.calibration_coverage(calibrated.cal, name, calibrated.simulated_belts[name])),
            "triggers": int(analysis.count[registry.trigger(name)][-1]),
            "notes": [note for note in c.notes if not (side and "nearest point" in note)],  # no value is shown
        }
    return per


def gains_speed(analysed: Analysed, calibrated: Calibrated) -> str | None:
    """Why the records cannot be a rocking block's, when their impacts gain speed: ``e_v``
    (the slope of ``D_v`` after the impact over the slope before, eq. 6) read above 1 by more
    than the upper end of its belt's 95 % band at the top of the calibrated range, which
    no block that loses energy at impacts gives (a record that runs backwards in time, or a
    system that is not a rocking block); else ``None``."""
    b = calibrated.belts["e_v"]
    raw = analysed.analysis.raw["e_v"]
    if b.e.size == 0 or not np.isfinite(raw):
        return None
    top = float(b.mean[-1] + np.max(np.atleast_1d(b.q_high)) * b.spread[-1])
    if not (raw > 1.0 and raw > top):
        return None
    return (
        f"the impacts of these records gain speed (e_v reads {raw:.3f}, above the {top:.3f} that a block losing energy at "
        "impacts gives at most): the record runs backwards in time, or the system is not a rocking block; e is not estimated"
    )


class GReading(NamedTuple):
    """``g`` as the report gives it (stage 6 of :func:`estimate`): its value (rad/s^2, as
    given or corrected), 95 % interval and its calibrated coverage (``None`` when there is
    none), the note on how it was found, and :class:`Note` s on a given ``g``."""

    value: float | None
    interval: list | None
    coverage: float | None
    note: str
    notes: tuple


def read_g(analysed: Analysed, choice: ModelChoice, calibrated: Calibrated, chosen: str | None, e_chosen: float) -> GReading:
    """Stage 6 of :func:`estimate`: ``g`` corrected at the reported ``e`` with its 95 %
    interval (:func:`rockdec.calibrate.belt.g_interval`), or as given, checked against the
    records' own."""
    g, own, analysis = analysed.g, analysed.own, analysed.analysis
    g_belt = calibrated.simulated_belts[measured.G_NAME]
    e_name = chosen or DEFAULT_ESTIMATOR  # the estimator whose corrected e corrects g
    e_belt = calibrated.simulated_belts[e_name]
    g_band = belt.g_band(calibrated.cal, e_name, e_belt, g_belt)
    value = g if g is not None else belt.correct_g(g_belt, analysis.raw[measured.G_NAME], e_chosen)
    no_interval = g is not None or chosen is None
    low, high = (math.nan, math.nan) if no_interval else belt.g_interval(g_band, e_belt, g_belt, analysis.raw[e_name], analysis.raw[measured.G_NAME])
    notes = []
    if g is not None and own is not None:
        own_low, own_high = belt.g_interval(g_band, e_belt, g_belt, own.raw[e_name], own.raw[measured.G_NAME])
        if np.isfinite(own_low) and not own_low <= g <= own_high:
            notes.append(Note("g_outside", (
                f"the given `g` {g:g} lies outside the records' own g, {own_low:.4g}-{own_high:.4g} rad/s^2 (calibrated 95 % "
                "interval): the estimate rests on the given g"
            )))
        elif not np.isfinite(own_low):
            notes.append(Note("g_unchecked", (
                f"the given `g` {g:g} was checked against the records' own g only to within a factor {G_FACTOR:g} "
                f"({own.raw[measured.G_NAME]:.4g} rad/s^2 read off them, not corrected): this calibration gives their g no "
                "interval; the estimate rests on the given g"
            )))
    return GReading(
        json_number(value),
        None if g is not None or not np.isfinite(low) else [json_number(low), json_number(high)],
        None if no_interval else json_number(belt.g_calibration_coverage(calibrated.cal, e_name, e_belt, g_belt, g_band)),
        _g_note(g is not None, bool(np.isfinite(low)), chosen is not None, calibrated.scale, sum(choice.cal_settings["lengths"])),
        tuple(notes),
    )


def _g_note(given: bool, has_interval: bool, has_e: bool, scale: float, simulated: int) -> str:
    """How the report's ``g`` was found (the JSON's ``g_interval_note``)."""
    if given:
        return "as given"
    if has_interval:
        return (
            "95 % interval: the corrected g over the scatter of the corrected g about the true g on the calibration's "
            "simulated records (the error of the corrected e included)"
            + (f", as long as those records ({simulated} samples): wider than the records' own" if scale != 1.0 else "")
        )
    if not has_e:
        return "no interval: no e was estimated, and g is corrected at the corrected e"
    return "no interval: g's interval needs a corrected e whose interval lies inside the calibrated range"


def long_record_note(analysed: Analysed, choice: ModelChoice) -> tuple:
    """A :class:`Note` when the records are more than :data:`LONG_RATIO` times as long as
    the calibration's simulated records (an empty tuple otherwise)."""
    simulated = sum(choice.cal_settings["lengths"])
    if analysed.samples <= LONG_RATIO * simulated:
        return ()
    return (Note("long_record", (
        f"{analysed.samples} samples are {analysed.samples / simulated:.0f} times the calibration's simulated records, beyond the "
        f"{LONG_RATIO:.0f} times at which the interval's coverage was measured: the narrower the interval, the more "
        "the calibration's own error of the bias counts"
    )),)


class Verdict(NamedTuple):
    """What the repair-and-retry of :func:`estimate` decides on, read off one estimate's
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


class Outcome(NamedTuple):
    """What :func:`estimate` gives: the JSON ``document`` (:func:`document`), for plots
    the ``analysis`` (:class:`rockdec.rdd.measured.Analysis`) and the ``belts`` of every
    estimator at the records' length (empty when the records were declined), and the
    :class:`Verdict` the repair-and-retry reads."""

    document: dict
    analysis: measured.Analysis
    belts: dict
    verdict: Verdict


def document(analysed: Analysed, choice: ModelChoice, calibrated: Calibrated | None, per: dict, selection: tuple,
             g_reading: GReading | None, notes: list, checks: dict, repaired: dict | None = None) -> dict:
    """The report stage of :func:`estimate`: its JSON document (keys in
    :func:`estimate`'s docstring). ``calibrated``, ``g_reading`` ``None``: the records were
    declined before any calibration (``choice.declined``). ``repaired``: the document's
    ``repair`` (:func:`repair_report`; none repaired when not given)."""
    chosen, rows, reason = selection
    shown = per[chosen] if chosen else {"e": None, "interval": [None, None], "coverage": None, "raw": None}
    analysis, g = analysed.analysis, analysed.g
    if calibrated is None:
        g_reading = GReading(None if g is None else json_number(g), None, None, _g_note(g is not None, False, False, 1.0, 0), ())
        cal = {"file": None, "cached": False, "seconds": 0.0}
    else:
        cal = {
            "file": f"calibration-{calibration.settings_hash(choice.cal_settings)}.nc", "cached": calibrated.cached,
            "seconds": round(calibrated.seconds, 2), "simulated_samples": sum(choice.cal_settings["lengths"]),
            "spread_scale": calibrated.scale,
        }
    return {
        "e": shown["e"], "interval": shown["interval"], "reason": reason, "estimator": chosen, "selection": rows,
        "coverage": shown["coverage"], "raw": shown["raw"], "g": g_reading.value, "g_given": g is not None,
        "g_raw": json_number(analysis.raw[measured.G_NAME]), "g_interval": g_reading.interval, "g_coverage": g_reading.coverage,
        "g_interval_note": g_reading.note, "points_per_cycle": json_number(analysis.points_per_cycle), "sigma_y": json_number(analysis.sigma_y),
        "dt": analysed.dt, "records": [r.source for r in analysed.records], "samples": analysed.samples,
        "nan_samples": int(analysis.nan_samples), "record_model": choice.report(analysed), "estimators": per,
        "warnings": [n.message for n in notes], "warning_codes": [n.code for n in notes], "diagnostics": diagnostics_report(checks),
        "rockdec_version": __version__, "calibration": cal,
        "repair": repaired if repaired is not None else repair_report(None, analysed.dt, True),
    }


def diagnostics_report(checks: dict) -> dict:
    """The JSON document's ``diagnostics``: per check of ``checks`` (``{name:
    diagnostics.Outcome}``) its ``statistic``, ``threshold`` and whether it ``fired``."""
    return {name: {"statistic": json_number(o.statistic), "threshold": json_number(o.threshold), "fired": o.fired}
            for name, o in checks.items()}


def declined_rows(analysed: Analysed) -> tuple[dict, tuple]:
    """The ``estimators`` and the selection of records declined before any calibration:
    every estimator's raw value, no corrected value or interval."""
    analysis = analysed.analysis
    per = {
        name: {
            "raw": json_number(analysis.raw[name]), "e": None, "beyond": None, "calibrated_range": None, "interval": [None, None],
            "coverage": None, "triggers": int(analysis.count[registry.trigger(name)][-1]), "notes": [],
        }
        for name in registry.ESTIMATORS
    }
    why = "not calibrated: the records are declined (see the reason)"
    rows = [{"estimator": name, "width": None, "width_at_common_e": None, "coverage": None, "holds": False, "why_not": why}
            for name in registry.CANDIDATES]
    return per, (None, rows, None)


class Pooled(NamedTuple):
    """What :func:`check_pooled` (a stage of :func:`estimate`) makes of records given
    together: the ``selection`` of :func:`select`, its estimator and reason replaced when
    the records disagree on one ``e``; its :class:`Note` s; its check
    (``{"pooled_consistency": rockdec.record.diagnostics.Outcome}``, empty for a single
    record)."""

    selection: tuple
    notes: tuple
    checks: dict


def check_pooled(analysed: Analysed, choice: ModelChoice, calibrated: Calibrated, selection: tuple) -> Pooled:
    """The stage of :func:`estimate` after :func:`select`: whether records given together
    agree on one ``e`` (:func:`rockdec.calibrate.consistency.check`: Cochran's ``Q`` of
    each record's own raw value of the reported estimator (:func:`_alone`) about their
    weighted mean, each with the spread of the calibration's belt scaled to its length). A
    single record passes unchanged. A record that cannot be analysed alone is left out of
    the test with a ``pooled_unchecked`` :class:`Note`.

    Records that disagree decline ``e`` (``reason`` names what each reads alone) with a
    ``pooled_disagree`` :class:`Note`, rather than print the pooled interval beside a
    warning. The pooled interval is a claim about one ``e`` that the test rejects: for
    records of ``e`` 0.80 and 0.90 it holds neither, and an interval beside a warning is
    still copied into a paper; a record-by-record estimate is always valid and costs a
    pool of one block little, which the test declines on few pools
    (:data:`rockdec.calibrate.consistency.LEVEL`; ``benchmarks/pooled_consistency.py``).
    """
    records = analysed.records
    chosen, rows, _ = selection
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
    return Pooled((None, rows, why), tuple(notes), checks)


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


def repair_report(done: repair.Repair | None, dt: float, enabled: bool, why: str | None = None) -> dict:
    """The JSON document's ``repair``: whether the repair was ``enabled``, the ``spikes``
    replaced (``spikes_removed``), the high-pass corner in rocking frequencies and in Hz (``None`` without
    one), and ``why`` it was done, in words (``None`` when nothing was repaired)."""
    spikes = 0 if done is None else done.removed
    corner = None if done is None else done.corner
    hz = None if corner is None else json_number(done.per_sample / dt)
    return {"enabled": enabled, "spikes_removed": spikes, "highpass_corner_rocking": corner, "highpass_corner_hz": hz,
            "repaired": done is not None and done.repaired, "why": why}


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
    """``outcome`` with ``e`` declined when a check of :data:`DECLINING_CHECKS` fired on the
    records as estimated (after any repair): ``reason`` names the check and its message, after
    what :func:`blunted_cause` says of a fired ``filtered``. A ``filtered`` that fired warns
    only when the records' filter (or its absence, in a record model declared whole) was
    declared; ``unfiltered``: :func:`declining_fired`."""
    verdict, doc = outcome.verdict, outcome.document
    fired = declining_fired(verdict, unfiltered)
    if doc["e"] is None or not fired:
        return outcome
    defects = "; ".join(f"{name}: {verdict.fired[name]}" for name in fired)
    repaired = " after the repair" if verdict.repaired else ""
    reason = (f"{blunted_cause(verdict, unfiltered)}the records show a defect that moves e by more than its interval and that{repaired} "
              f"is still there ({defects}); e is declined rather than given with an interval that does not hold")
    return outcome._replace(document={**doc, "e": None, "interval": [None, None], "coverage": None, "estimator": None, "reason": reason})


def estimate(
    records: list[Record], *, cache_dir, g: float | None = None, settings: dict | None = None, model: RecordModel | None = None,
    load: Load | str | None = None, sensor: SensorNoise | None = None, rocking: str | None = None, theta_cr: float | None = None,
    sensor_filter: SensorFilter | str | None = "auto",
    repair_records: bool = True, available=None, length_grid: bool = False,
) -> Outcome:
    """Calibrated estimates of ``e`` from ``records`` of one block (pooled), in named stages,
    after the records' repair.

    A record that holds each value for several samples is refused first
    (:func:`refuse_held`). Repair (``repair_records``, :mod:`rockdec.record.repair`): spikes are replaced before
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

    The stages of each estimate (:func:`estimate_once`): :func:`analyse` (check and analyse)
    → :func:`choose_model` (measure the record model, or take the declared one; decline when
    no calibration fits) → :func:`calibrate` (get or build the calibration) →
    :func:`correct` (correct every estimator and invert its belt) → :func:`select` (the
    reported estimator; none when the impacts gain speed, :func:`gains_speed`) →
    :func:`check_pooled` (records given together agree on one ``e``, else ``e`` is declined)
    → :func:`read_g` → :func:`diagnose` (the checks, thresholds from the calibration) →
    :func:`document` (the report).

    ``model`` declares the whole record model (:mod:`rockdec.physics.record_model`); else
    ``load``, ``sensor``, ``rocking`` and ``sensor_filter`` (``"auto"``: checked for, none
    simulated; ``None``: none) declare their parts and the rest is measured.
    Housner's model (eq. 2) needs the block's ``theta_cr`` (rad). Returns an
    :class:`Outcome` whose ``document`` holds ``e``, ``interval`` (95 %), ``reason`` (why
    ``e`` is null), ``estimator``, ``selection``, ``coverage``, ``raw``, ``g`` (rad/s^2),
    ``g_given``, ``g_raw``, ``g_interval``, ``g_coverage``, ``g_interval_note``,
    ``points_per_cycle``, ``sigma_y``, ``dt``, ``records``, ``samples``, ``nan_samples``,
    ``record_model`` (:func:`model_report`), ``estimators`` (per estimator: ``raw``,
    ``e``, ``interval``, ``coverage``, ``triggers``, ``notes``, ``calibrated_range``,
    ``beyond``), ``warnings`` and ``warning_codes`` (:class:`Note`), ``diagnostics``,
    ``rockdec_version``, ``calibration`` and ``repair`` (:func:`repair_report`).

    ``available``: the settings hashes of the calibrations the estimate may read (``None``:
    any, built when absent); the first it asks for outside them raises
    :class:`CalibrationNeeded`. The estimate reads at most two: that of the records as given
    (spikes replaced) and, when the repair decides on the high-pass, that of the high-passed
    records.

    ``length_grid``: calibrations shared by records of nearby lengths (:func:`choose_model`),
    their spread scaled to the records' length; a campaign of many lengths builds few.
    """
    options = dict(cache_dir=cache_dir, g=g, settings=settings, model=model, load=load, sensor=sensor, rocking=rocking, theta_cr=theta_cr,
                   sensor_filter=sensor_filter, available=available, length_grid=length_grid)
    records = list(records)
    refuse_held(records)  # before the repair, whose high-pass would hide the hold
    if not repair_records:
        return estimate_once(records, None, None, False, **options)
    thetas = [r.theta for r in records]
    cleaned, done = repair.apply(thetas, repair.settings(True, False), math.nan)  # no high-pass: no rocking frequency needed
    found = done.removed
    despiked = [r._replace(theta=y) for r, y in zip(records, cleaned)] if found else records
    repaired = repair.settings(True, False) if found else None
    why = f"{found} isolated sample{'s' if found > 1 else ''} off {repair.SPIKE_Z:g} robust scales of the second differences" if found else None
    try:
        first, refusal = estimate_once(despiked, repaired, done if found else None, True, why, **options), None
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
        second = estimate_once([r._replace(theta=y) for r, y in zip(records, filtered)], hp, done, True, why, **options)
    except RecordError:
        second = None
    if failed and (second is None or not second.verdict.calibrated):  # the high-pass did not help: as given
        if first is None:
            raise refusal
        return decline_unrepaired(first, unfiltered)
    if second is None:
        return decline_unrepaired(first, unfiltered)
    return decline_unrepaired(second, unfiltered)


def estimate_once(
    records: list[Record], repaired: dict | None, done: repair.Repair | None, enabled: bool, why: str | None = None, *, cache_dir,
    g: float | None = None, settings: dict | None = None, model: RecordModel | None = None, load: Load | str | None = None,
    sensor: SensorNoise | None = None, rocking: str | None = None, theta_cr: float | None = None,
    sensor_filter: SensorFilter | str | None = "auto", available=None, length_grid: bool = False,
) -> Outcome:
    """One estimate of :func:`estimate` on ``records`` as they are (already repaired as
    ``repaired`` says, :func:`rockdec.record.repair.settings`, with ``done`` what the repair
    did, ``why`` in words; ``enabled``: whether the repair was on), in the stages
    :func:`estimate` lists; the calibration's sets are repaired alike (``available``:
    :func:`calibrate`; ``length_grid``: :func:`choose_model`)."""
    analysed = analyse(records, g=g, settings=settings, length_grid=length_grid)
    report = repair_report(done, analysed.dt, enabled, why)
    choice = choose_model(analysed, model=model, load=load, sensor=sensor, rocking=rocking, theta_cr=theta_cr, sensor_filter=sensor_filter,
                          repaired=repaired, length_grid=length_grid)
    if choice.declined:
        per, selection = declined_rows(analysed)
        doc = document(analysed, choice, None, per, (None, selection[1], choice.declined), None, [*analysed.notes, *choice.notes], {}, report)
        return Outcome(doc, analysed.analysis, {}, Verdict.of(choice, False, {}, done))
    calibrated = calibrate(analysed, choice, cache_dir, available)
    per = correct(analysed, calibrated)
    selection = select(per, calibrated.n_sets, calibrated.belts)
    impossible = gains_speed(analysed, calibrated)
    if impossible:
        selection = (None, selection[1], impossible)
    pooled = check_pooled(analysed, choice, calibrated, selection)
    chosen = pooled.selection[0]
    shown = per[chosen] if chosen else {"e": None, "interval": [None, None]}
    g_reading = read_g(analysed, choice, calibrated, chosen, math.nan if shown["e"] is None else shown["e"])
    notes = [*analysed.notes, *choice.notes, *calibrated.notes, *g_reading.notes, *long_record_note(analysed, choice), *pooled.notes]
    fired, checks = diagnose(list(analysed.records), analysed.analysis, analysed.settings, calibrated.cal,
                             *checks_place(per, shown), 1.0 / calibrated.scale**2, None if done is None else done.spikes)
    doc = document(analysed, choice, calibrated, per, pooled.selection, g_reading, notes + fired, {**checks, **pooled.checks}, report)
    verdict = Verdict.of(choice, True, {name: o.message for name, o in {**checks, **pooled.checks}.items() if o.fired}, done)
    return Outcome(doc, analysed.analysis, calibrated.belts, verdict)


def beyond(b: belt.Belt, raw: float, c: belt.Corrected) -> str | None:
    """Why the corrected value ``c`` of the raw value ``raw`` is no estimate, or ``None``.

    When ``raw`` lies outside every value the belt's mean curve takes, :func:`belt.correct`
    returns the nearest point of the curve, which estimates nothing: ``"below"`` or
    ``"above"`` when that point is an end of the calibrated range of ``e`` (which then
    bounds ``e``), ``"unreached"`` when it is inside the range.
    """
    if b.e.size == 0 or not (np.isfinite(raw) and np.isfinite(c.value)) or b.mean.min() <= raw <= b.mean.max():
        return None
    if c.value == b.e[0]:
        return "below"
    return "above" if c.value == b.e[-1] else "unreached"



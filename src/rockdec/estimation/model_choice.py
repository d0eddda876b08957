"""Stage 2 of the estimate: the record model the calibration simulates (measured off the
records, or declared), where each part came from, and why no calibration fits when none does.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from rockdec.calibrate import calibration
from rockdec.estimation.analysed import Analysed, transient_decline
from rockdec.estimation.notes import Note
from rockdec.physics.record_model import NO_NOISE, WHITE, Load, RecordModel, SensorFilter, SensorNoise, check_filter_declared_with_model, parse_load
from rockdec.rdd import measured
from rockdec.record import diagnostics
from rockdec.record.records import Record
from rockdec.validate import InputError

if TYPE_CHECKING:
    from rockdec.record import record_measure

__all__ = ["BASE_NYQUIST_TOLERANCE", "BASE_SOURCE", "COLOUR_CORNER_FLOOR", "COLOUR_CORNER_Z", "DECLARED_FACTOR", "DECLARED_Z", "ModelChoice", "SIDE_G_SHARE", "base_short", "choose_model", "colour_decline", "declared_contradictions", "filter_decline", "measure_model", "record_model"]

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

#: How a base record's load reads its ``source`` (:func:`rockdec.physics.record_model.read_base_record`).
BASE_SOURCE = "base record"

#: Relative shortfall of a base record's last spectral row below the rocking record's Nyquist
#: frequency that :func:`base_short` lets pass: a base record at the rocking record's step ends
#: exactly at it, up to rounding.
BASE_NYQUIST_TOLERANCE = 1e-3


class ModelChoice(NamedTuple):
    """The record model the calibration simulates and where each part came from (stage 2
    of :func:`rockdec.estimation.estimate`, :func:`choose_model`).

    ``measurement``: :func:`rockdec.record.record_measure.measure` of the records (``None``
    when declared whole or not measurable, ``why_not`` then says why); ``measuring``:
    whether a part was left to measure; ``model`` and ``sources``: :func:`record_model`;
    ``cal_settings``: the calibration's settings
    (:func:`rockdec.calibrate.calibration.calibration_settings`); ``declined``: why no
    calibration fits these records (one sentence), else ``None``; ``rolloff``: the roll-off
    check (:func:`rockdec.record.record_measure.rolloff`, ``None`` when not made); ``notes``:
    :class:`~rockdec.estimation.notes.Note` s on declared parts the records contradict (:func:`declared_contradictions`)."""

    measurement: object
    why_not: str | None
    measuring: bool
    model: RecordModel
    sources: dict
    cal_settings: dict
    declined: str | None
    rolloff: object = None
    notes: tuple = ()


def choose_model(
    analysed: Analysed, *, model: RecordModel | None = None, load: Load | str | None = None, sensor: SensorNoise | None = None,
    rocking: str | None = None, theta_cr: float | None = None, sensor_filter: SensorFilter | str | None = "auto",
    repaired: dict | None = None, length_grid: bool = False,
) -> ModelChoice:
    """Stage 2 of :func:`rockdec.estimation.estimate`: measure the records' model (sensor noise, load colour,
    drift) unless declared, check them for a filter after the block unless one (or none) is
    declared (:func:`rockdec.record.record_measure.rolloff`), choose what the calibration
    simulates (:func:`record_model`), note declared parts the records contradict
    (:func:`declared_contradictions`) and a base record whose spectrum stops short
    (:func:`base_short`), and whether the records must be declined (a transient load,
    :func:`transient_decline`, first and with a ``transient_load`` :class:`~rockdec.estimation.notes.Note`, its model
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
    (:func:`~rockdec.estimation.selected.select`) then judges its belts."""
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
    """A :class:`~rockdec.estimation.notes.Note` for each declared part of ``model`` that the records' own measurement
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
    """A :class:`~rockdec.estimation.notes.Note` (``base_short``) when the declared load is a base record's spectrum
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

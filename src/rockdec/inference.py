"""From measured records to a calibrated ``e``: what ``rockdec estimate`` computes.

:func:`estimate` analyses the records (:func:`rockdec.measured.analyse`), checks that they
look like rocking (:func:`rockdec.measured.rocking_shape`) and that a given ``g`` agrees
with the records' own, fetches or builds the calibration for their lengths and sampling
(:mod:`rockdec.calibration`), corrects every estimator and gives its 95 % interval,
corrects ``g`` the same way, and lists what looks wrong with the records
(:func:`diagnose`). When no ``e`` can be given, ``reason`` says why.

The calibration simulates records as long as the measured ones, so its cost grows with
their length (:func:`cost`); the command line refuses, before reading the records, a run
the machine cannot finish soon. Two shortcuts for long records were measured and do not
cover (README): calibrating on shorter records with the spread scaled by the square
root of the length ratio (the bias itself moves with the length), and fewer simulated
sets per ``e`` (the belt's cubic mean then misses the true mean by about 0.001, more
than the spread of a record of 20 million samples). Records longer than
:data:`LONG_SAMPLES` are answered with a warning that says so.
"""

from __future__ import annotations

import math
import time
import warnings
from typing import TYPE_CHECKING

import numpy as np

from rockdec import __version__, belt, calibration, fits, measured, registry
from rockdec.record_model import NO_NOISE, WHITE, Load, RecordModel, SensorNoise
from rockdec.records import Record, RecordError, distinct, same_step
from rockdec.validate import InputError

from rockdec.registry import DEFAULT_ESTIMATOR

if TYPE_CHECKING:
    from rockdec import record_measure

#: Fewest triggers in the largest window before the result is called unreliable.
FEW_TRIGGERS = 100

#: Records (in all) longer than this are warned about: their spread falls below the
#: accuracy of the belt's fitted mean (about 0.001 at e = 0.95, measured on 20-million-sample records).
LONG_SAMPLES = 2_000_000

#: A given ``g`` off the records' own by more than this factor is refused before any
#: calibration (the calibrated 95 % spread of ``g`` is a few per cent).
G_FACTOR = 2.0

#: Peaks beyond this many ``sigma_Y`` are called spikes (or overturning).
SPIKE_SIGMAS = 15.0

#: Cost model of :func:`cost`, measured on an idle 2-core machine: seconds per sample to
#: read a CSV (pandas) and to analyse a record; seconds per simulated and analysed
#: calibration sample on one core; bytes held per sample while reading and analysing.
CSV_SECONDS, ANALYSIS_SECONDS, CALIBRATION_SECONDS, BYTES_PER_SAMPLE = 5e-7, 1.2e-7, 1.3e-7, 96.0


def cost(samples: int, csv: bool, g_given: bool, cores: int = 2) -> tuple[float, float]:
    """``(seconds, bytes)`` that :func:`estimate` needs for records of ``samples`` in all,
    calibration included (:data:`CSV_SECONDS` and the other constants of the model)."""
    calibrated = samples * len(calibration.E_GRID) * calibration.SETS_PER_E
    seconds = samples * (CSV_SECONDS * csv + ANALYSIS_SECONDS * (1 + g_given)) + calibrated * CALIBRATION_SECONDS / cores
    return seconds, samples * BYTES_PER_SAMPLE


def diagnose(records: list[Record], analysis: measured.Analysis, settings: dict) -> list[str]:
    """Warnings about the records: few triggers, coarse sampling, asymmetry, drift, spikes."""
    notes = []
    for trigger, name in (("a", "D_a (extremum)"), ("v", "D_v (zero crossing)")):
        n = int(analysis.count[trigger][-1])
        if n < FEW_TRIGGERS:
            notes.append(f"only {n} {name} triggers in the largest window: the estimates rest on few segments; pool longer records")
    level = settings.get("level", measured.DEFAULT_SETTINGS["level"])
    floor = fits.min_points_per_cycle(analysis.raw[DEFAULT_ESTIMATOR] if np.isfinite(analysis.raw[DEFAULT_ESTIMATOR]) else 0.95, level)
    if analysis.points_per_cycle < floor:
        notes.append(
            f"{analysis.points_per_cycle:.1f} samples per cycle at sigma_Y is below {floor:.1f}, too coarse for the local fits "
            "of e1..e4 (eq. 27); sample faster"
        )
    y = np.concatenate([r.theta - np.nanmean(r.theta) for r in records])
    y = y[np.isfinite(y)]
    skew = float(np.mean(y**3) / np.mean(y**2) ** 1.5)
    if abs(skew) > 0.5:
        notes.append(f"the response is asymmetric (skewness {skew:+.2f}): the block may lean on one side; the model assumes a symmetric block")
    if float(np.max(np.abs(y))) > SPIKE_SIGMAS * analysis.sigma_y:
        notes.append(f"a peak of {np.max(np.abs(y)) / analysis.sigma_y:.0f} sigma_Y: the record holds a spike or the block overturns")
    for r in records:
        quarters = np.array_split(r.theta - np.nanmean(r.theta), 4)
        spread = np.array([np.sqrt(np.nanmean(q**2)) for q in quarters])
        if spread.max() > 2.0 * spread.min():
            notes.append(f"{r.source}: the rms of its quarters ranges {spread.min():.3g}-{spread.max():.3g} rad: the response is not stationary")
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
    """:func:`rockdec.measured.analyse`, its refusals as :class:`RecordError` naming the
    records (a spike, when there is one, is named as the cause)."""
    names = ", ".join(r.source for r in records)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # empty windows are reported through the trigger counts
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
            f"--g {g:g} is {ratio:.3g} times the g the records show ({own.raw[measured.G_NAME]:.3g} rad/s^2, read off the "
            f"free response of {names}); give g = nu^2 theta_cr in rad/s^2 (theta_cr in rad, not degrees), or leave --g out."
        )


def measure_model(records: list[Record], dt: float) -> tuple[record_measure.MeasuredModel | None, str | None]:
    """:func:`rockdec.record_measure.measure` of the records, or ``None`` and why it could not
    be measured (too few triples on one side of zero, say)."""
    from rockdec import record_measure

    try:
        return record_measure.measure([r.theta for r in records], dt), None
    except InputError as exc:
        return None, str(exc).rstrip(".")


def record_model(
    measurement, analysis: measured.Analysis, *, model: RecordModel | None = None, load: Load | None = None,
    sensor: SensorNoise | None = None, rocking: str | None = None,
) -> tuple[RecordModel, dict]:
    """The record model the calibration simulates (before :func:`rockdec.calibration.binned_model`)
    and where each part came from.

    ``model`` declares every part; else ``load``, ``sensor`` and ``rocking`` declare theirs
    (the rocking model is the simplified one, eq. 4, unless declared) and the rest is measured (``measurement``, a :class:`rockdec.record_measure.MeasuredModel` or
    ``None`` when the records could not be measured; then the part is the paper's). A
    measured low-pass load (colour detected, :attr:`~rockdec.record_measure.MeasuredModel.coloured`)
    is stated by its pole per sample ``alpha``, as a corner ``-ln(alpha) N / (2 pi)`` in
    rocking frequencies at the ``N`` samples per cycle the analysis reads
    (``analysis.points_per_cycle``), so that the calibration, which simulates at that
    ``N``, simulates that pole; measured sensor noise (detected,
    :attr:`~rockdec.record_measure.MeasuredModel.noisy`) in units of ``sigma_Y``. A
    declared noise in rad is expressed in the records' ``sigma_Y``. Returns
    ``(model, sources)``, ``sources`` naming ``load``, ``sensor_noise`` and ``rocking`` as
    ``"declared"``, ``"measured"`` or ``"paper (not measured)"``.
    """
    if model is not None:
        load, sensor, rocking, how = model.load, model.sensor, model.rocking, "declared"
        sources = {"load": how, "sensor_noise": how, "rocking": how}
    else:
        sources = {"rocking": "paper (the simplified model, eq. 4)" if rocking is None else "declared"}
        rocking = rocking or "simplified"
        missing = "paper (not measured)" if measurement is None else "measured"
        sources["load"] = "declared" if load is not None else missing
        sources["sensor_noise"] = "declared" if sensor is not None else missing
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
    return RecordModel(rocking, load, sensor), sources


def _quantity(q, scale: float = 1.0) -> dict:
    """A measured quantity and its standard error for JSON (``scale`` multiplies both)."""
    return {"value": _num(q.value * scale), "se": _num(q.se * scale)}


def model_report(measurement, why_not: str | None, analysis: measured.Analysis, sources: dict, simulated: RecordModel, cal_settings: dict) -> dict:
    """The ``record_model`` of :func:`estimate`'s JSON: what was measured (each quantity
    with its standard error), what was detected, what the calibration simulated (the
    binned model, :func:`rockdec.calibration.binned_model`) and where each part came from."""
    cal_ppc = cal_settings["points_per_cycle"]
    ratio = cal_settings.get("sigma_y_over_theta_cr")
    out = {
        "sources": sources,
        "simulated": {
            **simulated.key(),
            "load_pole_per_sample": _num(simulated.load.pole(cal_ppc)),
            "points_per_cycle": _num(cal_ppc),
            "sigma_y_over_theta_cr": ratio,
            "described": f"{simulated.rocking} rocking" + (f" (sigma_Y/theta_cr {ratio:.3g})" if ratio else "") + f", {simulated.load.describe()} load, "
            + (f"sensor noise {simulated.sensor.std:.3g} sigma_Y" if simulated.sensor.std > 0 else "no sensor noise"),
        },
        "measured": None,
        "not_measured": why_not,
    }
    if measurement is not None:
        m = measurement
        rate = analysis.points_per_cycle / (2.0 * math.pi)  # corner in rocking frequencies per unit of -ln(pole)
        corner = (
            {"value": _num(-math.log(m.pole.value) * rate), "se": _num(m.pole.se / m.pole.value * rate)}
            if 0.0 < m.pole.value < 1.0 else {"value": None, "se": None}
        )
        out["measured"] = {
            "kind": m.kind,
            "detected": {"sensor_noise": m.noisy, "colour": m.coloured, "drift": m.drifting},
            "sensor_noise_sigma_y": _quantity(m.noise_ratio),
            "sensor_noise_z": _num(m.noise_var.z),
            "load_pole_per_sample": _quantity(m.pole),
            "load_pole_z": _num(m.pole.z),
            "load_corner_rocking": corner,
            "load_corner_hz": _quantity(m.corner_hz),
            "drift_rms_sigma_y": _num(m.drift_rms),
            "drift_z": _num(m.drift_z),
            "g": _quantity(m.g),
            "g_asymmetry": _quantity(m.asymmetry),
            "triples": m.triples,
        }
    return out


def coverage_floor(n_sets: int) -> float:
    """Lowest calibrated coverage (:func:`rockdec.belt.calibration_coverage`) at which an
    interval is taken to hold 95 %: the lower end of the binomial band
    ``0.95 - 1.96 sqrt(0.95 x 0.05 / n)`` of ``n`` calibration sets (what a belt that covers
    exactly 95 % shows on its own sets 97.5 % of the time)."""
    return 0.95 - belt.Z95 * math.sqrt(0.95 * 0.05 / max(n_sets, 1))


def select(per: dict, n_sets: int) -> tuple[str | None, list[dict], str | None]:
    """The reported estimator among :data:`rockdec.registry.CANDIDATES`: of those with a
    value whose calibrated coverage holds (:func:`coverage_floor`), the one with the
    narrowest 95 % interval. Returns ``(name or None, selection, reason)``: ``selection``
    lists each candidate's width, coverage, whether it holds and why not; ``reason`` is
    one sentence when none can be trusted."""
    floor = coverage_floor(n_sets)
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
        elif cov is None or cov < floor:
            why = f"its calibrated coverage {'-' if cov is None else f'{cov:.1%}'} is below {floor:.1%}"
        else:
            why = None
        rows.append({"estimator": name, "width": _num(width) if width is not None else None, "coverage": cov, "holds": why is None, "why_not": why})
    trusted = [row for row in rows if row["holds"]]
    if trusted:
        return min(trusted, key=lambda row: row["width"])["estimator"], rows, None
    reason = "no estimator can be trusted on these records: " + "; ".join(f"{row['estimator']}: {row['why_not']}" for row in rows)
    return None, rows, reason


def estimate(
    records: list[Record], *, cache_dir, g: float | None = None, settings: dict | None = None, model: RecordModel | None = None,
    load: Load | None = None, sensor: SensorNoise | None = None, rocking: str | None = None, theta_cr: float | None = None,
) -> dict:
    """Calibrated estimates of ``e`` from ``records`` of one block (pooled).

    ``model``: the record model the calibration simulates, declared whole
    (:mod:`rockdec.record_model`; :data:`rockdec.record_model.PAPER` is the paper's white
    load and perfect sensor); ``None`` measures it off the records
    (:func:`rockdec.record_measure.measure`, :func:`record_model`), except the parts
    ``load``, ``sensor`` and ``rocking`` declare. A sensor noise in rad is expressed in the
    records' ``sigma_Y``. Housner's model (eq. 2) needs the block's ``theta_cr`` (rad): its
    calibration simulates the records' ``sigma_Y / theta_cr``. The calibration simulates
    that model binned (:func:`rockdec.calibration.binned_model`).

    Returns a JSON-able dict: ``e``, ``interval`` (95 %), ``reason`` (why ``e`` is null,
    else ``None``), ``estimator`` (the candidate reported, :func:`select`; ``None`` when
    none can be trusted), ``selection`` (the candidates' widths and coverages),
    ``coverage`` (the share of the calibration's simulated record sets whose interval held
    their true ``e``, :func:`rockdec.belt.calibration_coverage`), ``raw`` (of the reported
    estimator), ``g`` (rad/s^2: corrected, or as given), ``g_raw``,
    ``points_per_cycle``, ``sigma_y``, ``dt``, ``samples``, ``nan_samples``,
    ``record_model`` (:func:`model_report`),
    ``estimators`` (per estimator: ``raw``, ``e``, ``interval``, ``coverage``, ``triggers``,
    ``notes``, ``calibrated_range`` and ``beyond``: ``"below"``, ``"above"`` or
    ``"unreached"`` when the raw value lies beyond what any calibrated ``e`` produces on
    average, and ``e`` is then ``None``, :func:`beyond`),
    ``g_interval`` (``None``: the calibration corrects ``g`` but gives it no interval;
    ``g_interval_note`` says so), ``rockdec_version``,
    ``warnings``, ``calibration`` (file, and whether it came from the cache), and, under
    keys starting with ``_``, the analysis and belts for plots.

    Refuses (:class:`RecordError`) records given twice, records that do not look like
    rocking (:func:`rockdec.measured.rocking_shape`), and a ``g`` off the records' own by
    more than :data:`G_FACTOR`; a ``g`` outside the calibrated 95 % interval of the
    records' own is warned about. Detected drift is warned about: the calibration
    simulates a stationary record.
    """
    settings = {**measured.DEFAULT_SETTINGS, **(settings or {})}
    records = distinct(records)
    dt = same_step(records)
    names = ", ".join(r.source for r in records)
    notes = []
    try:
        own = _analyse(records, dt, settings, None)
    except RecordError:
        if g is None:
            raise
        own = None
        notes.append("g cannot be read off the records, so --g could not be checked against them")
    if g is not None:
        _check_given_g(g, own, names)
        analysis = _analyse(records, dt, settings, g)
    else:
        analysis = own
    shape = measured.rocking_shape(own if own is not None else analysis)
    if shape:
        raise RecordError(f"{names} does not look like a rocking record: {shape}; rockdec estimate gives e only for rocking records.")
    measuring = model is None and (load is None or sensor is None)  # a part is to be measured
    measurement, why_not = measure_model(records, dt) if model is None else (None, "declared")
    if measuring and measurement is None:
        notes.append(f"the record model could not be measured ({why_not}): the calibration simulates the paper's white load and noise-free sensor")
    if measurement is not None and measurement.drifting:
        notes.append(
            f"the record drifts (its block means wander by {measurement.drift_rms:.2g} sigma_Y, drift z = {measurement.drift_z:.1f}): "
            "the calibration simulates a stationary record; remove the drift (high-pass the record) if it is the sensor's"
        )
    model, sources = record_model(measurement, analysis, model=model, load=load, sensor=sensor, rocking=rocking)
    if (model.rocking == "housner") != (theta_cr is not None):
        raise InputError("Housner's model (eq. 2) needs the block's critical angle theta_cr, and only it; give both or neither.")
    ratio = analysis.sigma_y / theta_cr if theta_cr is not None else None
    cal_settings = calibration.calibration_settings([r.theta.size for r in records], analysis.points_per_cycle, settings, model, ratio)
    started = time.perf_counter()
    cal, cached = calibration.load_or_build(cal_settings, cache_dir, notes)
    built_s = time.perf_counter() - started
    per = {}
    belts = belt.belts(cal)
    for name in registry.ESTIMATORS:
        c = belt.correct(belts[name], analysis.raw[name])
        trigger = registry.trigger(name)
        side = beyond(belts[name], analysis.raw[name], c)
        per[name] = {
            "raw": _num(analysis.raw[name]),
            "e": None if side else _num(c.value),
            "beyond": side,
            "calibrated_range": [_num(belts[name].e[0]), _num(belts[name].e[-1])] if belts[name].e.size else None,
            "interval": [_num(c.low), _num(c.high)],
            "coverage": _num(belt.calibration_coverage(cal, name, belts[name])),
            "triggers": int(analysis.count[trigger][-1]),
            "notes": [note for note in c.notes if not (side and "nearest point" in note)],  # no value is shown
        }
    chosen, selection, reason = select(per, int(cal["raw"].sizes["e_true"] * cal["raw"].sizes["set"]))
    shown = per[chosen] if chosen else {"e": None, "interval": [None, None], "coverage": None, "raw": None}
    e_chosen = math.nan if shown["e"] is None else shown["e"]
    g_belt = belts[measured.G_NAME]
    g_value = g if g is not None else belt.correct_g(g_belt, analysis.raw[measured.G_NAME], e_chosen)
    if g is not None and own is not None and g_belt.e.size and np.isfinite(e_chosen):
        own_raw = own.raw[measured.G_NAME]
        mean, spread = np.interp(e_chosen, g_belt.e, g_belt.mean), np.interp(e_chosen, g_belt.e, g_belt.spread)
        low, high = own_raw / (mean + belt.Z95 * spread), own_raw / max(mean - belt.Z95 * spread, 1e-12)
        if not low <= g <= high:
            notes.append(
                f"--g {g:g} lies outside the records' own g, {low:.4g}-{high:.4g} rad/s^2 (calibrated 95 % interval): "
                "the estimate rests on the given g"
            )
    samples = int(sum(r.theta.size for r in records))
    if samples > LONG_SAMPLES:
        notes.append(
            f"{samples} samples make the interval narrower than the accuracy of the calibration's fitted mean curve "
            "(about 0.001 at e = 0.95): on 20-million-sample records it covered the true e 73-90 % of the time, not 95 %"
        )
    simulated = RecordModel.from_key(cal_settings["record_model"])
    return {
        "e": shown["e"],
        "interval": shown["interval"],
        "reason": reason,
        "estimator": chosen,
        "selection": selection,
        "coverage": shown["coverage"],
        "raw": shown["raw"],
        "g": _num(g_value),
        "g_given": g is not None,
        "g_raw": _num(analysis.raw[measured.G_NAME]),
        "g_interval": None,
        "g_interval_note": "as given (--g)" if g is not None else (
            "no interval: the calibration corrects g's bias at the corrected e but does not give g an interval "
            "whose coverage has been checked"
        ),
        "points_per_cycle": _num(analysis.points_per_cycle),
        "sigma_y": _num(analysis.sigma_y),
        "dt": dt,
        "records": [r.source for r in records],
        "samples": samples,
        "nan_samples": int(analysis.nan_samples),
        "record_model": model_report(measurement, why_not if measuring else None, analysis, sources, simulated, cal_settings),
        "estimators": per,
        "warnings": notes + diagnose(records, analysis, settings),
        "rockdec_version": __version__,
        "calibration": {
            "file": f"calibration-{calibration.settings_hash(cal_settings)}.nc", "cached": cached, "seconds": round(built_s, 2),
        },
        "_analysis": analysis,
        "_belts": belts,
    }


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


def _num(x) -> float | None:
    """A float for JSON, ``None`` for NaN."""
    x = float(x)
    return x if math.isfinite(x) else None

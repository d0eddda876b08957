"""From measured records to a calibrated ``e``: what ``rockdec estimate`` computes.

:func:`estimate` analyses the records (:func:`rockdec.measured.analyse`), checks that they
look like rocking (:func:`rockdec.measured.rocking_shape`) and that a given ``g`` agrees
with the records' own, fetches or builds the calibration for their lengths and sampling
(:mod:`rockdec.calibration`), corrects every estimator and gives its 95 % interval,
corrects ``g`` the same way, and lists what looks wrong with the records
(:func:`diagnose`: the checks of :mod:`rockdec.diagnostics`, their thresholds from the
calibration's own simulated records). When no ``e`` can be given, ``reason`` says why.

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

import dataclasses
import math
import time
import warnings

import numpy as np

from rockdec import __version__, belt, calibration, diagnostics, measured, registry
from rockdec.record_model import PAPER, RecordModel, SensorNoise
from rockdec.records import Record, RecordError, distinct, same_step

from rockdec.registry import DEFAULT_ESTIMATOR

#: Records (in all) longer than this are warned about: their spread falls below the
#: accuracy of the belt's fitted mean (about 0.001 at e = 0.95, measured on 20-million-sample records).
LONG_SAMPLES = 2_000_000

#: A given ``g`` off the records' own by more than this factor is refused before any
#: calibration (the calibrated 95 % spread of ``g`` is a few per cent).
G_FACTOR = 2.0

#: Peaks beyond this many ``sigma_Y`` are named as the cause when the analysis refuses the
#: records (a spike that inflates ``sigma_Y`` leaves too few triggers).
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


def diagnose(records: list[Record], analysis: measured.Analysis, settings: dict, cal, e: float | None, interval) -> tuple[list[str], dict]:
    """The checks of :mod:`rockdec.diagnostics` on the records, against thresholds from the
    calibration ``cal`` near the corrected ``e`` and its 95 % ``interval``: the warnings of
    the checks that fired, and per check ``{"statistic", "threshold", "fired"}`` (JSON-able)."""
    level = settings.get("level", measured.DEFAULT_SETTINGS["level"])
    outcomes = diagnostics.evaluate([r.theta for r in records], analysis, cal, e, interval, level)
    notes = [o.message for o in outcomes.values() if o.fired]
    return notes, {name: {"statistic": _num(o.statistic), "threshold": _num(o.threshold), "fired": o.fired} for name, o in outcomes.items()}


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


def estimate(records: list[Record], *, cache_dir, g: float | None = None, settings: dict | None = None, model: RecordModel = PAPER) -> dict:
    """Calibrated estimates of ``e`` from ``records`` of one block (pooled).

    ``model``: the record model the calibration simulates (its load and sensor noise, e.g.
    measured off the records; :mod:`rockdec.record_model`); the paper's white load and a
    perfect sensor by default. A sensor noise in rad is expressed in the records' ``sigma_Y``.

    Returns a JSON-able dict: ``e``, ``interval`` (95 %), ``reason`` (why ``e`` is null,
    else ``None``), ``estimator``, ``coverage`` (the
    share of the calibration's simulated record sets whose interval held their true ``e``,
    :func:`rockdec.belt.calibration_coverage`), ``raw`` (of the default estimator), ``g`` (rad/s^2: corrected, or as given), ``g_raw``,
    ``points_per_cycle``, ``sigma_y``, ``dt``, ``samples``, ``nan_samples``,
    ``estimators`` (per estimator: ``raw``, ``e``, ``interval``, ``coverage``, ``triggers``,
    ``notes``, ``calibrated_range`` and ``beyond``: ``"below"``, ``"above"`` or
    ``"unreached"`` when the raw value lies beyond what any calibrated ``e`` produces on
    average, and ``e`` is then ``None``, :func:`beyond`),
    ``g_interval`` (``None``: the calibration corrects ``g`` but gives it no interval;
    ``g_interval_note`` says so), ``rockdec_version``,
    ``warnings``, ``diagnostics`` (per check of :mod:`rockdec.diagnostics`: ``statistic``,
    ``threshold``, ``fired``), ``calibration`` (file, and whether it came from the cache), and, under
    keys starting with ``_``, the analysis and belts for plots.

    Refuses (:class:`RecordError`) records given twice, records that do not look like
    rocking (:func:`rockdec.measured.rocking_shape`), and a ``g`` off the records' own by
    more than :data:`G_FACTOR`; a ``g`` outside the calibrated 95 % interval of the
    records' own is warned about.
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
    if model.sensor.units == "rad":
        model = dataclasses.replace(model, sensor=SensorNoise(model.sensor.std / analysis.sigma_y, "sigma_y"))
    cal_settings = calibration.calibration_settings([r.theta.size for r in records], analysis.points_per_cycle, settings, model)
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
    default = per[DEFAULT_ESTIMATOR]
    e_default = math.nan if default["e"] is None else default["e"]
    g_belt = belts[measured.G_NAME]
    g_value = g if g is not None else belt.correct_g(g_belt, analysis.raw[measured.G_NAME], e_default)
    if g is not None and own is not None and g_belt.e.size and np.isfinite(e_default):
        own_raw = own.raw[measured.G_NAME]
        mean, spread = np.interp(e_default, g_belt.e, g_belt.mean), np.interp(e_default, g_belt.e, g_belt.spread)
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
    warned, checks = diagnose(records, analysis, settings, cal, default["e"], default["interval"])
    reason = None
    if default["beyond"] is not None:
        reason = f"the raw value lies beyond what any calibrated e gives ({default['beyond']})"
    elif default["e"] is None:
        reason = "; ".join(default["notes"]) or "the estimator gave no value on these records"
    return {
        "e": default["e"],
        "interval": default["interval"],
        "reason": reason,
        "estimator": DEFAULT_ESTIMATOR,
        "coverage": default["coverage"],
        "raw": default["raw"],
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
        "estimators": per,
        "warnings": notes + warned,
        "diagnostics": checks,
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

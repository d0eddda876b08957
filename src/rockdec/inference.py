"""From measured records to a calibrated ``e``: what ``rockdec estimate`` computes.

:func:`estimate` analyses the records (:func:`rockdec.measured.analyse`), fetches or
builds the calibration for their lengths and sampling (:mod:`rockdec.calibration`),
corrects every estimator and gives its 95 % interval, corrects ``g`` the same way, and
lists what looks wrong with the records (:func:`diagnose`).
"""

from __future__ import annotations

import math
import time
import warnings

import numpy as np

from rockdec import __version__, belt, calibration, estimators, measured
from rockdec.records import Record, RecordError, same_step

#: The estimator reported as ``e``: the calibration's coverage study shows it best
#: (smallest spread and bias of the corrected value, coverage closest to 95 %).
DEFAULT_ESTIMATOR = "e_v"

#: Fewest triggers in the largest window before the result is called unreliable.
FEW_TRIGGERS = 100


def diagnose(records: list[Record], analysis: measured.Analysis, settings: dict) -> list[str]:
    """Warnings about the records: few triggers, coarse sampling, asymmetry, drift, spikes."""
    notes = []
    for trigger, name in (("a", "D_a (extremum)"), ("v", "D_v (zero crossing)")):
        n = int(analysis.count[trigger][-1])
        if n < FEW_TRIGGERS:
            notes.append(f"only {n} {name} triggers in the largest window: the estimates rest on few segments; pool longer records")
    level = settings.get("level", measured.DEFAULT_SETTINGS["level"])
    floor = estimators.min_points_per_cycle(analysis.raw[DEFAULT_ESTIMATOR] if np.isfinite(analysis.raw[DEFAULT_ESTIMATOR]) else 0.95, level)
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
    if float(np.max(np.abs(y))) > 15.0 * analysis.sigma_y:
        notes.append(f"a peak of {np.max(np.abs(y)) / analysis.sigma_y:.0f} sigma_Y: the record holds a spike or the block overturns")
    for r in records:
        quarters = np.array_split(r.theta - np.nanmean(r.theta), 4)
        spread = np.array([np.sqrt(np.nanmean(q**2)) for q in quarters])
        if spread.max() > 2.0 * spread.min():
            notes.append(f"{r.source}: the rms of its quarters ranges {spread.min():.3g}-{spread.max():.3g} rad: the response is not stationary")
    return notes


def estimate(records: list[Record], *, cache_dir, g: float | None = None, settings: dict | None = None) -> dict:
    """Calibrated estimates of ``e`` from ``records`` of one block (pooled).

    Returns a JSON-able dict: ``e``, ``interval`` (95 %), ``estimator``, ``coverage`` (the
    share of the calibration's simulated record sets whose interval held their true ``e``,
    :func:`rockdec.belt.calibration_coverage`), ``raw`` (of the default estimator), ``g`` (rad/s^2: corrected, or as given), ``g_raw``,
    ``points_per_cycle``, ``sigma_y``, ``dt``, ``samples``, ``nan_samples``,
    ``estimators`` (per estimator: ``raw``, ``e``, ``interval``, ``coverage``, ``triggers``,
    ``notes``, ``calibrated_range`` and ``beyond``: ``"below"``, ``"above"`` or
    ``"unreached"`` when the raw value lies beyond what any calibrated ``e`` produces on
    average, and ``e`` is then ``None``, :func:`beyond`),
    ``g_interval`` (``None``: the calibration corrects ``g`` but gives it no interval;
    ``g_interval_note`` says so), ``rockdec_version``,
    ``warnings``, ``calibration`` (file, and whether it came from the cache), and, under
    keys starting with ``_``, the analysis and belts for plots.
    """
    settings = {**measured.DEFAULT_SETTINGS, **(settings or {})}
    dt = same_step(records)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # empty windows are reported through the trigger counts
        try:
            analysis = measured.analyse([r.theta for r in records], dt, settings, g=g)
        except ValueError as exc:
            raise RecordError(f"{', '.join(r.source for r in records)}: {exc}.") from None
    if int(analysis.count["v"][-1]) < 3 or int(analysis.count["a"][-1]) < 3:
        raise RecordError(
            f"{', '.join(r.source for r in records)}: only {int(analysis.count['a'][-1])} extremum and "
            f"{int(analysis.count['v'][-1])} zero-crossing triggers, too few for the fits; give a longer record."
        )
    cal_settings = calibration.calibration_settings([r.theta.size for r in records], analysis.points_per_cycle, settings)
    started = time.perf_counter()
    cal, cached = calibration.load_or_build(cal_settings, cache_dir)
    built_s = time.perf_counter() - started
    per = {}
    belts = belt.belts(cal)
    for name in estimators.ESTIMATORS:
        c = belt.correct(belts[name], analysis.raw[name])
        trigger = "v" if name == "e_v" else "a"
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
    g_value = g if g is not None else belt.correct_g(belts[measured.G_NAME], analysis.raw[measured.G_NAME], e_default)
    return {
        "e": default["e"],
        "interval": default["interval"],
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
        "samples": int(sum(r.theta.size for r in records)),
        "nan_samples": int(analysis.nan_samples),
        "estimators": per,
        "warnings": diagnose(records, analysis, settings),
        "rockdec_version": __version__,
        "calibration": {"file": f"calibration-{calibration.settings_hash(cal_settings)}.nc", "cached": cached, "seconds": round(built_s, 2)},
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

"""The JSON document of an estimate of ``e`` (:func:`document`), made once from its typed
:class:`rockdec.estimation.stages.Outcome`: the numbers as JSON numbers (NaN and inf as null).
"""

from __future__ import annotations

import math

from rockdec._version import __version__
from rockdec.calibrate import calibration
from rockdec.estimation.stages import Outcome, Repaired
from rockdec.physics.record_model import RecordModel
from rockdec.rdd import measured
from rockdec.validate import json_number

__all__ = ["candidate_row", "diagnostics_report", "document", "record_model_report", "repair_report"]


def _quantity(q, scale: float = 1.0) -> dict:
    """A measured quantity and its standard error for JSON (``scale`` multiplies both)."""
    return {"value": json_number(q.value * scale), "se": json_number(q.se * scale)}


def _model_report(measurement, why_not: str | None, analysis: measured.Analysis, sources: dict, simulated: RecordModel, cal_settings: dict,
                 own_points_per_cycle: float, rolloff=None) -> dict:
    """The ``record_model`` of the JSON document (:func:`record_model_report`): what was measured (each quantity
    with its standard error), what was detected, what the calibration simulated (the
    binned model, :func:`rockdec.calibrate.calibration.binned_model`) and where each part
    came from; ``g_side_share`` at ``own_points_per_cycle`` (:func:`rockdec.estimation.model_choice.colour_decline`);
    ``filter_rolloff``: the roll-off check (:func:`rockdec.record.record_measure.rolloff`,
    ``None`` when not made: a declared filter, or too few samples per cycle), and whether a
    steep filter shows (:func:`rockdec.estimation.model_choice.filter_decline`; a gentle one is the calibrated check
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


def record_model_report(outcome: Outcome) -> dict:
    """The ``record_model`` of the JSON document of ``outcome``: :func:`_model_report` of its
    model choice, what the calibration simulates (or would, when declined)."""
    choice, analysed = outcome.choice, outcome.analysed
    simulated = RecordModel.from_key(choice.cal_settings["record_model"])
    out = _model_report(choice.measurement, choice.why_not if choice.measuring else None, analysed.analysis, choice.sources, simulated,
                        choice.cal_settings, analysed.own_points_per_cycle, choice.rolloff)
    if choice.declined:
        out["simulated"]["described"] = f"nothing (declined; a calibration would simulate {out['simulated']['described']})"
    return out


def repair_report(repaired: Repaired, dt: float) -> dict:
    """The JSON document's ``repair`` (``repaired``, what the repair did to records sampled
    at ``dt``): whether the repair was ``enabled``, the ``spikes`` replaced
    (``spikes_removed``), the high-pass corner in rocking frequencies and in Hz (``None``
    without one), and ``why`` it was done, in words (``None`` when nothing was repaired)."""
    done = repaired.done
    spikes = 0 if done is None else done.removed
    corner = None if done is None else done.corner
    hz = None if corner is None else json_number(done.per_sample / dt)
    return {"enabled": repaired.enabled, "spikes_removed": spikes, "highpass_corner_rocking": corner, "highpass_corner_hz": hz,
            "repaired": done is not None and done.repaired, "why": repaired.why}


def diagnostics_report(checks: dict) -> dict:
    """The JSON document's ``diagnostics``: per check of ``checks`` (``{name:
    diagnostics.Outcome}``) its ``statistic``, ``threshold`` and whether it ``fired``."""
    return {name: {"statistic": json_number(o.statistic), "threshold": json_number(o.threshold), "fired": o.fired}
            for name, o in checks.items()}


def _reading(r) -> dict:
    """One estimator's entry of the document's ``estimators`` (a :class:`rockdec.estimation.corrected.Reading`)."""
    return {
        "raw": json_number(r.raw), "e": json_number(r.e), "beyond": r.beyond,
        "calibrated_range": None if r.calibrated_range is None else [json_number(x) for x in r.calibrated_range],
        "interval": [json_number(r.low), json_number(r.high)], "coverage": json_number(r.coverage), "triggers": r.triggers,
        "notes": list(r.notes),
    }


def candidate_row(c) -> dict:
    """One candidate's row of the document's ``selection`` (a :class:`rockdec.estimation.selected.Candidate`)."""
    return {"estimator": c.estimator, "width": json_number(c.width), "width_at_common_e": json_number(c.width_at_common_e),
            "coverage": json_number(c.coverage), "holds": c.holds, "why_not": c.why_not}


def _g(outcome: Outcome) -> tuple:
    """``(value, interval, coverage, note)`` of the document's ``g``."""
    reading = outcome.g_reading
    interval = None if reading.interval is None else [json_number(x) for x in reading.interval]
    return json_number(reading.value), interval, json_number(reading.coverage), reading.note


def _calibration(outcome: Outcome) -> dict:
    """The document's ``calibration``: its file, whether it was read from the cache, the seconds it took, its length and spread factor."""
    calibrated, cal_settings = outcome.calibrated, outcome.choice.cal_settings
    if calibrated is None:
        return {"file": None, "cached": False, "seconds": 0.0}
    return {
        "file": f"calibration-{calibration.settings_hash(cal_settings)}.nc", "cached": calibrated.cached,
        "seconds": round(calibrated.seconds, 2), "simulated_samples": sum(cal_settings["lengths"]), "spread_scale": calibrated.scale,
    }


def document(outcome: Outcome) -> dict:
    """The JSON document of an estimate (``outcome``, :func:`rockdec.estimation.estimate`):
    ``e``, ``interval`` (95 %), ``reason`` (why ``e`` is null), ``estimator``,
    ``selection``, ``coverage``, ``raw``, ``g`` (rad/s^2), ``g_given``, ``g_raw``,
    ``g_interval``, ``g_coverage``, ``g_interval_note``, ``points_per_cycle``, ``sigma_y``,
    ``dt``, ``records``, ``samples``, ``nan_samples``, ``record_model``
    (:func:`record_model_report`), ``estimators`` (per estimator: ``raw``, ``e``,
    ``beyond``, ``calibrated_range``, ``interval``, ``coverage``, ``triggers``, ``notes``),
    ``warnings`` and ``warning_codes``, ``diagnostics`` (:func:`diagnostics_report`),
    ``rockdec_version``, ``calibration`` and ``repair`` (:func:`repair_report`); the schema
    is ``estimate.schema.json``."""
    analysed, selection = outcome.analysed, outcome.selection
    analysis = analysed.analysis
    chosen = selection.chosen
    r = outcome.readings[chosen] if chosen else None
    value, interval, coverage, note = _g(outcome)
    doc = {
        "e": None if r is None else json_number(r.e), "interval": [None, None] if r is None else [json_number(r.low), json_number(r.high)],
        "reason": selection.reason, "estimator": chosen, "selection": [candidate_row(c) for c in selection.rows],
        "coverage": None if r is None else json_number(r.coverage), "raw": None if r is None else json_number(r.raw),
        "g": value, "g_given": analysed.g is not None, "g_raw": json_number(analysis.raw[measured.G_NAME]), "g_interval": interval,
        "g_coverage": coverage, "g_interval_note": note, "points_per_cycle": json_number(analysis.points_per_cycle),
        "sigma_y": json_number(analysis.sigma_y), "dt": analysed.dt, "records": [rec.source for rec in analysed.records],
        "samples": analysed.samples, "nan_samples": int(analysis.nan_samples), "record_model": record_model_report(outcome),
        "estimators": {name: _reading(reading) for name, reading in outcome.readings.items()},
        "warnings": [n.message for n in outcome.notes], "warning_codes": [n.code for n in outcome.notes],
        "diagnostics": diagnostics_report(outcome.checks), "rockdec_version": __version__, "calibration": _calibration(outcome),
        "repair": repair_report(outcome.repaired, analysed.dt),
    }
    if outcome.declined:  # declined after all (a defect the repair left): the same keys, e and its interval null
        doc.update({"e": None, "interval": [None, None], "coverage": None, "estimator": None, "reason": outcome.declined})
    return doc

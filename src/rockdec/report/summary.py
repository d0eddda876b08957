"""The text report of an estimate (:meth:`rockdec.RestitutionEstimate.summary`).

The reported ``e`` and its interval come first, then the candidates it was chosen from,
then the record in a few words and the warnings; ``verbose`` adds every estimator with its
notes, the record model as measured, the calibration and the checks. The words are
those of :data:`rockdec.report.glossary.GLOSSARY`.
"""

from __future__ import annotations

import math

from rockdec.rdd import registry

__all__ = ["beyond_note", "block_lines", "pct", "reads", "text", "with_block"]

def _f(x, spec: str = ".4f") -> str:
    return "-" if x is None else format(x, spec)


def pct(x) -> str:
    """A share as a percentage with one decimal, ``-`` when there is none."""
    return "-" if x is None else f"{x:.1%}"


def reads(name: str) -> str:
    """What estimator ``name`` reads, in words (the registry's ``reads``; blank for a name it lacks)."""
    return registry.spec(name).reads if name in registry.ESTIMATORS else ""


def beyond_note(est: dict) -> str:
    """Why an estimator's raw value gives no corrected value: it lies beyond its calibration."""
    lo, hi = est["calibrated_range"] or (math.nan, math.nan)
    if est["beyond"] == "below":
        return f"below the calibrated range {lo:.3f}-{hi:.3f}: e is less than {lo:.3f}, not estimated"
    if est["beyond"] == "above":
        return f"above the calibrated range {lo:.3f}-{hi:.3f}: e is more than {hi:.3f}, not estimated"
    return "the raw value is beyond what any calibrated e gives on average: not estimated"


def _interval(est: dict) -> str:
    """An estimator's interval as the report shows it: none when it gives no value."""
    if est["e"] is None or est["interval"][0] is None:
        return "-"
    return f"[{est['interval'][0]:.4f}, {est['interval'][1]:.4f}]"


def _corrected(est: dict) -> str:
    beyond = est.get("beyond")
    if beyond == "below":
        return f"< {est['calibrated_range'][0]:.3f}"
    if beyond == "above":
        return f"> {est['calibrated_range'][1]:.3f}"
    return "none" if est["e"] is None else f"{est['e']:.4f}"


def _table(doc: dict, names) -> list[str]:
    words = {name: reads(name) for name in names}
    width = max([len(r) for r in words.values()] + [5])
    lines = [f"  {'estimator':<10} {'reads':<{width}} {'raw':>7} {'corrected':>10}  {'95 % interval':<18} {'coverage':>8} {'triggers':>8}"]
    for name in [n for n in names if n in doc["estimators"]]:
        est = doc["estimators"][name]
        mark = " *" if name == doc["estimator"] else ""
        lines.append(
            f"  {name + mark:<10} {words[name]:<{width}} {_f(est['raw']):>7} {_corrected(est):>10}  {_interval(est):<18} "
            f"{pct(est['coverage']):>8} {est['triggers']:>8}"
        )
    return lines


def _headline(doc: dict) -> list[str]:
    if doc["e"] is None:
        return [f"e: not estimated: {doc.get('reason') or 'no estimator gave a value'}"]
    low, high = doc["interval"]
    return [
        f"e = {doc['e']:.4f} (95 % interval [{low:.4f}, {high:.4f}]; estimator {doc['estimator']}, "
        f"{registry.spec(doc['estimator']).reads})",
        f"  the interval held the true e on {pct(doc['coverage'])} of the calibration's simulated records",
    ]


def _g(doc: dict) -> str:
    raw = doc.get("g_raw")
    if doc["g"] is None:
        read = "" if raw is None else f" (raw value read off the record {raw:.4g}, not corrected)"
        return f"block's restoring acceleration g = nu^2 theta_cr: not determined{read}"
    if doc["g_given"]:
        how = "given"
    else:
        how = "read off the record" + ("" if raw is None else f" (raw {raw:.4g}) and corrected")
    if doc.get("g_interval"):
        held = "" if doc.get("g_coverage") is None else f", held the true g on {doc['g_coverage']:.0%} of the calibration's records"
        how += f"; 95 % interval [{doc['g_interval'][0]:.5g}, {doc['g_interval'][1]:.5g}]{held}"
    return f"block's restoring acceleration g = nu^2 theta_cr = {doc['g']:.5g} rad/s^2 ({how}; not gravity)"


def _model(doc: dict) -> str:
    report = doc.get("record_model")
    if not report:
        return "record model: not determined"
    src = report["sources"]
    return (f"record model the calibration simulates: {report['simulated']['described']} "
            f"(load {src['load']}, sensor noise {src['sensor_noise']}, rocking model {src['rocking']}"
            + (f", sensor filter {src['sensor_filter']}" if "sensor_filter" in src else "") + ")")


def _measured(report: dict | None) -> list[str]:
    """The record model as measured, in words (verbose)."""
    if not report:
        return []
    from rockdec.record.record_measure import ROLLOFF_FLOOR  # not at the top: it imports numba, which the report needs not

    m = report.get("measured")
    roll = report.get("filter_rolloff")
    lines = [] if roll is None else [
        f"  sensor filter check: the second differences fall as f^{roll['slope']['value']:.2f} (+- {roll['slope']['se']:.2g}) between "
        f"{roll['band_rocking'][0]:g} and {roll['band_rocking'][1]:g} rocking frequencies, {roll['z']:+.1f} errors from f^{ROLLOFF_FLOOR:g}"
        f" ({'a steep filter shows' if roll['detected'] else 'no steep filter shows'})"
    ]
    if m is None:
        return lines + ([f"  record model not measured: {report['not_measured']}"] if report.get("not_measured") else [])

    def pm(q, scale=1.0, spec=".3g"):
        if q["value"] is None:
            return "not measurable"
        return format(q["value"] * scale, spec) + ("" if q["se"] is None else f" +- {q['se'] * scale:.2g}")

    det = m["detected"]
    noise = f"{pm(m['sensor_noise_sigma_y'], 100.0)} % of sigma_Y ({'detected' if det['sensor_noise'] else 'not detected'})"
    if det["colour"]:
        load = f"low-pass, corner at {pm(m['load_corner_rocking'])} rocking frequencies"
    else:
        load = "white (no colour detected)"
    drift = f"{m['drift_rms_sigma_y']:.2g} sigma_Y in the block means ({'detected' if det['drift'] else 'not detected'})"
    share = "" if m["g_side_share"] is None else f", {m['g_side_share']:.2f} of the signature's"
    return lines + [
        "  measured off the record:",
        f"    sensor noise {noise}",
        f"    load {load}",
        f"    drift {drift}",
        f"    g from the second differences {pm(m['g'], spec='.4g')} rad/s^2{share}; the two sides differ by {pm(m['g_asymmetry'], spec='+.3f')}",
    ]


def _record(doc: dict) -> list[str]:
    nan = f", {doc['nan_samples']} NaN skipped" if doc["nan_samples"] else ""
    ppc = "-" if doc["points_per_cycle"] is None else f"{doc['points_per_cycle']:.1f}"
    return [
        f"record: {', '.join(doc['records'])}",
        f"  {doc['samples']} samples at a step of {doc['dt']:.6g} s{nan}; rms angle sigma_Y = {_f(doc['sigma_y'], '.4g')} rad, "
        f"{ppc} samples per rocking cycle at sigma_Y",
        f"  {_g(doc)}",
        f"  {_model(doc)}",
        *_repair(doc.get("repair")),
    ]


def _repair(rep: dict | None) -> list[str]:
    """What the repair did, in a line (none when nothing was repaired)."""
    if not rep:
        return []
    if not rep.get("enabled"):
        return ["  repair: off (the record as given)"]
    if not rep.get("repaired"):
        return []
    parts = []
    if rep["spikes_removed"]:
        parts.append(f"{rep['spikes_removed']} spike{'s' if rep['spikes_removed'] > 1 else ''} replaced by the line through their neighbours")
    if rep["highpass_corner_rocking"] is not None:
        hz = "" if rep["highpass_corner_hz"] is None else f", {rep['highpass_corner_hz']:.3g} Hz"
        parts.append(f"drift removed by a zero-phase high-pass at {rep['highpass_corner_rocking']:g} rocking frequencies{hz}")
    return [f"  repaired: {'; '.join(parts)}; the calibration's records were repaired alike (--no-repair: as given)"]


def _calibration(doc: dict) -> str:
    cal = doc["calibration"]
    if cal["file"] is None:
        return "calibration: none (the records were declined before calibrating)"
    how = "from the cache" if cal["cached"] else f"built in {cal['seconds']:.1f} s and stored for the next record like these"
    return f"calibration: {cal['file']}, {how}"


def text(doc: dict, verbose: bool = False) -> str:
    """The report of the JSON document ``doc`` of an estimate (:meth:`rockdec.RestitutionEstimate.summary`)."""
    lines = _headline(doc)
    lines += ["", "candidates (* reported):", *_table(doc, registry.CANDIDATES)]
    if verbose:
        lines += [f"  not chosen: {row['estimator']}: {row['why_not']}" for row in doc["selection"] if not row["holds"]]
    lines += ["", *_record(doc), *block_lines(doc)]
    if doc["warnings"]:
        lines += ["", *[f"warning: {w}" for w in doc["warnings"]]]
    if verbose:
        others = [name for name in doc["estimators"] if name not in registry.CANDIDATES]
        lines += ["", "other estimators:", *_table(doc, others), "", "notes on the estimators:"]
        for name, est in doc["estimators"].items():
            notes = est["notes"] + ([beyond_note(est)] if est.get("beyond") else [])
            lines += [f"  {name}: {note}" for note in notes]
        lines += ["", *_measured(doc.get("record_model")), _calibration(doc)]
        if doc.get("diagnostics"):
            lines.append("checks (statistic / threshold):")
            for name, c in doc["diagnostics"].items():
                lines.append(f"  {name}: {_f(c['statistic'], '.3g')} / {_f(c['threshold'], '.3g')}{'  FIRED' if c['fired'] else ''}")
    return "\n".join(lines)


def with_block(doc: dict, block) -> dict:
    """``doc`` with the block's geometry beside its ``e`` (unchanged without a ``block``,
    a :class:`rockdec.physics.geometry.Block`): ``block`` holds its ``height`` and ``width``,
    ``theta_cr`` (``atan(B/H)``, rad), Housner's ``housner_e`` and ``e_over_housner``.

    Examples
    --------
    >>> from rockdec.physics.geometry import Block
    >>> with_block({"e": 0.9}, Block(0.6, 0.2))["block"]["e_over_housner"]
    1.0588235294117647
    """
    if block is None:
        return doc
    e = doc.get("e")
    return {**doc, "block": {"height": float(block.height), "width": float(block.width), "theta_cr": block.theta_cr,
                             "housner_e": block.housner_e, "e_over_housner": None if e is None else e / block.housner_e}}


def block_lines(doc: dict) -> list[str]:
    """The report's line on the block's geometry (none without one): Housner's ``e`` and the
    measured one's ratio to it."""
    block = doc.get("block")
    if not block:
        return []
    ratio = "" if block["e_over_housner"] is None else f"; measured e / Housner's = {block['e_over_housner']:.3f}"
    return [f"  block {block['height']:g} x {block['width']:g} (height x width): theta_cr = atan(B/H) = {block['theta_cr']:.4g} rad, "
            f"Housner's e = 1 - 1.5 sin^2(theta_cr) = {block['housner_e']:.4f}{ratio}"]


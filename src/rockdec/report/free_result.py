"""The free-rocking test as an estimate's document, report and dataset
(:func:`rockdec.free_rocking`, a :class:`rockdec.RestitutionEstimate` with ``test == "free"``).

The document holds the pooled ``e`` and its interval, the impacts' spread of ``e`` with its
interval and how many impacts returned more speed than they received, the loss in flight
(``c``, fitted or only tested), ``g`` (and ``nu``), one row per impact
and one per release (where its analysis stopped and why), the trend of ``e`` with
amplitude and the notes of the analysis (:mod:`rockdec.free.analysis`).
"""

from __future__ import annotations

import math

import numpy as np

from rockdec._version import __version__
from rockdec.report.summary import block_lines
from rockdec.validate import json_number

__all__ = ["free_dataset", "free_document", "free_text"]

#: The warning code of every note of the free-rocking analysis.
NOTE_CODE = "free_rocking"


def _pair(pair) -> list | None:
    low, high = (json_number(v) for v in pair)
    return None if low is None or high is None else [low, high]


def free_document(fit, sources: list[str], steps: list[float], sizes: list[int]) -> dict:
    """The JSON document of the free-rocking analysis ``fit``
    (:class:`rockdec.free.analysis.FreeRockingFit`) of the records ``sources`` sampled at
    ``steps`` (s) with ``sizes`` samples."""
    has_e = fit.reason is None and math.isfinite(fit.e)
    impacts = [
        {"record": int(fit.impact_record[i]), "release": int(fit.impact_release[i]), "time": json_number(fit.impact_time[i]),
         "amplitude_before": json_number(fit.amplitude_before[i]), "omega_before": json_number(fit.omega_before[i]),
         "omega_before_se": json_number(fit.omega_before_se[i]), "omega_after": json_number(fit.omega_after[i]),
         "omega_after_se": json_number(fit.omega_after_se[i]), "e": json_number(fit.e_impact[i]), "e_se": json_number(fit.e_impact_se[i])}
        for i in range(fit.n_impacts)
    ]
    releases = [
        {"record": int(fit.release_record[j]), "time": json_number(fit.release_time[j]), "angle": json_number(fit.release_angle[j]),
         "g": json_number(fit.release_g[j]), "stop_time": json_number(fit.stop_time[j]), "stop_reason": fit.stop_reason[j],
         "residual_std": json_number(fit.residual_std[j])}
        for j in range(len(fit.release_time))
    ]
    return {
        "e": json_number(fit.e) if has_e else None,
        "interval": _pair(fit.e_interval) if has_e else [None, None],
        "reason": fit.reason,
        "estimator": "impacts" if has_e else None,
        "coverage": None,
        "g": json_number(fit.g),
        "g_interval": _pair(fit.g_interval),
        "nu": json_number(fit.nu),
        "nu_interval": _pair(fit.nu_interval),
        "model": fit.model,
        "theta_cr": fit.theta_cr,
        "log_e_se": json_number(fit.log_e_se),
        "scatter_ratio": json_number(fit.scatter_ratio),
        "e_spread": json_number(fit.e_spread),
        "e_spread_interval": _pair(fit.e_spread_interval),
        "impacts_above_one": int(fit.impacts_above_one),
        "flight_loss": json_number(fit.flight_loss),
        "flight_loss_interval": _pair(fit.flight_loss_interval),
        "loss_in_flight": bool(fit.loss_in_flight),
        "e_trend": json_number(fit.e_trend),
        "e_trend_se": json_number(fit.e_trend_se),
        "e_reference": json_number(fit.e_reference),
        "e_reference_interval": _pair(fit.e_reference_interval),
        "reference_speed": json_number(fit.reference_speed),
        "dt": float(steps[0]),
        "records": list(sources),
        "samples": int(sum(sizes)),
        "noise_std": [json_number(v) for v in fit.noise_std],
        "impacts": impacts,
        "releases": releases,
        "warnings": list(fit.notes),
        "warning_codes": [NOTE_CODE] * len(fit.notes),
        "rockdec_version": __version__,
    }


def free_text(doc: dict, verbose: bool = False) -> str:
    """The report of a free-rocking document (:meth:`rockdec.RestitutionEstimate.summary`)."""
    impacts, releases = doc["impacts"], doc["releases"]
    if doc["e"] is None:
        lines = [f"e: not estimated: {doc['reason']}"]
    else:
        low, high = doc["interval"]
        lines = [
            f"e = {doc['e']:.4f} (95 % interval [{low:.4f}, {high:.4f}]; free-rocking test: {len(impacts)} impacts of "
            f"{len(releases)} release(s), pooled over the steps of their log impact speeds)",
            "  the interval's coverage is measured by the free-rocking study on simulated records of known e",
        ]
        if doc.get("e_spread") is not None and doc.get("e_spread_interval"):
            s_low, s_high = doc["e_spread_interval"]
            lines.append(f"  spread of e from impact to impact: {doc['e_spread']:.4f} (95 % interval [{s_low:.4f}, {s_high:.4f}]); "
                         f"{doc.get('impacts_above_one', 0)} of {len(impacts)} impacts returned more speed than they received")
    g = "-" if doc["g"] is None else f"{doc['g']:.5g}"
    inner = f", 95 % interval [{doc['g_interval'][0]:.5g}, {doc['g_interval'][1]:.5g}]" if doc.get("g_interval") else ""
    lines += [
        "",
        f"record: {', '.join(doc['records'])}",
        f"  {doc['samples']} samples at a step of {doc['dt']:.6g} s; flights fitted with the {doc['model']} model",
        f"  block's restoring acceleration g = nu^2 theta_cr = {g} rad/s^2 (read off the arcs{inner}; not gravity)",
    ]
    if doc.get("flight_loss") is not None and doc.get("flight_loss_interval"):
        c_low, c_high = doc["flight_loss_interval"]
        lines.append(f"  loss in flight c = {doc['flight_loss']:.3g} per s (95 % interval [{c_low:.3g}, {c_high:.3g}]; "
                     + ("fitted: e is the impacts' share)" if doc.get("loss_in_flight") else "not found: e from flights without loss)"))
    if doc.get("e_trend") is not None and doc.get("e_trend_se") is not None:
        lines.append(f"  trend of log e with the log impact speed: {doc['e_trend']:+.3g} +- {doc['e_trend_se']:.2g} (the models predict "
                     f"none); e = {doc['e_reference']:.4f} at {doc['reference_speed']:.3g} rad/s, the impacts' geometric mean speed")
    lines += block_lines(doc)
    lines += [f"  release {j + 1} stops at {r['stop_time']:.6g} s: {r['stop_reason']}" for j, r in enumerate(releases)]
    if doc["warnings"]:
        lines += ["", *[f"warning: {w}" for w in doc["warnings"]]]
    if verbose and impacts:
        lines += ["", f"  {'release':>7} {'time (s)':>10} {'apex (rad)':>11} {'speed before':>13} {'after':>11} {'e':>7} {'se':>7}"]
        for row in impacts:
            lines.append(
                f"  {row['release'] + 1:>7} {row['time']:>10.5g} {row['amplitude_before']:>11.4g} {row['omega_before']:>13.4g} "
                f"{row['omega_after']:>11.4g} {row['e']:>7.4f} {row['e_se']:>7.4f}"
            )
    return "\n".join(lines)


def free_dataset(res):
    """The CF-1.10 dataset of a free-rocking estimate: ``e`` with ``e_low``/``e_high``,
    the impact-to-impact spread ``e_spread`` with its bounds, ``g`` with its bounds, and per ``impact`` its time, apex, speeds and ``e``
    (of a shake-table test's tails: also ``shaking_end`` per record)."""
    import xarray as xr

    from rockdec.report.result_dataset import global_attrs

    doc = res.to_dict()
    rows = doc["impacts"]

    def column(key):
        return np.array([math.nan if r[key] is None else r[key] for r in rows], dtype=np.float64)

    low, high = doc["interval"] if doc["e"] is not None else (None, None)
    g_low, g_high = doc["g_interval"] or (None, None)
    spread_low, spread_high = doc.get("e_spread_interval") or (None, None)
    nan = lambda x: math.nan if x is None else float(x)  # noqa: E731
    what = "coefficient of restitution"
    ds = xr.Dataset(
        {
            "e": ((), nan(doc["e"]), {"units": "1", "long_name": f"{what}, pooled over the impacts", "ancillary_variables": "e_low e_high"}),
            "e_low": ((), nan(low), {"units": "1", "long_name": f"{what}, lower end of the 95 % confidence interval"}),
            "e_high": ((), nan(high), {"units": "1", "long_name": f"{what}, upper end of the 95 % confidence interval"}),
            "g": ((), nan(doc["g"]), {"units": "rad s-2", "long_name": "restoring acceleration nu^2 theta_cr of the block",
                                      "ancillary_variables": "g_low g_high"}),
            "g_low": ((), nan(g_low), {"units": "rad s-2", "long_name": "restoring acceleration, lower end of the 95 % confidence interval"}),
            "g_high": ((), nan(g_high), {"units": "rad s-2", "long_name": "restoring acceleration, upper end of the 95 % confidence interval"}),
            "e_spread": ((), nan(doc.get("e_spread")), {"units": "1", "long_name": f"standard deviation of the {what} from impact to impact",
                                                         "ancillary_variables": "e_spread_low e_spread_high"}),
            "e_spread_low": ((), nan(spread_low), {"units": "1", "long_name": "impact-to-impact spread, lower end of the 95 % confidence interval"}),
            "e_spread_high": ((), nan(spread_high), {"units": "1", "long_name": "impact-to-impact spread, upper end of the 95 % confidence interval"}),
            "flight_loss": ((), nan(doc.get("flight_loss")), {"units": "s-1", "long_name": "loss in flight c of theta'' = -g sign(theta) - c theta'",
                                                              "comment": "fitted" if doc.get("loss_in_flight") else "tested, not found"}),
            "impact_time": ("impact", column("time"), {"units": "s", "long_name": "time of the impact on its record's axis"}),
            "amplitude_before": ("impact", column("amplitude_before"), {"units": "rad", "long_name": "apex of the flight before the impact"}),
            "omega_before": ("impact", column("omega_before"), {"units": "rad s-1", "long_name": "angular velocity just before the impact"}),
            "omega_after": ("impact", column("omega_after"), {"units": "rad s-1", "long_name": "angular velocity just after the impact"}),
            "e_impact": ("impact", column("e"), {"units": "1", "long_name": f"{what} of the impact (eq. 6)",
                                                 "ancillary_variables": "e_impact_se"}),
            "e_impact_se": ("impact", column("e_se"), {"units": "1", "long_name": f"standard error of the {what} of the impact"}),
        },
    )
    if doc["test"] == "shake":
        ends = [nan(t) for t in doc["shake_table"]["shaking_end"]]
        ds["shaking_end"] = ("record", np.array(ends, dtype=np.float64),
                             {"units": "s", "long_name": "time the base's shaking ends, on the record's axis (NaN: it never does)"})
        ds.attrs = global_attrs(doc, "from the free-decay tails of a shake-table test", "shake-table analysis")
    else:
        ds.attrs = global_attrs(doc, "from a free-rocking test", "free-rocking analysis")
    return ds

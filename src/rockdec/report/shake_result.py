"""The shake-table test as an estimate's document and report (:func:`rockdec.shake_table`,
a :class:`rockdec.RestitutionEstimate` with ``test == "shake"``).

The document is the free-rocking document of the pooled free-decay tails
(:mod:`rockdec.report.free_result`; impacts and releases numbered by the record they lie in,
times on that record's axis) and a ``shake_table`` entry: the base's units, the thresholds of
quiet and of a tail's length, where the shaking ends in each record, the tails analysed (with
their own ``e``) and the stretches refused, each with its reason (:mod:`rockdec.free.shake`).
"""

from __future__ import annotations

from rockdec._version import __version__
from rockdec.free.shake import MIN_TAIL, QUIET
from rockdec.report.free_result import free_document, free_text
from rockdec.validate import json_number

__all__ = ["shake_document", "shake_text"]

#: The free-rocking document's entries of a shake-table test with no tail to analyse.
_EMPTY = {
    "g_interval": None, "nu_interval": None, "e_spread_interval": None, "flight_loss_interval": None, "loss_in_flight": False,
    "e_reference_interval": None, "impacts_above_one": 0, "noise_std": [], "impacts": [], "releases": [],
}


def shake_document(shake, sources: list[str], steps: list[float], sizes: list[int], *, base_units: str, model: str,
                   theta_cr: float | None) -> dict:
    """The JSON document of the shake-table analysis ``shake``
    (:class:`rockdec.free.shake.ShakeTableFit`) of the records ``sources`` sampled at
    ``steps`` (s) with ``sizes`` samples, their base in ``base_units``, the tails fitted with
    ``model``."""
    if shake.fit is not None:
        doc = free_document(shake.fit, sources, steps, sizes)
        owner = [record for record, _, _ in shake.tails]
        for row in doc["impacts"] + doc["releases"]:
            row["record"] = owner[row["record"]]
    else:
        doc = _empty_document(sources, steps, sizes, model, theta_cr)
    doc["reason"] = shake.reason
    doc["shake_table"] = {
        "base_units": base_units,
        "quiet": QUIET,
        "min_tail": MIN_TAIL,
        "shaking_end": [json_number(t) for t in shake.shaking_end],
        "tails": [{"record": int(k), "start": json_number(t0), "stop": json_number(t1), "e": json_number(fit.e),
                   "impacts": int(fit.n_impacts), "base_motion": json_number(load)}
                  for (k, t0, t1), fit, load in zip(shake.tails, shake.tail_fits, shake.tail_loads)],
        "refused": [{"record": int(k), "start": json_number(t0), "reason": why} for k, t0, why in shake.refused],
    }
    return doc


def _empty_document(sources: list[str], steps: list[float], sizes: list[int], model: str, theta_cr: float | None) -> dict:
    """A free-rocking document with no impact: every number ``None``, every table empty."""
    numbers = ("e", "reason", "estimator", "coverage", "g", "nu", "log_e_se", "scatter_ratio", "e_spread", "flight_loss", "e_trend",
               "e_trend_se", "e_reference", "reference_speed")
    return {**dict.fromkeys(numbers), **_EMPTY, "interval": [None, None], "model": model, "theta_cr": theta_cr, "dt": float(steps[0]),
            "records": list(sources), "samples": int(sum(sizes)), "warnings": [], "warning_codes": [], "rockdec_version": __version__}


def shake_text(doc: dict, verbose: bool = False) -> str:
    """The report of a shake-table document (:meth:`rockdec.RestitutionEstimate.summary`):
    the free-rocking report of its tails, then where the shaking ends and each tail."""
    table = doc["shake_table"]
    text = free_text(doc, verbose).replace("free-rocking test:", "shake-table test, free-decay tails:", 1)
    text = text.replace("measured by the free-rocking study on simulated records of known e",
                        "measured on shake-table records of known e from an independent simulator (the docs' shake-table page)", 1)
    lines = [text, "", "shake table:"]
    for k, end in enumerate(table["shaking_end"]):
        name = doc["records"][k] if k < len(doc["records"]) else f"record {k}"
        lines.append(f"  {name}: the shaking ends at {end:.6g} s" if end is not None else f"  {name}: the shaking never ends")
    lines += [f"  tail of record {t['record']} from {t['start']:.6g} s to {t['stop']:.6g} s: {t['impacts']} impacts, e = {t['e']:.4f}"
              for t in table["tails"] if t["e"] is not None]
    lines += [f"  refused in record {r['record']} from {r['start']:.6g} s: {r['reason']}" for r in table["refused"]]
    lines.append(f"  (base in {table['base_units']}; quiet below {table['quiet']:g} of the uplift level for at least {table['min_tail']:g} s)")
    return "\n".join(lines)


"""The shake-table test as an estimate's document and report (:func:`rockdec.shake_table`,
a :class:`rockdec.RestitutionEstimate` with ``test == "shake"``).

The document is the free-rocking document of the pooled free-decay tails
(:mod:`rockdec.report.free_result`; impacts and releases numbered by the record they lie in,
times on that record's axis; with tails in several records, its ``e``, interval and
``log_e_se`` those of the records pooled by their errors) and a ``shake_table`` entry: the base's units, the thresholds of
quiet and of a tail's length, where the shaking ends in each record, the tails analysed (with
their own ``e``) and the stretches refused, each with its reason (:mod:`rockdec.free.shake`),
and ``forced``: the records read with the base as a known load in their arcs
(:mod:`rockdec.free.forced`), per record and pooled, with the base read linear between
samples and held over each (``readings``, their ``reading_gap``). The document's ``e`` is the reading with
the narrower interval (:attr:`rockdec.free.shake.ShakeTableFit.answer`; ``estimator``
"impacts" for the tails, "forced" for every impact).
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
    forced = shake.forced_pooled
    source, e, interval = shake.answer
    if source == "forced":
        doc.update(e=json_number(e), interval=[json_number(x) for x in interval], reason=None, estimator="forced")
        if doc["g"] is None:
            doc["g"] = json_number(forced.g)
    elif source == "impacts" and shake.record_fits:
        doc.update(e=json_number(e), interval=[json_number(x) for x in interval], log_e_se=json_number(shake.log_e_se))
    elif forced is not None and doc["reason"]:
        doc["reason"] = doc["reason"].rstrip(".") + f"; and every impact with the base a known load gives none: {forced.reason}"
    doc["shake_table"]["tails_e"] = json_number(shake.e)
    doc["shake_table"]["tails_interval"] = [json_number(x) for x in shake.e_interval]
    if forced is not None:
        doc["shake_table"]["forced"] = {**_forced(shake.forced_pooled), "g": json_number(shake.forced_pooled.g),
                                        "records": [{"record": k, **_forced(f), "g": json_number(f.g), "load_gain": json_number(f.load_gain),
                                                     "base_shift": json_number(f.shift)} for k, f in enumerate(shake.forced)]}
    return doc


def _forced(fit) -> dict:
    """The entries of one reading of :mod:`rockdec.free.forced` (a record's or the pool's):
    its answer, and each way of reading the base between samples with the gap between them."""
    return {"e": json_number(fit.e), "interval": [json_number(x) for x in fit.e_interval], "impacts": fit.impacts,
            "set_aside": int(fit.set_aside), "reason": fit.reason, "reading_gap": json_number(fit.reading_gap),
            "readings": {name: {"e": json_number(r.e), "interval": [json_number(x) for x in r.e_interval], "base_shift": json_number(r.shift)}
                         for name, r in fit.readings.items()}}


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
    if doc["estimator"] == "forced":
        head, _, rest = text.partition("\n")
        lo, hi = doc["interval"]
        tails = "no free-decay tail gives an e" if not table["tails"] else "narrower than the free-decay tails' interval"
        text = "\n".join([f"e = {doc['e']:.4f} (95 % interval [{lo:.4f}, {hi:.4f}]; shake-table test: every impact, the base as a "
                           f"known load in the arcs, {table['forced']['impacts']} impacts; {tails})", rest])
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
    forced = table.get("forced")
    if forced is not None:
        lines += ["", "every impact, the base as a known load in the arcs:"]
        rows = [("all records", forced), *((doc["records"][r["record"]] if r["record"] < len(doc["records"]) else f"record {r['record']}", r)
                                          for r in forced["records"])] if len(forced["records"]) > 1 else [("the record", forced)]
        for name, r in rows:
            if r["e"] is None:
                lines.append(f"  {name}: no e: {r['reason']}")
            else:
                lo, hi = r["interval"]
                both = ", ".join(f"{way}: {x['e']:.4f}" for way, x in r["readings"].items() if x["e"] is not None)
                lines.append(f"  {name}: e = {r['e']:.4f}, 95 % interval [{lo:.4f}, {hi:.4f}], from {r['impacts']} impacts"
                             + (f" (the base between samples {both})" if both else ""))
        gains = [r["load_gain"] for r in forced["records"] if r["load_gain"] is not None]
        if gains:
            lines.append(f"  (the base's fitted load over what its units and the block's angle say: {min(gains):.3f}-{max(gains):.3f})")
        lines.append("  (each interval the union of two readings of the base between samples: linear, and held over each sample)")
    return "\n".join(lines)


"""How often the shake-table test answers, and how often its interval holds ``e``.

Shake-table tests of known ``e`` (:func:`rockdec.physics.base_motion.shake_test`: 20 s of
earthquake-like base motion at ``peak`` uplift levels, then 20 s of free decay, 200 Hz, the
simplified block at ``g`` = 1 rad/s^2, sensor noise a share of the largest angle), by cell
of ``e`` x ``peak`` x sensor noise, each analysed by
:func:`rockdec.free.shake.analyse_shake_table` (what ``rockdec.shake_table`` and ``rockdec
estimate --test shake`` run): per cell, for the test's ``e`` (the tails', else every
impact's with the base a known load) and for each of those two readings alone, the share
answered, the share of answered intervals that hold ``e`` and the median width, and the
most frequent reasons for no ``e`` (:func:`run_grid`, :func:`markdown`). The records of a generator written apart from the
project meet the same analysis in ``benchmarks/shake_coverage.py``.

Explanation: docs/how-to/shake-table.md ("How far it holds").
"""

from __future__ import annotations

import collections
import math
import statistics

from rockdec.free.shake import analyse_shake_table
from rockdec.physics.base_motion import shake_test

__all__ = ["COLUMNS", "E_VALUES", "NOISE", "PEAKS", "READINGS", "RECORDS", "cell", "markdown", "run_grid", "tally"]

#: The cells: true ``e``, the base's strength in uplift levels, sensor noise (share of the
#: largest angle), and records per cell.
E_VALUES, PEAKS, NOISE, RECORDS = (0.8, 0.9, 0.95), (1.2, 1.6, 2.2, 3.0), (0.0, 0.01), 40

#: Samples a record (half shaking, half free decay) and their step (s).
N_POINTS, DT = 8_000, 0.005

#: Seeds of the study's records start here (apart from the demonstration campaign's).
STUDY_SEED_OFFSET = 7_000_000


#: The cell's columns of :func:`markdown`: its key and heading.
COLUMNS = (("e", "e"), ("peak", "peak (uplift levels)"), ("noise", "sensor noise"))


#: The readings :func:`tally` counts: the test's ``e``, the tails' and every impact's.
READINGS = ("test", "tails", "forced")


def _reading(fit, name: str) -> tuple[float, tuple[float, float], str | None]:
    """``e``, its interval and the reason for none of one of :data:`READINGS` of ``fit``."""
    if name == "test":
        source, e, interval = fit.answer
        return e, interval, None if source else fit.reason
    if name == "tails":
        return fit.e, fit.e_interval, fit.reason
    forced = fit.forced_pooled
    return forced.e, forced.e_interval, forced.reason


def tally(fits, e: float) -> dict:
    """How the shake-table fits ``fits`` (:class:`rockdec.free.shake.ShakeTableFit`) of records
    of true ``e`` went, for each of :data:`READINGS`: ``answered``, ``covered`` (intervals that
    hold ``e``), the ``widths`` of the answered intervals; and ``why`` the test gave no ``e``
    (the first words of each reason, counted). The test's counts are also at the top level."""
    out = {name: {"answered": 0, "covered": 0, "widths": []} for name in READINGS}
    why = collections.Counter()
    for fit in fits:
        for name in READINGS:
            value, (low, high), reason = _reading(fit, name)
            if not math.isfinite(value):
                if name == "test":
                    why[" ".join(reason.split(": ")[-1].split()[:6])] += 1
                continue
            out[name]["answered"] += 1
            out[name]["covered"] += bool(low <= e <= high)
            out[name]["widths"].append(high - low)
    return {**out["test"], "readings": out, "why": why}


def cell(e: float, peak: float, noise: float, records: int = RECORDS) -> dict:
    """One cell: ``records`` shake-table tests analysed, their answers tallied (:func:`tally`).

    Examples
    --------
    >>> c = cell(0.95, 3.0, 0.0, records=1)
    >>> c["answered"] <= c["records"] == 1, c["covered"] <= c["answered"]
    (True, True)
    """
    tests = (shake_test(e, N_POINTS, DT, STUDY_SEED_OFFSET + k, peak=peak, noise=noise) for k in range(records))
    fits = (analyse_shake_table(theta, base, DT, base_units="rad/s2", g_block=1.0) for theta, base in tests)
    return {"e": e, "peak": peak, "noise": noise, "records": records, **tally(fits, e)}


def run_grid(e_values=E_VALUES, peaks=PEAKS, noise=NOISE, records: int = RECORDS) -> list[dict]:
    """Every cell of ``e_values`` x ``peaks`` x ``noise`` (:func:`cell`)."""
    return [cell(e, peak, level, records) for e in e_values for peak in peaks for level in noise]


def markdown(cells: list[dict], columns=COLUMNS) -> str:
    """The cells (``columns``: their keys and headings, :data:`COLUMNS`) as a Markdown table
    (for each of :data:`READINGS`: answered, covered, median width; why the test gave no
    ``e``), then the answered and covered counts pooled over them."""
    heads = " | ".join(f"{name}: answered | covered | median width" for name in READINGS)
    lines = ["| " + " | ".join(h for _, h in columns) + f" | {heads} | no e: why (count) |",
             "| --- " * (len(columns) + 3 * len(READINGS) + 1) + "|"]
    for c in cells:
        parts = []
        for name in READINGS:
            r = c["readings"][name]
            width = f"{statistics.median(r['widths']):.3g}" if r["widths"] else "-"
            parts.append(f"{r['answered']}/{c['records']} | {r['covered']}/{r['answered']} | {width}")
        why = "; ".join(f"{w} ({n})" for w, n in c["why"].most_common(2)) or "-"
        lines.append("| " + " | ".join(f"{c[k]:g}" for k, _ in columns) + " | " + " | ".join(parts) + f" | {why} |")
    total = sum(c["records"] for c in cells)
    lines.append("")
    for name in READINGS:
        answered = sum(c["readings"][name]["answered"] for c in cells)
        covered = sum(c["readings"][name]["covered"] for c in cells)
        lines.append(f"Pooled, {name}: {answered} of {total} answered, {covered} of those {answered} covered.")
    return "\n".join(lines)

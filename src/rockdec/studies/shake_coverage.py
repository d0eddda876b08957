"""How often the shake-table test answers, and how often its interval holds ``e``.

Shake-table tests of known ``e`` (:func:`rockdec.physics.base_motion.shake_test`: 20 s of
earthquake-like base motion at ``peak`` uplift levels, then 20 s of free decay, 200 Hz, the
simplified block at ``g`` = 1 rad/s^2, sensor noise a share of the largest angle), by cell
of ``e`` x ``peak`` x sensor noise, each analysed by
:func:`rockdec.free.shake.analyse_shake_table` (what ``rockdec.shake_table`` and ``rockdec
estimate --test shake`` run): per cell the share answered, the share of answered intervals
that hold ``e``, the median width, and the most frequent reasons for no ``e``
(:func:`run_grid`, :func:`markdown`). The records of a generator written apart from the
project meet the same analysis in ``benchmarks/shake_coverage.py``.

Explanation: docs/how-to/shake-table.md ("How far it holds").
"""

from __future__ import annotations

import collections
import statistics

from rockdec.free.shake import analyse_shake_table
from rockdec.physics.base_motion import shake_test

__all__ = ["COLUMNS", "E_VALUES", "NOISE", "PEAKS", "RECORDS", "cell", "markdown", "run_grid", "tally"]

#: The cells: true ``e``, the base's strength in uplift levels, sensor noise (share of the
#: largest angle), and records per cell.
E_VALUES, PEAKS, NOISE, RECORDS = (0.8, 0.9, 0.95), (1.2, 1.6, 2.2, 3.0), (0.0, 0.01), 40

#: Samples a record (half shaking, half free decay) and their step (s).
N_POINTS, DT = 8_000, 0.005

#: Seeds of the study's records start here (apart from the demonstration campaign's).
STUDY_SEED_OFFSET = 7_000_000


#: The cell's columns of :func:`markdown`: its key and heading.
COLUMNS = (("e", "e"), ("peak", "peak (uplift levels)"), ("noise", "sensor noise"))


def tally(fits, e: float) -> dict:
    """How the shake-table fits ``fits`` (:class:`rockdec.free.shake.ShakeTableFit`) of records
    of true ``e`` went: ``answered``, ``covered`` (intervals that hold ``e``), the ``widths``
    of the answered intervals, and ``why`` the others gave no ``e`` (the first words of each
    reason, counted)."""
    out = {"answered": 0, "covered": 0, "widths": [], "why": collections.Counter()}
    for fit in fits:
        if fit.reason is not None:
            out["why"][" ".join(fit.reason.split(": ")[-1].split()[:6])] += 1
            continue
        low, high = fit.e_interval
        out["answered"] += 1
        out["covered"] += bool(low <= e <= high)
        out["widths"].append(high - low)
    return out


def cell(e: float, peak: float, noise: float, records: int = RECORDS) -> dict:
    """One cell: ``records`` shake-table tests analysed, their answers tallied (:func:`tally`).

    Examples
    --------
    >>> c = cell(0.95, 3.0, 0.0, records=2)
    >>> c["answered"] <= c["records"] == 2, c["covered"] <= c["answered"]
    (True, True)
    """
    tests = (shake_test(e, N_POINTS, DT, STUDY_SEED_OFFSET + k, peak=peak, noise=noise) for k in range(records))
    fits = (analyse_shake_table(theta, base, DT, base_units="rad/s2", g_block=1.0) for theta, base in tests)
    return {"e": e, "peak": peak, "noise": noise, "records": records, **tally(fits, e)}


def run_grid(e_values=E_VALUES, peaks=PEAKS, noise=NOISE, records: int = RECORDS) -> list[dict]:
    """Every cell of ``e_values`` x ``peaks`` x ``noise`` (:func:`cell`)."""
    return [cell(e, peak, level, records) for e in e_values for peak in peaks for level in noise]


def markdown(cells: list[dict], columns=COLUMNS) -> str:
    """The cells (``columns``: their keys and headings, :data:`COLUMNS`) as a Markdown table,
    then the answered and covered counts pooled over them."""
    lines = ["| " + " | ".join(h for _, h in columns) + " | answered | covered | median width | no e: why (count) |",
             "| --- " * (len(columns) + 4) + "|"]
    for c in cells:
        width = f"{statistics.median(c['widths']):.3g}" if c["widths"] else "-"
        why = "; ".join(f"{w} ({n})" for w, n in c["why"].most_common(2)) or "-"
        lines.append("| " + " | ".join(f"{c[k]:g}" for k, _ in columns) + f" | {c['answered']}/{c['records']} | "
                     f"{c['covered']}/{c['answered']} | {width} | {why} |")
    answered, covered = sum(c["answered"] for c in cells), sum(c["covered"] for c in cells)
    total = sum(c["records"] for c in cells)
    lines += ["", f"Pooled: {answered} of {total} answered, {covered} of those {answered} covered."]
    return "\n".join(lines)

"""Does the repair (drift high-passed, spikes replaced by their neighbours' line) give intervals that hold, and no false asymmetry?

A plain script (not a test): measures, never asserts.

    nice -n 10 python benchmarks/repair_study.py --records 50 --out results/repair_study.jsonl
    python benchmarks/repair_study.py --records 0 --out results/repair_study.jsonl --table results/repair_study.md

Cells, each at ``e`` = 0.6, 0.9 and 0.98 (``--e``), records of ``--n-points`` samples
(:func:`rockdec.simulate`, 75 samples per cycle at its amplitude, the record model measured as a
new user's is), estimated by :func:`rockdec.estimation.estimate` with the repair on:

* ``clean``: no defect. How often a repair triggers (spikes found, or the high-pass), and for
  those the same record estimated without the repair (is the answer unchanged?).
* ``drift-linear``: a straight drift of ``A`` sigma_Y over the record, ``A`` uniform in 1-5.
* ``drift-walk``: a random walk of :data:`WALK_KNOTS` steps joined by straight lines, scaled
  to a range of ``A`` sigma_Y, ``A`` uniform in 1-5.
* ``spikes``: ``k`` isolated samples moved by ``a`` sigma_Y each (random sign), ``k``
  log-uniform from 10 to 1 % of the samples, ``a`` uniform in 1-50.
* ``load-doubles``: the load's impulses twice as strong from the middle of the record on.
* ``ref-drift``, ``ref-spikes``: drift (linear) and spikes on records of the independent
  simulator ``tests/rocking_vectorised.py`` (its own random numbers and code), at the step
  the calibration's search gives for 75 samples per cycle.

Per cell: records, share answered (``e`` given), coverage of the answered and of all records
(a null counted as not covered), the share on which the asymmetry check fires, the share on
which any check fires on the estimated record, the share repaired by the high-pass, the
median spikes found over those injected, and the reasons ``e`` was declined. Rows go to
``--out`` (JSON lines, appended as each record finishes: a partial run covers every cell
in turn); the table (Markdown) to ``--table``.
"""

from __future__ import annotations

import argparse
import json
import math
import time
import warnings
from pathlib import Path

import numpy as np

import tests_path  # noqa: F401  (tests/ on sys.path for the second simulator)
import rockdec
from rockdec.calibrate import calibration
from rockdec import estimation
from rockdec.report.estimate_report import document
from rockdec.rdd import measured
from rockdec.record.records import Record

#: Seeds of the records start here (apart from the calibration's seeds and the other
#: studies'); cell ``c``, record ``k``: ``SEED_OFFSET + 10**5 c + k``.
SEED_OFFSET = 9_300_000

#: Knots of the random-walk drift, joined by straight lines: a wander over tens of cycles
#: (a sensor's zero moves smoothly; a walk of one step a sample would be white noise in the
#: second differences, which the record model reads as sensor noise).
WALK_KNOTS = 50

CELLS = ("clean", "drift-linear", "drift-walk", "spikes", "load-doubles", "ref-drift", "ref-spikes")


def _reference(e: float, n: int, seed: int) -> tuple[np.ndarray, float]:
    """A record of the second simulator at the step the calibration's search gives for 75
    samples per cycle (``g = sigma_p = 1``)."""
    import rocking_vectorised

    dt, burn_in, _ = calibration.step_for(e, 75.0, [n], measured.DEFAULT_SETTINGS, seed + 10**9)
    y = rocking_vectorised.simulate_records([seed], n, dt=dt, g=1.0, e=e, sigma_p=1.0, burn_in=burn_in)[0]
    return np.asarray(y, dtype=float), dt


def _project(e: float, n: int, seed: int, doubled: bool = False) -> tuple[np.ndarray, float]:
    """A record of :func:`rockdec.simulate` (75 samples per cycle); ``doubled``: the second
    half continues the first with the impulses' strength doubled."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        first = rockdec.simulate(e, n if not doubled else n // 2, seed=seed)
        y = np.asarray(first.values, dtype=float).ravel()
        dt = float(first.time[1] - first.time[0])
        if doubled:
            sigma_p = float(first.attrs["sigma_p"]) if "sigma_p" in first.attrs else None
            second = rockdec.simulate(e, n - n // 2, seed=seed + 1, dt=dt, sigma_p=2.0 * sigma_p, burn_in=0,
                                      theta0=float(y[-1]), theta_dot0=float((y[-1] - y[-2]) / dt),
                                      nu=float(first.attrs["nu"]), theta_cr=float(first.attrs["theta_cr"]))
            y = np.concatenate([y, np.asarray(second.values, dtype=float).ravel()])
    return y, dt


def record(cell: str, e: float, k: int, n: int, seed: int) -> tuple[np.ndarray, float, dict]:
    """One record of ``cell`` and what was done to it."""
    rng = np.random.default_rng(seed)
    y, dt = _reference(e, n, seed) if cell.startswith("ref-") else _project(e, n, seed, cell == "load-doubles")
    sy = float(np.std(y))
    defect: dict = {}
    if cell.endswith("drift-linear") or cell == "ref-drift":
        a = rng.uniform(1.0, 5.0) * rng.choice([-1.0, 1.0])
        y = y + a * sy * np.arange(n) / n
        defect = {"drift_sigma_y": abs(a)}
    elif cell == "drift-walk":
        a = rng.uniform(1.0, 5.0)
        knots = np.cumsum(rng.normal(size=WALK_KNOTS))
        walk = np.interp(np.arange(n), np.linspace(0, n - 1, WALK_KNOTS), knots)
        y = y + a * sy * walk / np.ptp(walk)
        defect = {"drift_sigma_y": a}
    elif cell.endswith("spikes"):
        count = int(round(math.exp(rng.uniform(math.log(10), math.log(0.01 * n)))))
        where = rng.choice(n, count, replace=False)
        y = y.copy()
        y[where] += rng.choice([-1.0, 1.0], count) * rng.uniform(1.0, 50.0, count) * sy
        defect = {"spikes": count}
    return y, dt, defect


def run(cells, es, records: int, n: int, cache: str, out: Path, first: int = 0) -> None:
    """Estimate ``records`` records of every cell and ``e`` in turn, one at a time, appending rows to ``out``."""
    out.parent.mkdir(parents=True, exist_ok=True)
    for k in range(first, first + records):
        for c, cell in enumerate(cells):
            for j, e in enumerate(es):
                seed = SEED_OFFSET + 10**5 * (CELLS.index(cell) * 10 + j) + k
                y, dt, defect = record(cell, e, k, n, seed)
                started = time.perf_counter()
                try:
                    doc = document(estimation.estimate([Record(y, dt, f"{cell} {seed}")], cache_dir=cache))
                except rockdec.RecordError as exc:
                    doc = {"e": None, "interval": [None, None], "reason": f"refused: {exc}", "diagnostics": {}, "repair": {}}
                row = {
                    "cell": cell, "e_true": e, "seed": seed, **defect, "e": doc["e"], "low": doc["interval"][0],
                    "high": doc["interval"][1], "reason": doc["reason"], "estimator": doc.get("estimator"),
                    "fired": [name for name, v in doc["diagnostics"].items() if v["fired"]], "repair": doc["repair"],
                    "seconds": round(time.perf_counter() - started, 2),
                }
                if cell == "clean" and doc["repair"].get("repaired"):  # the same record without the repair
                    plain = document(estimation.estimate([Record(y, dt, "plain")], cache_dir=cache, repair_records=False))
                    row["unrepaired"] = {"e": plain["e"], "low": plain["interval"][0], "high": plain["interval"][1]}
                with out.open("a") as f:
                    f.write(json.dumps(row) + "\n")
                print(json.dumps(row)[:300], flush=True)


def table(rows: list[dict]) -> str:
    """The Markdown table of the rows (module docstring)."""
    lines = ["| cell | e | n | answered | coverage of answered | coverage of all | asymmetry fired | any check fired | "
             "high-passed | spikes found / injected (median) | declined: why |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    keys = sorted({(r["cell"], r["e_true"]) for r in rows}, key=lambda t: (CELLS.index(t[0]), t[1]))
    for cell, e in keys:
        got = [r for r in rows if r["cell"] == cell and r["e_true"] == e]
        n = len(got)
        answered = [r for r in got if r["e"] is not None]
        covered = sum(r["low"] <= e <= r["high"] for r in answered)
        asym = sum("asymmetry" in r["fired"] for r in got)
        anyf = sum(bool(r["fired"]) for r in got)
        hp = sum((r["repair"] or {}).get("highpass_corner_rocking") is not None for r in got)
        found = [(r["repair"] or {}).get("spikes_removed", 0) / r["spikes"] for r in got if r.get("spikes")]
        why = {}
        for r in got:
            if r["e"] is None:
                key = (r["reason"] or "").split("(")[0].split(":")[0][:70]
                why[key] = why.get(key, 0) + 1
        lines.append(
            f"| {cell} | {e:g} | {n} | {len(answered)} | {100 * covered / max(len(answered), 1):.0f} % | {100 * covered / n:.0f} % "
            f"| {100 * asym / n:.0f} % | {100 * anyf / n:.0f} % | {hp} | {np.median(found) if found else '-'} | "
            + ("; ".join(f"{v}: {k}" for k, v in why.items()) or "-") + " |"
        )
    clean = [r for r in rows if r["cell"] == "clean" and "unrepaired" in r]
    lines.append("")
    lines.append(f"clean records repaired: {len(clean)} of {sum(r['cell'] == 'clean' for r in rows)}; "
                 + ", ".join(f"e {r['e']} vs {r['unrepaired']['e']} unrepaired" for r in clean if r["e"] is not None or r["unrepaired"]["e"] is not None))
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--records", type=int, default=50, help="records per cell and e")
    parser.add_argument("--first", type=int, default=0, help="index of the first record (to add records to a run)")
    parser.add_argument("--n-points", type=int, default=200_000)
    parser.add_argument("--e", type=float, nargs="+", default=[0.6, 0.9, 0.98])
    parser.add_argument("--cells", nargs="+", default=list(CELLS), choices=CELLS)
    parser.add_argument("--cache", default="results/repair_study_cache")
    parser.add_argument("--out", type=Path, default=Path("results/repair_study.jsonl"))
    parser.add_argument("--table", type=Path, default=None)
    args = parser.parse_args()
    run(args.cells, args.e, args.records, args.n_points, args.cache, args.out, args.first)
    rows = [json.loads(line) for line in args.out.read_text().splitlines()] if args.out.exists() else []
    text = table(rows)
    print(text)
    if args.table:
        args.table.write_text(text)


if __name__ == "__main__":
    main()

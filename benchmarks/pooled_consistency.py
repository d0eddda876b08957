"""How often does the pooled-records check fire on records of one block, and on records of two?

A plain script (not a test): prints measurements, never asserts them.

    nice python benchmarks/pooled_consistency.py --pairs 40
    nice python benchmarks/pooled_consistency.py --pairs 40 --first-pair 40  # 40 more pairs a cell
    python benchmarks/pooled_consistency.py --cells 0.8/0.9 0.85/0.87 --pairs 20 --n-points 200000

Each cell ``A/B`` simulates pairs of records (:func:`rockdec.simulate`, ``--n-points`` samples
each): the first at ``e = A`` with its own step (75 samples per cycle at its amplitude), the
second at ``e = B`` at the SAME step, as a laboratory records two tests. The pair is
estimated together as a new user would (:func:`rockdec.estimate` with a list, record model
measured), all cells sharing one calibration folder (``--cache``) so each calibration is
built once. The cells run in turn, one pair each, so a partial run covers every cell.

Per cell it prints how many pairs were estimated, the share on which ``pooled_disagree``
fires (and so ``e`` is declined: Cochran's ``Q`` of :mod:`rockdec.calibrate.consistency`,
which the estimate reports, above the point of chi-square at
:data:`rockdec.calibrate.consistency.LEVEL`; rows of runs at another level are read at
this one), the shares above the 95 %, 98 %, 99 % and 99.9 % points, the share whose pooled interval
holds ``A`` (one block: ``A = B``) among those that were answered, and the median of the
pooled ``e`` of pairs the check let through (both at the level of the run that estimated the pair), over every pair in ``--out`` (JSON lines, to
which each pair's row is appended as it finishes: ``--pairs 0`` prints the table alone).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

import rockdec
from rockdec.calibrate import consistency

#: Seeds of the pairs start here, apart from the calibration's seeds (2**61 on) and the
#: studies' (their own offsets); cell ``c``, pair ``k``: ``SEED_OFFSET + 10**6 c + 2 k`` and the next.
SEED_OFFSET = 7_000_000


def one_pair(a: float, b: float, seed: int, n_points: int, cache: Path) -> dict:
    first = rockdec.simulate(a, n_points, seed=seed)
    dt = float(first.attrs["dt"])
    second = rockdec.simulate(b, n_points, seed=seed + 1, dt=dt)
    started = time.perf_counter()
    try:
        doc = rockdec.estimate([first.values, second.values], dt=dt, cache=cache).to_dict()
    except (rockdec.InputError, rockdec.RecordError) as exc:
        return {"a": a, "b": b, "seed": seed, "refused": str(exc)}
    check = doc["diagnostics"].get("pooled_consistency", {})
    return {
        "a": a, "b": b, "seed": seed, "seconds": round(time.perf_counter() - started, 2), "e": doc["e"],
        "interval": doc["interval"], "reason": doc["reason"], "statistic": check.get("statistic"),
        "threshold": check.get("threshold"), "fired": check.get("fired"), "codes": doc["warning_codes"],
    }


def summary(rows: list[dict]) -> str:
    done = [r for r in rows if "refused" not in r]
    tested = [r for r in done if r["statistic"] is not None]
    share = lambda n, d: f"{100 * n / d:.0f} % ({n}/{d})" if d else "-"  # noqa: E731
    levels = []
    for level in (consistency.LEVEL, 0.95, 0.98, 0.99, 0.999):
        over = sum(r["statistic"] > consistency.threshold(1, level) for r in tested)  # a pair: 1 degree of freedom
        levels.append(share(over, len(tested)))
    answered = [r for r in done if r["e"] is not None]
    a, b = rows[0]["a"], rows[0]["b"]
    covered = share(sum(r["interval"][0] <= a <= r["interval"][1] for r in answered), len(answered)) if a == b else "-"
    median = f"{np.median([r['e'] for r in answered]):.4f}" if answered else "-"
    return (f"| {a:g} / {b:g} | {len(done)} ({len(rows) - len(done)}) | {' | '.join(levels)} | "
            f"{covered} | {median} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", nargs="+", default=["0.6/0.6", "0.8/0.8", "0.9/0.9", "0.95/0.95", "0.8/0.9", "0.85/0.6", "0.85/0.88"])
    parser.add_argument("--pairs", type=int, default=40)
    parser.add_argument("--first-pair", type=int, default=0, help="the pair index to start at (another run's pairs go on)")
    parser.add_argument("--n-points", type=int, default=200_000)
    parser.add_argument("--cache", type=Path, default=Path("results/pooled_consistency/calibration"))
    parser.add_argument("--out", type=Path, default=Path("results/pooled_consistency/pairs.jsonl"))
    args = parser.parse_args()
    cells = [tuple(float(x) for x in cell.split("/")) for cell in args.cells]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    with args.out.open("a") as out:
        for k in range(args.first_pair, args.first_pair + args.pairs):
            for c, (a, b) in enumerate(cells):
                row = one_pair(a, b, SEED_OFFSET + 10**6 * c + 2 * k, args.n_points, args.cache)
                out.write(json.dumps(row) + "\n")
                out.flush()
    rows: dict[tuple, list] = {cell: [] for cell in cells}
    for line in args.out.read_text().splitlines():  # every pair in the file: this run's and earlier runs'
        row = json.loads(line)
        rows.setdefault((row["a"], row["b"]), []).append(row)
    print(f"pairs of records of {args.n_points} samples at one step, estimated together (record model measured); "
          f"the check's level {consistency.LEVEL}")
    print(f"| e of the records | pairs estimated (refused) | pooled_disagree fires (Q above {100 * consistency.LEVEL:g} %) "
          "| Q above 95 % | above 98 % | above 99 % | above 99.9 % | one block: interval holds e | median pooled e answered |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for cell in cells:
        print(summary(rows[cell]))
    seconds = [r["seconds"] for rs in rows.values() for r in rs if "seconds" in r]
    print(f"median seconds per estimate (calibrations built included in the first ones): {np.median(seconds):.1f}"
          if seconds else "no estimate")


if __name__ == "__main__":
    main()

"""Coverage of calibrations shared across record lengths (``length_grid``) against
exact-length calibrations, on the same records of known ``e``.

A plain script (not a test): prints measurements, never asserts them.

    python benchmarks/length_grid_coverage.py                      # 25 records a cell, 200 in all
    python benchmarks/length_grid_coverage.py --records 5 --lengths 12000 60000

The records come from the tests' vectorised simulator written apart from the project
(``tests/rocking_vectorised.py``: its own flight, impacts and random impulses), clean, at
75 samples per rocking cycle. Each is estimated twice, with the same cache folder:
calibrated at its own length, and on the length grid
(:func:`rockdec.calibrate.calibration.length_bin`: a calibration simulated at the grid length
at or below the record's, its spread scaled by ``sqrt(grid / record)``). Per cell (``e`` x
length) and pooled: answered, covered, the mean width, the mean ``|e_grid - e_exact|`` over
records both answer, and the calibrations each way built.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import rocking_vectorised  # noqa: E402

from rockdec.calibrate import calibration

from rockdec import estimation
from rockdec.report.estimate_report import document  # noqa: E402
from rockdec.physics.simulate import default_burn_in  # noqa: E402
from rockdec.rdd import measured  # noqa: E402
from rockdec.record.records import Record  # noqa: E402

PPC = 75.0


def records(e: float, n_points: int, count: int, seed: int) -> tuple[np.ndarray, float]:
    """``count`` clean records of the independent simulator and their step (``g = sigma_p = 1``)."""
    dt = calibration.step_for(e, PPC, [n_points], measured.DEFAULT_SETTINGS, 777)[0]
    theta = rocking_vectorised.simulate_records(np.arange(seed, seed + count), n_points, dt=dt, g=1.0, e=e, sigma_p=1.0,
                                                burn_in=default_burn_in(e, PPC))
    return theta, dt


def outcome(doc: dict, e: float) -> tuple[bool, bool, float]:
    """Answered, covered, width."""
    if doc["e"] is None:
        return False, False, float("nan")
    low, high = doc["interval"]
    return True, low <= e <= high, high - low


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--e", type=float, nargs="+", default=[0.8, 0.9])
    parser.add_argument("--lengths", type=int, nargs="+", default=[12_000, 25_000, 60_000, 150_000])
    parser.add_argument("--records", type=int, default=25)
    parser.add_argument("--seed", type=int, default=50_000)
    parser.add_argument("--cache", help="calibration folder (default: a new temporary one, so every calibration is built)")
    args = parser.parse_args()
    cache = Path(args.cache or tempfile.mkdtemp(prefix="length-grid-"))
    rows, built = [], {False: set(), True: set()}
    seconds = {False: 0.0, True: 0.0}
    start = time.perf_counter()
    for e in args.e:
        for n in args.lengths:
            theta, dt = records(e, n, args.records, args.seed)
            cell = {"e": e, "n": n, False: [], True: [], "diff": []}
            for k, y in enumerate(theta):
                docs = {}
                for grid in (False, True):
                    tick = time.perf_counter()
                    out = document(estimation.estimate([Record(y, dt, f"record {k}")], cache_dir=cache, length_grid=grid))
                    seconds[grid] += time.perf_counter() - tick
                    docs[grid] = out
                    if out["calibration"]["file"]:
                        built[grid].add(out["calibration"]["file"])
                    cell[grid].append(outcome(out, e))
                if docs[False]["e"] is not None and docs[True]["e"] is not None:
                    cell["diff"].append(abs(docs[True]["e"] - docs[False]["e"]))
            rows.append(cell)
            print(f"  e {e:g}, {n} samples: done", file=sys.stderr)
    print("| e | samples | grid length | exact: answered, covered, width | grid: answered, covered, width | mean abs(grid - exact) |")
    print("| --- | --- | --- | --- | --- | --- |")

    def text(results):
        answered = [r for r in results if r[0]]
        width = np.mean([r[2] for r in answered]) if answered else float("nan")
        return f"{len(answered)}/{len(results)}, {sum(r[1] for r in answered)}, {width:.4f}"

    for c in rows:
        print(f"| {c['e']:g} | {c['n']} | {calibration.length_bin(c['n'])} | {text(c[False])} | {text(c[True])} | "
              f"{np.mean(c['diff']) if c['diff'] else float('nan'):.4f} |")
    pooled = {grid: [r for c in rows for r in c[grid]] for grid in (False, True)}
    for grid in (False, True):
        answered = [r for r in pooled[grid] if r[0]]
        print(f"\n{'grid' if grid else 'exact'}: {len(answered)}/{len(pooled[grid])} answered, {sum(r[1] for r in answered)} covered "
              f"({100 * sum(r[1] for r in answered) / max(len(answered), 1):.1f} %); {len(built[grid])} calibrations; "
              f"{seconds[grid]:.0f} s of estimates (calibrations included)")
    print(f"{time.perf_counter() - start:.0f} s in all; cache {cache}")


if __name__ == "__main__":
    main()

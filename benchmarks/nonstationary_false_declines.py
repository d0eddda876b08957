"""How often the ``nonstationary`` check fires, so declines ``e``, on stationary records with sensor noise, by cell.

A plain script (not a test): it prints a table and never asserts.

    python benchmarks/nonstationary_false_declines.py [--records 100] [--cache DIR]

The records are the warnings' study's clean records (:mod:`rockdec.studies.diagnostics_study`:
100,000 samples at 75 samples per cycle, a white load, the study's seeds, so the first 40
of a cell are the study's own), at each ``e`` of the study and sensor noise 0, 1, 2 and 3 %
of their rms, each through ``rockdec estimate`` with the record model measured off it. Per
cell it prints how many records the check fired on, that share with its 95 % Wilson
interval, and the median of the statistic over its threshold. A fired ``nonstationary``
declines ``e`` on the user's path (:data:`rockdec.estimation.DECLINING_CHECKS`), so the share
is the cell's false-decline rate.
"""

from __future__ import annotations

import argparse
import math
import tempfile
import time

import numpy as np

from rockdec.pipeline.layout import DIAGNOSTICS_E
from rockdec.studies import diagnostics_study

NOISE = (0.0, 0.01, 0.02, 0.03)


def wilson(k: int, n: int, z: float = 1.959964) -> tuple[float, float]:
    """The 95 % Wilson interval of a share ``k / n``."""
    if n == 0:
        return math.nan, math.nan
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return max(0.0, centre - half), min(1.0, centre + half)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=100, help="records a cell")
    parser.add_argument("--cache", help="calibration folder (default: a new temporary one)")
    args = parser.parse_args()
    start = time.perf_counter()
    table = diagnostics_study.run(e_values=DIAGNOSTICS_E, defects={}, n_records=args.records,
                                  cache_dir=args.cache or tempfile.mkdtemp(prefix="nonstationary-"), noise_levels=NOISE,
                                  corners=(0.0,), coloured_noise=())
    print(f"{len(table)} records, {table.attrs['calibrations']} calibrations, {time.perf_counter() - start:.0f} s\n")
    print("| e | sensor noise | records | fired | share (95 % interval) | median statistic / threshold |")
    print("| --- | --- | --- | --- | --- | --- |")
    worst = 0.0
    for (e, noise), cell in table.groupby(["e_true", "noise"]):
        read = cell.dropna(subset=["nonstationary_fired"])
        fired = int(read["nonstationary_fired"].astype(bool).sum())
        n = len(read)
        low, high = wilson(fired, n)
        ratio = np.median(read["nonstationary_statistic"] / read["nonstationary_threshold"])
        worst = max(worst, fired / n if n else 0.0)
        print(f"| {e:g} | {noise:.0%} | {n} | {fired} | {fired / n:.1%} ({low:.1%}-{high:.1%}) | {ratio:.2f} |")
    total = table.dropna(subset=["nonstationary_fired"])
    print(f"\nall cells: {int(total['nonstationary_fired'].astype(bool).sum())} of {len(total)} fired; worst cell {worst:.1%}")


if __name__ == "__main__":
    main()

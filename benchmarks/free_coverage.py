"""Coverage of the free-rocking interval and bias of the per-impact ``e``, on simulated releases.

A plain script (not a test): prints measurements, never asserts them.

    python benchmarks/free_coverage.py                 # the grid of issue 37, 50 records a cell
    python benchmarks/free_coverage.py --records 10 --e 0.9 --noise 0.01

Cells: true ``e`` x sensor noise (in units of the release angle) x model (simplified, eq. 4;
linearised Housner, eq. 2), each record at its own samples per cycle, log-uniform in
``--samples-per-cycle`` (:func:`rockdec.studies.free_coverage.record_density`); defaults from
:data:`rockdec.studies.free_coverage.GRID_E` and its neighbours. Prints the Markdown table of
:func:`rockdec.studies.free_coverage.markdown`: per cell the answered records, the coverage
of the 95 % interval, the median width, the mean and standard deviation of
``(e_i - e)/se_i`` over the impacts, and the declines or refusals; then the pooled coverage.
"""

from __future__ import annotations

import argparse
import time

from rockdec.studies import free_coverage as study


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--e", type=float, nargs="+", default=list(study.GRID_E))
    parser.add_argument("--noise", type=float, nargs="+", default=list(study.GRID_NOISE))
    parser.add_argument("--models", nargs="+", default=list(study.GRID_MODELS))
    parser.add_argument("--samples-per-cycle", type=float, nargs="+", default=list(study.GRID_DENSITY))
    parser.add_argument("--records", type=int, default=study.GRID_RECORDS)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    density = args.samples_per_cycle[0] if len(args.samples_per_cycle) == 1 else tuple(args.samples_per_cycle[:2])
    start = time.perf_counter()
    cells = study.run_grid(args.e, args.noise, args.models, args.records, density, args.seed)
    print(study.markdown(cells))
    print(f"\n{sum(c.records for c in cells)} records in {time.perf_counter() - start:.0f} s.")


if __name__ == "__main__":
    main()

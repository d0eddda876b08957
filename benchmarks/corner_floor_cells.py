"""What would `rockdec estimate` answer on a coverage cell if the colour decline's corner floor were lower?

A plain script (not a test): prints measurements, never asserts them.

    python benchmarks/corner_floor_cells.py kernel_corner1_e0.9 --floor 0 --records 200 --cache DIR --out DIR

Runs the coverage study's cell (:func:`rockdec.studies.coverage.run_cell`, the kernel's
records or the reference simulator's, as the cell says) with
:data:`rockdec.estimation.COLOUR_CORNER_FLOOR` set to ``--floor`` (0: no record is
declined for its corner; the side means' rule and every other rule stay), on ``--threads``
Dask threads, writes the cell to ``<out>/<cell>_floor<F>.nc`` and prints what
:func:`rockdec.studies.coverage.summary` reads off it, with the median interval width beside
3.92 times the sd of the reported ``e`` (what an interval as wide as the records' scatter
would be) and the coverage and width per reported estimator. Calibrations are built into
``--cache`` as the records ask for them: one cell of 200 records at corner 1 builds 20-40
coloured calibrations (about 40 s of one core each).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from rockdec import io
from rockdec import estimation
from rockdec import engine
from rockdec.pipeline.layout import COVERAGE_CASES
from rockdec.studies import coverage


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("cell", choices=sorted(COVERAGE_CASES))
    parser.add_argument("--floor", type=float, default=0.0, help="corner floor in rocking frequencies (the tool's: 2)")
    parser.add_argument("--records", type=int, default=200)
    parser.add_argument("--n-points", type=int, default=200_000)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--cache", type=Path, required=True, help="calibration folder (shared between runs)")
    parser.add_argument("--out", type=Path, required=True, help="folder for the cell's NetCDF")
    args = parser.parse_args()

    estimation.COLOUR_CORNER_FLOOR = args.floor
    reference = Path(__file__).resolve().parents[1] / "tests" / "rocking_vectorised.py"
    with engine.session(args.threads):
        ds = coverage.run_cell(args.cell, args.records, args.n_points, args.cache,
                               simulate=coverage.simulator_of(args.cell, reference))
    args.out.mkdir(parents=True, exist_ok=True)
    io.write_netcdf(ds, args.out / f"{args.cell}_floor{args.floor:g}.nc")

    row = coverage.summary(ds)
    e = row["e_true"]
    values = ds["e_hat"].values
    answered = np.isfinite(values)
    print(f"{args.cell}, corner floor {args.floor:g}: {row['answered']} of {row['records']} answered, "
          f"coverage of answered {100 * row['answered_coverage']:.1f} %, bias {row['bias']:+.4f} ({row['bias_over_sd']:+.2f} sd), "
          f"median width {row['median_width']:.3f} against 3.92 sd {3.92 * row['sd']:.3f}; paper model: coverage "
          f"{100 * row['paper_coverage']:.1f} %, width {row['paper_median_width']:.3f}")
    print(f"  nulls: {row['null_reasons'] or 'none'}")
    print(f"  warnings: {row['warnings'] or 'none'}")
    for name in sorted(set(ds["reported_by"].values[answered])):
        mine = ds["reported_by"].values == name
        low, high = ds["low"].values[mine], ds["high"].values[mine]
        print(f"  {name}: {mine.sum()} records, coverage {100 * np.mean((low <= e) & (e <= high)):.1f} %, "
              f"median width {np.median(high - low):.3f}")


if __name__ == "__main__":
    main()

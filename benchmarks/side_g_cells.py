"""Which answered records of the coverage study's cells does the side means' share of g decline?

A plain script (not a test): prints measurements, never asserts them.

    python benchmarks/side_g_cells.py results/studies/coverage/cells
    python benchmarks/side_g_cells.py results/studies/coverage/cells --cells kernel_corner0.5_e0.6 reference_corner1_e0.6

For each cell file (``<folder>/<cell>.nc``, written by :func:`rockdec.studies.coverage.run_cell`)
the records that were given a number are made again from their seeds (record ``i`` has seed
``first_seed + i``; the cell's simulator, :func:`rockdec.studies.coverage.simulator_of`, with the
reference of this checkout's tests/, and the cell's step, pole, burn-in and noise) and
measured (:func:`rockdec.record.record_measure.measure`); their share
(:meth:`rockdec.record.record_measure.MeasuredModel.side_g_share`) is read at the samples per
cycle the cell's run read. The share only adds declines
(:func:`rockdec.estimation.colour_decline`), so the records without a number stay
without one. Prints per cell the records, those without a number, those with one and how many
of their intervals cover the true ``e``, the same with the share, and the share's smallest and
median value on the records with a number.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
import xarray as xr

from rockdec import estimation
from rockdec.record import record_measure
from rockdec.studies import coverage
from rockdec.validate import InputError


def cell_row(path: Path) -> str:
    ds = xr.open_dataset(path)
    a = ds.attrs
    answered = np.flatnonzero(np.isfinite(ds["e_hat"].values))
    covered = (ds["low"].values <= a["e_true"]) & (a["e_true"] <= ds["high"].values)
    shares = []
    if answered.size:
        simulate = coverage.simulator_of(str(a["cell"]), Path(__file__).resolve().parent.parent / "tests" / "rocking_vectorised.py")
        theta = simulate(int(a["first_seed"]) + answered, int(a["n_points"]), dt=float(a["dt"]), e=float(a["e_true"]),
                                          burn_in=int(a["burn_in"]), pole=float(a["pole"]), noise=float(a["noise"]))
        for y, i in zip(theta, answered):
            try:
                shares.append(record_measure.measure(y, float(a["dt"])).side_g_share(float(ds["ppc_read"].values[i])))
            except InputError:
                shares.append(math.nan)
    shares = np.array(shares)
    kept = answered[shares >= estimation.SIDE_G_SHARE]
    n = ds.sizes["record"]
    low = f"{np.nanmin(shares):.2f}, {np.nanmedian(shares):.2f}" if answered.size else "-"
    return (f"| {path.stem} | {n} | {n - answered.size} | {answered.size}: {int(covered[answered].sum())} | {n - kept.size} | "
            f"{kept.size}: {int(covered[kept].sum())} | {low} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=Path, help="the coverage study's cells (results/studies/coverage/cells)")
    parser.add_argument("--cells", nargs="+", help="cell names (default: every .nc in the folder)")
    args = parser.parse_args()
    paths = [args.folder / f"{c}.nc" for c in args.cells] if args.cells else sorted(args.folder.glob("*.nc"))
    print("| cell | records | declined by the corner | left answered: covered | declined with the share | left answered: covered "
          "| side g share of those the corner leaves (min, median) |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for path in paths:
        print(cell_row(path), flush=True)


if __name__ == "__main__":
    main()

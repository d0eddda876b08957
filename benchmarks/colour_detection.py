"""How often is a coloured load found beneath sensor noise, and how often is noise alone called coloured?

A plain script (not a test): prints measurements, never asserts them.

    python benchmarks/colour_detection.py --records 100
    python benchmarks/colour_detection.py --conditions noise5 corner1_noise2 --e 0.95 --records 20

Records of the coverage study's cells (:mod:`rockdec.studies.coverage`: its step and pole
for 200,000 samples at 75 samples per cycle, the compiled kernel, sensor noise of the
condition's share of each record's rms), with seeds ``--offset`` past each cell's first seed,
apart from the cell's own records (the first few hundred) and from the seeds the thresholds
were chosen on (offset 1,000,000). Each record is analysed as ``rockdec estimate`` analyses it
(:func:`rockdec.rdd.measured.analyse` with its default settings, whose samples per cycle place
the measured corner) and measured (:func:`rockdec.record.record_measure.measure`). For each
cell it prints the share of records measured noisy and coloured
(:attr:`rockdec.record.record_measure.MeasuredModel.coloured`), the share whose load beneath
noise is left possibly low-pass below the floor, the share declined by
:func:`rockdec.estimation.colour_decline` for any reason, the percentiles of the shape
ratio's z, the 0, 5 and 50th percentiles of the side means' share of the signature's ``g``
(:meth:`rockdec.record.record_measure.MeasuredModel.side_g_share`) and the records that could
not be analysed or measured.
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from rockdec import estimation
from rockdec.physics.record_model import Load, RecordModel
from rockdec.pipeline.layout import COVERAGE_CASES, COVERAGE_CONDITIONS
from rockdec.rdd import measured
from rockdec.record import record_measure
from rockdec.studies import coverage
from rockdec.validate import InputError


def cell_rates(cell: str, records: int, offset: int) -> dict:
    _, condition, e = COVERAGE_CASES[cell]
    noise, corner = COVERAGE_CONDITIONS[condition]
    seed0 = coverage.STUDY_SEED_OFFSET + list(COVERAGE_CASES).index(cell) * coverage.CELL_SEEDS
    staged = coverage.stage(e, 200_000, corner, seed0 + coverage.PILOT_SEEDS)
    rows, refused = [], 0
    for seed in seed0 + offset + np.arange(records):
        theta = coverage.kernel_records([seed], 200_000, dt=staged["dt"], e=e, burn_in=staged["burn_in"], pole=staged["pole"], noise=noise)[0]
        try:
            n = measured.analyse([theta], staged["dt"], measured.DEFAULT_SETTINGS).points_per_cycle
            m = record_measure.measure(theta, staged["dt"])
        except (InputError, ValueError):
            refused += 1
            continue
        load = Load("lowpass", -math.log(m.pole.value) * n / (2 * math.pi)) if m.coloured else Load()
        declined = estimation.colour_decline(RecordModel(load=load), {"load": "measured"}, m, n) is not None
        unruled = declined and m.noisy and not m.coloured and m.shape_corner_low(n, estimation.COLOUR_CORNER_Z) < estimation.COLOUR_CORNER_FLOOR
        rows.append((m.noisy, m.coloured, unruled, declined, m.shape_z if m.noisy else math.nan, m.side_g_share(n)))
    r = np.array(rows, dtype=float)
    z = r[:, 4][np.isfinite(r[:, 4])]
    return {"cell": cell, "measured": len(rows), "refused": refused, "noisy": r[:, 0].mean(), "coloured": r[:, 1].mean(),
            "not_ruled_out": r[:, 2].mean(), "declined": r[:, 3].mean(),
            "z": np.percentile(z, [50, 95, 99, 100]) if z.size else [math.nan] * 4, "share": np.percentile(r[:, 5], [0, 5, 50])}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--conditions", nargs="+", default=["clean", "noise1", "noise3", "noise5", "corner1_noise2"])
    parser.add_argument("--e", nargs="+", type=float, default=[0.8, 0.9, 0.95])
    parser.add_argument("--records", type=int, default=100)
    parser.add_argument("--offset", type=int, default=2_000_000, help="seeds past each cell's first (the thresholds: 1,000,000)")
    args = parser.parse_args()
    print("| condition | e | records measured (refused) | noisy | coloured | white, colour not ruled out | declined | shape z (50, 95, 99 %, max) "
          "| side g share (min, 5, 50 %) |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for condition in args.conditions:
        for e in args.e:
            r = cell_rates(f"kernel_{condition}_e{e:g}", args.records, args.offset)
            z = ", ".join(f"{x:.1f}" for x in r["z"]) if np.isfinite(r["z"]).all() else "-"
            share = ", ".join(f"{x:.2f}" for x in r["share"])
            print(f"| {condition} | {e:g} | {r['measured']} ({r['refused']}) | {100 * r['noisy']:.0f} % | {100 * r['coloured']:.0f} % | "
                  f"{100 * r['not_ruled_out']:.0f} % | {100 * r['declined']:.0f} % | {z} | {share} |", flush=True)


if __name__ == "__main__":
    main()

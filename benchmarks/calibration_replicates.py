"""How far does one calibration's interval stray from another's, on records none of them saw?

A plain script (not a test): prints measurements, never asserts them.

    python benchmarks/calibration_replicates.py --e 0.8 --records 200 --replicates 6 --sets 30 60 --cache DIR

Fresh clean records of the compiled kernel (``--records`` of ``--n-points`` samples at the
coverage study's sampling, :func:`rockdec.studies.coverage.stage`; seeds apart from the
study's and the calibrations') are analysed as ``rockdec estimate`` analyses them; those in
the commonest samples-per-cycle bin are kept. For each number of sets per ``e``,
``--replicates`` calibrations of those records' settings
(:func:`rockdec.calibrate.calibration.calibration_settings`) are built with independent sets
(the settings carry a replicate number, which moves the seed base), and every kept record's
raw value of each estimator is inverted through each calibration's belt. Per estimator and
number of sets it prints the coverage and width / (3.92 sd)
(:func:`rockdec.studies.coverage.sharpness`) of each calibration on the same records, and
their mean and sd over the calibrations: the calibration-to-calibration scatter that every
record one calibration serves shares.
"""

from __future__ import annotations

import argparse
from collections import Counter
from pathlib import Path

import numpy as np

from rockdec import engine
from rockdec.calibrate import belt, calibration
from rockdec import estimation
from rockdec.rdd import measured
from rockdec.studies import coverage

#: Seeds of this bench's records start here (apart from the study's, the fresh records' and noise_high_e's).
SEED_OFFSET = 2**57


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--e", type=float, default=0.8)
    parser.add_argument("--records", type=int, default=200)
    parser.add_argument("--n-points", type=int, default=200_000)
    parser.add_argument("--replicates", type=int, default=6)
    parser.add_argument("--sets", type=int, nargs="+", default=[30, 60])
    parser.add_argument("--names", nargs="+", default=["e_v", "e_0"])
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--cache", type=Path, required=True, help="calibration folder")
    args = parser.parse_args()

    seed0 = SEED_OFFSET + int(round(1000 * args.e)) * 10**6
    staged = coverage.stage(args.e, args.n_points, None, seed0 + 9 * 10**5)
    seeds = seed0 + np.arange(args.records)
    rows = []
    for i in range(0, args.records, 20):
        theta = coverage.kernel_records(seeds[i:i + 20], args.n_points, dt=staged["dt"], e=args.e, burn_in=staged["burn_in"], pole=0.0, noise=0.0)
        for row in theta:
            a = measured.analyse([row], staged["dt"], dict(measured.DEFAULT_SETTINGS))
            rows.append((a.points_per_cycle, dict(a.raw)))
    key, kept = Counter(calibration.ppc_key(p) for p, _ in rows).most_common(1)[0]
    raws = [r for p, r in rows if calibration.ppc_key(p) == key]
    print(f"e = {args.e:g}: {len(raws)} of {len(rows)} fresh records read in the bin of {key:g} samples per cycle")
    for n in args.sets:
        per = {name: [] for name in args.names}
        for k in range(args.replicates):
            settings = {**calibration.calibration_settings([args.n_points], key), "sets_per_e": n, "replicate": k}
            with engine.session(args.threads):
                cal, _ = calibration.load_or_build(settings, args.cache)
            belts = belt.belts(cal)
            for name in args.names:
                got = []
                for raw in raws:
                    c = belt.correct(belts[name], raw[name])
                    ok = estimation.beyond(belts[name], raw[name], c) is None and np.isfinite(c.value)
                    got.append((c.value, c.low, c.high) if ok else (np.nan,) * 3)
                v, lo, hi = np.array(got).T
                answered = np.isfinite(v)
                cov = float(np.mean((lo[answered] <= args.e) & (args.e <= hi[answered])))
                per[name].append((cov, coverage.sharpness(args.e, v, hi - lo), coverage.sharpness(args.e, v, hi - lo, robust=True)))
        for name, values in per.items():
            a = np.array(values)
            print(f"  {name}, {n} sets per e, {args.replicates} calibrations: coverage "
                  + " ".join(f"{100 * x:.1f}" for x in a[:, 0]) + f" (mean {100 * a[:, 0].mean():.1f}, sd {100 * a[:, 0].std(ddof=1):.1f}); "
                  "width/(3.92 sd) " + " ".join(f"{x:.2f}" for x in a[:, 1]) + f" (mean {a[:, 1].mean():.2f}, sd {a[:, 1].std(ddof=1):.2f}); "
                  f"robust mean {a[:, 2].mean():.2f}, sd {a[:, 2].std(ddof=1):.2f}", flush=True)


if __name__ == "__main__":
    main()

"""Which candidate to report: the narrowest belt at the candidates' common ``e``
(:func:`rockdec.estimation.select`) against the narrowest of the record's own intervals,
on clean records of known ``e``, in one run.

Each record (``--samples`` samples at 75 samples per cycle, ``g = 1``, seeds from ``--seed``
on, apart from every calibration's) goes through :func:`rockdec.estimation.estimate`
with the calibration cache ``--cache`` (built once per samples-per-cycle bin). From its
trusted candidates, both rules pick one; printed per ``e``: the coverage of the 95 % interval
each rule reports, with its binomial sd, and the median width, beside each candidate's own
coverage. A record with no trusted candidate counts for neither.

Run: ``python benchmarks/selection_rule.py --e 0.6 0.85 0.95 --records 80 --cache DIR``.
Prints numbers; asserts nothing.
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from rockdec.calibrate import belt

from rockdec import estimation

from rockdec.report.estimate_report import document
from rockdec.physics import simulate
from rockdec.rdd import registry
from rockdec.record.records import Record


def picks(res: dict) -> dict[str, str]:
    """The candidate each rule reports for one estimate's result: ``common e`` (the
    package's) and ``own width`` (the narrowest of the record's own intervals)."""
    trusted = [row["estimator"] for row in res["selection"] if row["holds"]]
    if not trusted:
        return {}
    width = {name: res["estimators"][name]["interval"][1] - res["estimators"][name]["interval"][0] for name in trusted}
    return {"common e": res["estimator"], "own width": min(trusted, key=width.get)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--e", type=float, nargs="+", default=[0.6, 0.85, 0.95])
    parser.add_argument("--records", type=int, default=80)
    parser.add_argument("--samples", type=int, default=20_000)
    parser.add_argument("--seed", type=int, default=1000)
    parser.add_argument("--cache", required=True)
    args = parser.parse_args()
    for e in args.e:
        step = simulate.calibrate_dt(e=e, g=1.0, sigma_p=0.003, points_per_cycle=75)
        covered = {rule: [] for rule in ("common e", "own width", *registry.CANDIDATES)}
        width = {rule: [] for rule in covered}
        for seed in range(args.seed, args.seed + args.records):
            theta = simulate.simulate_block([seed], args.samples, dt=step["dt"], g=1.0, e=e, sigma_p=0.003, burn_in=step["burn_in"])[0][0]
            res = document(estimation.estimate([Record(theta.astype(float), step["dt"], f"seed {seed}")], cache_dir=args.cache))
            chosen = picks(res)
            for row in res["selection"]:
                if row["holds"]:
                    chosen[row["estimator"]] = row["estimator"]
            for rule, name in chosen.items():
                low, high = res["estimators"][name]["interval"]
                covered[rule].append(low <= e <= high)
                width[rule].append(high - low)
        print(f"e = {e}, {args.records} records of {args.samples} samples")
        for rule, hits in covered.items():
            n = len(hits)
            if n:
                p = float(np.mean(hits))
                print(f"  {rule:>9}: coverage {p:6.1%} (+- {math.sqrt(p * (1 - p) / n):.1%}, n = {n}), median width {np.median(width[rule]):.3f}")


if __name__ == "__main__":
    main()

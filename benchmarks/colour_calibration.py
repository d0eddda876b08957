"""How alike are a coloured calibration's record sets, and do its belts cover them?

A plain script (not a test): prints measurements, never asserts them.

    python benchmarks/colour_calibration.py spread --corners 0.5 1 1.5 2 3 --e 0.8 0.9 0.95
    python benchmarks/colour_calibration.py coverage --corner 3 --cache DIR

``spread``: for each corner (rocking frequencies, eq. 5) and ``e``, one grid point of the
calibration of a 200,000-sample record at 75 samples per cycle under a low-pass load
(:func:`rockdec.calibrate.calibration._grid_point`: the step search and the sets' step
correction); prints the samples per cycle read off its 30 sets (10th, 25th, 50th, 75th,
90th percentiles of the try kept) and the number of tries. The spread (90th over 10th
percentile) is what :data:`rockdec.estimation.COLOUR_CORNER_FLOOR` rests on.

``coverage``: the whole calibration at one corner (built in, or read from, ``--cache``);
prints each estimator's in-sample coverage
(:func:`rockdec.calibrate.belt.calibration_coverage`) and, for the candidates, its coverage
per ``e``, and the median samples per cycle read off the sets of every try at every ``e``.
"""

from __future__ import annotations

import argparse
import math
from collections import defaultdict

import numpy as np

from rockdec.calibrate import belt, calibration
from rockdec.physics.record_model import Load, RecordModel
from rockdec.rdd import registry


def _watch() -> dict:
    """Record the samples per cycle read off the sets of every try, per ``e``."""
    tries: dict = defaultdict(list)
    real = calibration._sets

    def sets(e, *args):
        out = real(e, *args)
        tries[e].append(out[2])
        return out

    calibration._sets = sets
    return tries


def spread(corners, es, n_points: int) -> None:
    tries = _watch()
    for corner in corners:
        settings = calibration.calibration_settings([n_points], 75.0, model=RecordModel(load=Load("lowpass", corner)))
        target = settings["points_per_cycle"]
        for e in es:
            tries.clear()
            calibration._grid_point(6, e, settings, calibration.CALIBRATION_SEED_OFFSET)
            kept = min(tries[e], key=lambda read: abs(math.log(np.nanmedian(read) / target)))
            q = np.nanpercentile(kept, [10, 25, 50, 75, 90])
            print(f"corner {corner:g} e {e:g}: {len(tries[e])} tries; samples per cycle read (target {target:g}): "
                  f"{q[0]:.0f} {q[1]:.0f} [{q[2]:.0f}] {q[3]:.0f} {q[4]:.0f}; 90th/10th {q[4] / q[0]:.1f}", flush=True)


def coverage(corner: float, n_points: int, cache: str) -> None:
    tries = _watch()
    settings = calibration.calibration_settings([n_points], 75.0, model=RecordModel(load=Load("lowpass", corner)))
    cal, cached = calibration.load_or_build(settings, cache)
    belts = belt.belts(cal)
    for name in registry.ESTIMATORS:
        print(f"{name}: in-sample coverage {belt.calibration_coverage(cal, name, belts[name]):.3f}")
    for name in registry.CANDIDATES:
        cells = []
        for i, e in enumerate(cal["e_true"].values):
            raw = np.asarray(cal["raw"].sel(name=name).values[i])
            low, high = belt.intervals(belts[name], raw)
            ok = np.isfinite(raw)
            cells.append(f"{e:g}: {np.mean((low[ok] <= e) & (e <= high[ok])):.2f}")
        print(f"{name} per e: " + ", ".join(cells))
    if cached:
        print("(read from the cache: the sets' tries are not shown)")
    for e, reads in sorted(tries.items()):
        print(f"e {e:g}: median samples per cycle per try " + " -> ".join(f"{np.nanmedian(r):.1f}" for r in reads))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="what", required=True)
    s = sub.add_parser("spread")
    s.add_argument("--corners", type=float, nargs="+", default=[0.5, 1.0, 1.5, 2.0, 3.0])
    s.add_argument("--e", type=float, nargs="+", default=[0.8, 0.9, 0.95])
    c = sub.add_parser("coverage")
    c.add_argument("--corner", type=float, required=True)
    c.add_argument("--cache", required=True)
    for p in (s, c):
        p.add_argument("--samples", type=int, default=200_000)
    args = parser.parse_args()
    if args.what == "spread":
        spread(args.corners, args.e, args.samples)
    else:
        coverage(args.corner, args.samples, args.cache)


if __name__ == "__main__":
    main()

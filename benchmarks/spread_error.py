"""How wide is a calibration's band against the scatter it must hold, calibration by calibration?

A plain script (not a test): prints measurements, never asserts them.

    python benchmarks/spread_error.py --noise 0 --ppc 75 --pool 480 --sets 30 60 120 --gamma 1.4 4.9

The reported interval's width over 3.92 times the spread of the reported ``e`` (the
coverage study's sharpness, :func:`rockdec.studies.coverage.sharpness`) is, record for
record, the belt's band ``(q_high - q_low) s(e)`` over 3.92 times the raw value's true spread
at ``e`` (the mean curve's slope divides both). So a calibration's sharpness is read here
without records: a pool of ``--pool`` sets is simulated at each ``e`` of
:data:`rockdec.calibrate.calibration.E_GRID` and at the coverage study's ``e`` between them
(:func:`calibration_mean_error.pool`, seeds apart from every calibration's), belts are
fitted to disjoint blocks of ``n`` sets per grid point (each block a calibration of ``n``
sets per ``e``), and at each test ``e`` the band's width is divided by 3.92 times the sd of
the pool's sets outside the block. Per variant (sets per ``e``; the GCV penalty of the
smoothers, :data:`rockdec.calibrate.belt.GCV_GAMMA`, where 4.9 leaves ten points only a
straight line; the quantile pooling's bandwidth :data:`rockdec.calibrate.belt.QUANTILE_BANDWIDTH`)
it prints the mean of that ratio over the blocks, its sd (one calibration against another)
and the share of the pool's sets the band holds at each test ``e`` (the interval's
coverage at that ``e``, with the mean curve's error), its mean and sd over the blocks (how
far one calibration's coverage strays from another's).
"""

from __future__ import annotations

import argparse
import itertools
from pathlib import Path

import numpy as np

from calibration_mean_error import pool
from rockdec.calibrate import belt, calibration

#: Test values of e: the coverage study's (0.6, 0.9 and 0.98 between grid points).
TEST_E = (0.6, 0.8, 0.9, 0.95, 0.98)


def ratios(raw: np.ndarray, es, name: str, n: int) -> tuple[np.ndarray, np.ndarray]:
    """``(block, test e)``: the band's width over 3.92 times the pool's sd outside the block,
    and the share of the pool's sets outside the block that the band holds."""
    es = list(es)
    grid = [es.index(e) for e in calibration.E_GRID]
    values = raw[:, :, list(calibration.NAMES).index(name)]
    width, held = [], []
    for b in range(values.shape[1] // n):
        block = slice(b * n, (b + 1) * n)
        fitted = belt.fit(np.asarray(calibration.E_GRID), values[grid][:, block])
        w_row, h_row = [], []
        for e in TEST_E:
            j = es.index(e)
            rest = np.ones(values.shape[1], bool)
            if e in calibration.E_GRID:
                rest[block] = False
            x = values[j, rest]
            x = x[np.isfinite(x)]
            m, s = (np.interp(e, fitted.e, v) for v in (fitted.mean, fitted.spread))
            lo, hi = (np.interp(e, fitted.e, np.broadcast_to(q, fitted.e.shape)) for q in (fitted.q_low, fitted.q_high))
            w_row.append((hi - lo) * s / (2 * belt.Z95 * np.std(x, ddof=1)))
            h_row.append(np.mean((x >= m + lo * s) & (x <= m + hi * s)))
        width.append(w_row)
        held.append(h_row)
    return np.asarray(width), np.asarray(held)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--noise", type=float, default=0.0, help="sensor noise in sigma_Y")
    parser.add_argument("--ppc", type=float, default=75.0, help="samples per cycle the sets read")
    parser.add_argument("--samples", type=int, default=200_000, help="samples of a record")
    parser.add_argument("--pool", type=int, default=480, help="sets per e of the pool")
    parser.add_argument("--sets", type=int, nargs="+", default=[30, 60, 120], help="sets per grid point of the belts compared")
    parser.add_argument("--gamma", type=float, nargs="+", default=[belt.GCV_GAMMA], help="GCV penalties compared")
    parser.add_argument("--bandwidth", type=float, nargs="+", default=[belt.QUANTILE_BANDWIDTH], help="quantile bandwidths compared")
    parser.add_argument("--names", nargs="+", default=["e_0", "e_v"], help="estimators")
    parser.add_argument("--threads", type=int, default=2, help="threads simulating the pool")
    parser.add_argument("--save", help="store the pool here (.npy) / read it from here if it exists")
    args = parser.parse_args(argv)
    es = sorted({*calibration.E_GRID, *TEST_E})

    if args.save and Path(args.save).exists():
        raw = np.load(args.save)
    else:
        raw = pool(args.noise, args.ppc, args.samples, args.pool, es, args.threads)
        if args.save:
            np.save(args.save, raw)
    print(f"\nnoise {args.noise:g}, {args.ppc:g} samples per cycle, {args.samples} samples, pool {args.pool} sets per e")
    print("| estimator | sets per e | GCV penalty | bandwidth | blocks | width / (3.92 sd) mean (sd over blocks) at e = "
          + ", ".join(map(str, TEST_E)) + " | band holds at each e: mean (sd over blocks), % |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for name, n, gamma, bw in itertools.product(args.names, args.sets, args.gamma, args.bandwidth):
        belt.GCV_GAMMA, belt.QUANTILE_BANDWIDTH = gamma, bw
        w, h = ratios(raw, es, name, n)
        print(f"| {name} | {n} | {gamma:g} | {bw:g} | {len(w)} | "
              + " / ".join(f"{a:.2f} ({b:.2f})" for a, b in zip(np.nanmean(w, 0), np.nanstd(w, 0, ddof=1)))
              + " | " + " / ".join(f"{100 * a:.1f} ({100 * b:.1f})" for a, b in zip(np.nanmean(h, 0), np.nanstd(h, 0, ddof=1))) + " |",
              flush=True)


if __name__ == "__main__":
    main()

"""The forced reading of shake-table records (:mod:`rockdec.free.forced`: every impact, the
base a known load in the arcs) beside the free-decay tails, on records of the tests'
independent transient generator (``tests/transient_reference.py``: its own stepper, not the
project's simulator).

A plain script (not a test): prints measurements, never asserts them.

    python benchmarks/shake_forced.py                  # the default grid, 10 records a cell
    python benchmarks/shake_forced.py --records 4 --e 0.8

Cells: true ``e`` x the shaking's strength (``--peak``, the base's std in its strong phase in
uplift levels) x sensor noise (a share of the record's std) x how the generator's base acts
between samples (``linear``, a sampled smooth motion as the fit reads it, or ``held``, a
simulator's staircase). Each record is 20 s of shaking and 20 s of free decay at 200 Hz.
Per cell, for the forced reading and for the tails (what ``rockdec.shake_table`` reports as
``e``): records answered, how many intervals hold the true ``e``, the median width. Then
``--campaigns`` campaigns of ten records a cell pooled (linear base): answered, held, the
median pooled width against the median single-record width.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import transient_reference as tr  # noqa: E402

from rockdec.free.shake import analyse_shake_table  # noqa: E402

BASES = {"linear": 8, "held": 0}


def _fit(records):
    return analyse_shake_table([t for t, _ in records], [b for _, b in records], 1 / tr.FS, base_units="rad/s2", g_block=tr.G) \
        if len(records) > 1 else analyse_shake_table(*records[0], 1 / tr.FS, base_units="rad/s2", g_block=tr.G)


def _tally(readings, e):
    """Answered, held and the median width of ``(e, (low, high))`` readings."""
    answered = [(lo, hi) for v, (lo, hi) in readings if math.isfinite(v)]
    held = sum(lo <= e <= hi for lo, hi in answered)
    width = statistics.median(hi - lo for lo, hi in answered) if answered else math.nan
    return len(answered), held, width


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--records", type=int, default=10)
    p.add_argument("--e", type=float, nargs="+", default=[0.8, 0.9, 0.95])
    p.add_argument("--peak", type=float, nargs="+", default=[1.2, 1.6, 2.2])
    p.add_argument("--noise", type=float, nargs="+", default=[0.0, 0.01])
    p.add_argument("--base", nargs="+", default=list(BASES), choices=list(BASES))
    p.add_argument("--campaigns", type=int, default=5)
    args = p.parse_args(argv)
    start = time.perf_counter()
    print("| base | e | peak | noise | records | forced: answered | held | median width | tails: answered | held | median width |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    totals = {"forced": [0, 0], "tails": [0, 0]}
    for base in args.base:
        for e in args.e:
            for peak in args.peak:
                for noise in args.noise:
                    fits = [_fit([tr.transient_with_base(e, seed, peak=peak, noise=noise, substeps=BASES[base])]) for seed in range(args.records)]
                    forced = _tally([(f.forced_pooled.e, f.forced_pooled.e_interval) for f in fits], e)
                    tails = _tally([(f.e, f.e_interval) for f in fits], e)
                    for name, (a, h, _) in (("forced", forced), ("tails", tails)):
                        totals[name][0] += a
                        totals[name][1] += h
                    print(f"| {base} | {e} | {peak} | {noise:g} | {args.records} | {forced[0]} | {forced[1]} | {forced[2]:.2g} | {tails[0]} | {tails[1]} | {tails[2]:.2g} |", flush=True)
    cells = len(args.base) * len(args.e) * len(args.peak) * len(args.noise) * args.records
    for name, (a, h) in totals.items():
        print(f"{name}: {a} of {cells} answered, {h} of them held ({h / max(a, 1):.1%})")
    if args.campaigns:
        print("\n| e | peak | noise | campaigns | answered | held | median pooled width | median single width |")
        print("|---|---|---|---|---|---|---|---|")
        for e in args.e:
            for peak in args.peak:
                for noise in [n for n in args.noise if n > 0]:
                    pooled, single = [], []
                    for c in range(args.campaigns):
                        records = [tr.transient_with_base(e, 1000 + 10 * c + k, peak=peak, noise=noise, substeps=8) for k in range(10)]
                        fit = _fit(records)
                        pooled.append((fit.forced_pooled.e, fit.forced_pooled.e_interval))
                        single += [f.e_interval[1] - f.e_interval[0] for f in fit.forced if math.isfinite(f.e)]
                    a, h, w = _tally(pooled, e)
                    print(f"| {e} | {peak} | {noise:g} | {args.campaigns} | {a} | {h} | {w:.2g} | {statistics.median(single):.2g} |", flush=True)
    print(f"\n{time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    main()

"""The forced response calibrated by replaying the record (issue 50, item 2), measured against
the other two readings of a shake-table test: the free-decay tails and every impact with the
base a known load (:mod:`rockdec.free.forced`).

The replay: the project's simplified block (:func:`rockdec.physics.simulate.integrate`) under
the record's own base acceleration, at a grid of ``e``, each set perturbed by white noise of
``--perturb`` times the base's std on the base (the base record's own noise, and what makes
the chaotic response differ set to set) and the record's sensor noise on the angle; the
statistic is the log rms angle up to the shaking's end; its belt is
:func:`rockdec.calibrate.belt.fit` and the record's ``e`` and interval
:func:`rockdec.calibrate.belt.correct`, as the random test's. The block's ``g`` is given (the
generator's). Records: the tests' independent generator (``tests/transient_reference.py``).

A plain script (not a test): prints measurements, never asserts them.

    python benchmarks/shake_replay.py                 # 10 records a cell, 40 sets a grid point
    python benchmarks/shake_replay.py --records 4 --sets 20
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import transient_reference as tr  # noqa: E402

from rockdec.calibrate import belt  # noqa: E402
from rockdec.free.shake import analyse_shake_table, shaking_end, uplift_ratio  # noqa: E402
from rockdec.physics.simulate import integrate  # noqa: E402

GRID = np.linspace(0.5, 0.99, 50)


def statistic(theta: np.ndarray, end: int) -> np.ndarray:
    """The log rms angle of the first ``end`` samples (of each row)."""
    return np.log(np.sqrt(np.mean(theta[..., :end] ** 2, axis=-1)))


def replay(base: np.ndarray, e: float, sets: int, perturb: float, noise: float, rng) -> np.ndarray:
    """``sets`` replays of the block under ``base`` (rad/s^2) at ``e``, with sensor noise ``noise`` (rad)."""
    dt = 1 / tr.FS
    theta, omega = np.empty((sets, base.size)), np.empty(base.size)
    for j in range(sets):
        integrate((base[:-1] + perturb * base.std() * rng.standard_normal(base.size - 1)) * dt, dt, tr.G, e, 0.0, 0.0, 0, theta[j], omega)
    return theta + noise * rng.standard_normal(theta.shape)


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--records", type=int, default=10)
    p.add_argument("--sets", type=int, default=40)
    p.add_argument("--perturb", type=float, default=0.01)
    p.add_argument("--e", type=float, nargs="+", default=[0.8, 0.9, 0.95])
    p.add_argument("--noise", type=float, nargs="+", default=[0.0, 0.01])
    p.add_argument("--peak", type=float, default=1.6)
    args = p.parse_args(argv)
    start = time.perf_counter()
    print("| e | noise | records | replay: answered | held | median width | forced: held | median width | tails: answered | held | median width |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for e in args.e:
        for noise in args.noise:
            rows = []
            for seed in range(args.records):
                theta, base = tr.transient_with_base(e, seed, peak=args.peak, noise=noise, substeps=8)
                end = shaking_end(uplift_ratio(base, base_units="rad/s2", g_block=tr.G), 1 / tr.FS)
                rng = np.random.default_rng([seed, 7])
                raw = np.array([statistic(replay(base, x, args.sets, args.perturb, noise * theta.std(), rng), end) for x in GRID])
                got = belt.correct(belt.fit(GRID, raw), float(statistic(theta, end)))
                shake = analyse_shake_table(theta, base, 1 / tr.FS, base_units="rad/s2", g_block=tr.G)
                rows.append(((got.value, (got.low, got.high)), (shake.forced_pooled.e, shake.forced_pooled.e_interval), (shake.e, shake.e_interval)))
            cells = []
            for k in range(3):
                answered = [(lo, hi) for v, (lo, hi) in (r[k] for r in rows) if math.isfinite(v)]
                held = sum(lo <= e <= hi for lo, hi in answered)
                cells.append((len(answered), held, statistics.median(hi - lo for lo, hi in answered) if answered else math.nan))
            (ra, rh, rw), (_, fh, fw), (ta, th, tw) = cells
            print(f"| {e} | {noise:g} | {args.records} | {ra} | {rh} | {rw:.3g} | {fh} | {fw:.2g} | {ta} | {th} | {tw:.2g} |", flush=True)
    print(f"\n{time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    main()

"""How far off is a calibration's mean curve, in units of the records' spread?

A plain script (not a test): prints measurements, never asserts them.

    python benchmarks/calibration_mean_error.py --noise 0.03 --ppc 90 --sets 30 45 60
    python benchmarks/calibration_mean_error.py --noise 0 --ppc 81.45 --names e_v e_0

The belt's mean ``m(e)`` (:func:`rockdec.calibrate.belt.fit`) is read off a calibration's
sets, so its error is shared by every record corrected through that calibration: it is
their bias, not a scatter. For one record model (white load, sensor noise ``--noise`` in
``sigma_Y``, ``--ppc`` samples per cycle, records of ``--samples``), this simulates a pool
of ``--pool`` sets at each ``e`` of :data:`rockdec.calibrate.calibration.E_GRID` and at the
test values between them, each at the step the calibration's own search finds
(:func:`rockdec.calibrate.calibration.step_for`, then the sets' median samples per cycle
brought to ``--ppc`` by the white law, so that every ``e`` sits at the same sampling),
with seeds apart from every calibration's. Belts are fitted to disjoint blocks of ``n``
sets per grid point; at each test ``e`` the error of the belt's mean against the pool's
mean (the block's own sets left out) is divided by the pool's spread. Prints, per
estimator and ``n``, the rms of that error over the blocks and its mean (the part more
sets do not remove: the smoother's).
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from rockdec.calibrate import belt, calibration
from rockdec.physics.record_model import WHITE, RecordModel, SensorNoise
from rockdec.rdd import measured

#: Seeds of the pools start here, apart from the calibration's, the studies' and the scenes'.
SEED_OFFSET = 2**62

#: Test values of e between and on the grid points.
TEST_E = (0.5, 0.6, 0.65, 0.7, 0.75, 0.8, 0.865, 0.9, 0.95, 0.985)


def pool(noise: float, ppc: float, samples: int, sets: int, es, threads: int = 1) -> np.ndarray:
    """Raw zero-window values ``(e, set, name)`` of ``sets`` sets at each of ``es`` (the values
    of ``e`` spread over ``threads`` threads; the same numbers whatever their number)."""
    from concurrent.futures import ThreadPoolExecutor

    model = RecordModel("simplified", WHITE, SensorNoise(noise, "sigma_y"))
    settings = dict(measured.DEFAULT_SETTINGS)

    def one(j: int) -> np.ndarray:
        e = es[j]
        raw = np.full((sets, len(calibration.NAMES)), np.nan)
        seed0 = SEED_OFFSET + j * 10**7
        dt, burn_in, _ = calibration.step_for(e, ppc, [samples], settings, seed0 + 9 * 10**6, model)
        probe = [measured.analyse(calibration._simulate_set(seed0 + 8 * 10**6 + k, [samples], dt, e, burn_in, model), dt, settings).points_per_cycle
                 for k in range(30)]
        dt *= math.sqrt(float(np.median(probe)) / ppc)
        for k in range(sets):
            try:
                analysis = measured.analyse(calibration._simulate_set(seed0 + k, [samples], dt, e, burn_in, model), dt, settings)
            except ValueError:
                continue
            raw[k] = [analysis.raw[name] for name in calibration.NAMES]
        print(f"pool e = {e}: dt = {dt:.4g}, median samples per cycle of the probe {np.median(probe):.1f}", flush=True)
        return raw

    with ThreadPoolExecutor(threads) as workers:
        return np.stack(list(workers.map(one, range(len(es)))))


def errors(raw: np.ndarray, es, name: str, n: int) -> np.ndarray:
    """``(block, test e)``: the error of the mean of belts fitted to disjoint blocks of ``n``
    sets per grid point, in units of the pool's spread at each test ``e``."""
    es = list(es)
    grid = [es.index(e) for e in calibration.E_GRID]
    values = raw[:, :, list(calibration.NAMES).index(name)]
    out = []
    for b in range(values.shape[1] // n):
        block = slice(b * n, (b + 1) * n)
        fitted = belt.fit(np.asarray(calibration.E_GRID), values[grid][:, block])
        row = []
        for e in TEST_E:
            j = es.index(e)
            rest = np.ones(values.shape[1], bool)
            if e in calibration.E_GRID:
                rest[block] = False
            row.append((np.interp(e, fitted.e, fitted.mean) - np.nanmean(values[j, rest])) / np.nanstd(values[j]))
        out.append(row)
    return np.asarray(out)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--noise", type=float, default=0.03, help="sensor noise in sigma_Y")
    parser.add_argument("--ppc", type=float, default=90.0, help="samples per cycle the sets read")
    parser.add_argument("--samples", type=int, default=200_000, help="samples of a record")
    parser.add_argument("--pool", type=int, default=300, help="sets per e of the pool")
    parser.add_argument("--sets", type=int, nargs="+", default=[30, 60], help="sets per grid point of the belts compared")
    parser.add_argument("--names", nargs="+", default=["e_0", "e_v", "e4"], help="estimators")
    args = parser.parse_args(argv)
    es = sorted({*calibration.E_GRID, *TEST_E})
    raw = pool(args.noise, args.ppc, args.samples, args.pool, es)
    print("\n| estimator | sets per e | blocks | rms error / spread at e = " + ", ".join(map(str, TEST_E)) + " | mean error / spread |")
    print("| --- | --- | --- | --- | --- |")
    for name in args.names:
        for n in args.sets:
            err = errors(raw, es, name, n)
            rms, mean = np.sqrt(np.mean(err**2, axis=0)), err.mean(axis=0)
            print(f"| {name} | {n} | {len(err)} | {' / '.join(f'{x:.2f}' for x in rms)} | {' / '.join(f'{x:+.2f}' for x in mean)} |")


if __name__ == "__main__":
    main()

"""A campaign of records of many lengths: calibrations shared across lengths
(``share_lengths``) against one exact-length calibration a record, cold, in one run.

A plain script (not a test): prints timings, counts and their ratios, never asserts them.

    python benchmarks/bench_campaign_lengths.py                    # 20 records, 2,000-200,000 samples
    python benchmarks/bench_campaign_lengths.py --records 6 --longest 50000

The records (``--records``, lengths evenly spaced in their logarithm from ``--shortest`` to
``--longest``, one seed each) come from the tests' vectorised simulator written apart from
the project (``tests/rocking_vectorised.py``), clean, at ``e`` = ``--e`` and 75 samples per
rocking cycle. Each is estimated as the campaign's estimate step does it
(:func:`rockdec.estimate`), one after the other, twice, each time into its own empty cache:

1. **exact**: ``share_lengths=False``, a calibration a record length (what a campaign
   costs without the option);
2. **shared**: ``share_lengths=True`` (the sheet's ``share_lengths yes``): records whose
   lengths fall in one bin of the length grid share one calibration.

Printed per record: its length, the grid length it is calibrated at, both answers; then
the calibrations each way built, their wall and CPU seconds, the shared/exact ratios and
the samples each way simulated per set (the ratio the cost model predicts). The coverage
of the shared calibrations is measured on more records by
``benchmarks/length_grid_coverage.py``.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import rocking_vectorised  # noqa: E402

import rockdec  # noqa: E402
from rockdec.calibrate import calibration  # noqa: E402
from rockdec.physics.simulate import default_burn_in  # noqa: E402
from rockdec.rdd import measured  # noqa: E402

PPC = 75.0


def _cpu() -> float:
    """CPU seconds of this process and its children, every thread."""
    times = os.times()
    return times.user + times.system + times.children_user + times.children_system


def lengths(count: int, shortest: int, longest: int) -> list[int]:
    """``count`` record lengths evenly spaced in their logarithm, rounded to 3 significant digits."""
    return [int(float(f"{n:.3g}")) for n in np.geomspace(shortest, longest, count)]


def record(e: float, n_points: int, seed: int) -> tuple[np.ndarray, float]:
    """One clean record of the independent simulator and its step (``g = sigma_p = 1``)."""
    dt = calibration.step_for(e, PPC, [n_points], measured.DEFAULT_SETTINGS, 777)[0]
    theta = rocking_vectorised.simulate_records(np.array([seed]), n_points, dt=dt, g=1.0, e=e, sigma_p=1.0,
                                                burn_in=default_burn_in(e, PPC))
    return theta[0], dt


def answer(result, e: float) -> str:
    """The estimate in words: ``e [low, high]`` and whether it holds the true ``e``, or the reason."""
    if result.e is None:
        return f"no e ({result.reason[:60]})"
    low, high = result.confidence_interval
    return f"{result.e:.3f} [{low:.3f}, {high:.3f}] {'holds' if low <= e <= high else 'MISSES'}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--e", type=float, default=0.9)
    parser.add_argument("--records", type=int, default=20)
    parser.add_argument("--shortest", type=int, default=2_000)
    parser.add_argument("--longest", type=int, default=200_000)
    parser.add_argument("--seed", type=int, default=70_000)
    args = parser.parse_args()
    sizes = lengths(args.records, args.shortest, args.longest)
    print(f"load average {os.getloadavg()[0]:.2f}; {len(sizes)} records of e {args.e:g}, {sizes[0]}-{sizes[-1]} samples", file=sys.stderr)
    data = [record(args.e, n, args.seed + k) for k, n in enumerate(sizes)]
    caches = {share: Path(tempfile.mkdtemp(prefix=f"campaign-lengths-{'shared' if share else 'exact'}-")) for share in (False, True)}
    wall, cpu, answers = {}, {}, {}
    for share in (False, True):
        start, tick = time.perf_counter(), _cpu()
        answers[share] = []
        for k, (theta, dt) in enumerate(data):
            answers[share].append(answer(rockdec.estimate(theta, dt, cache=caches[share], share_lengths=share), args.e))
            print(f"  {'shared' if share else 'exact'} {k + 1}/{len(data)}", file=sys.stderr)
        wall[share], cpu[share] = time.perf_counter() - start, _cpu() - tick
    print("| samples | grid length | exact | shared |")
    print("| --- | --- | --- | --- |")
    for n, exact, shared in zip(sizes, answers[False], answers[True]):
        print(f"| {n} | {sum(calibration.simulated_lengths([n], True))} | {exact} | {shared} |")
    built = {share: len(list(caches[share].glob("calibration-*.nc"))) for share in (False, True)}
    simulated = {share: sum({sum(calibration.simulated_lengths([n], share)) for n in sizes}) for share in (False, True)}
    print()
    for share in (False, True):
        print(f"{'shared' if share else 'exact'}: {built[share]} calibrations, {wall[share]:.0f} s wall, {cpu[share]:.0f} s CPU, "
              f"{simulated[share]} samples simulated a set")
    print(f"shared / exact: calibrations {built[True] / built[False]:.2f}, wall {wall[True] / wall[False]:.2f}, "
          f"CPU {cpu[True] / cpu[False]:.2f}, simulated samples {simulated[True] / simulated[False]:.2f}")


if __name__ == "__main__":
    main()

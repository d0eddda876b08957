"""The cost of pooling many short records, against one record of as many samples, in one run.

Measures ``rockdec.estimate`` (cold: a fresh calibration cache each) on ``N`` records of
``n`` samples and on one record of ``N n`` samples, both at e = 0.85, and prints the
seconds per extra record and per simulated set that the cost model's
:data:`rockdec.estimation.RECORD_SECONDS` stands for, with the model's estimate
beside the measured time (ratios, not absolute times, carry over between machines).

Run: ``python benchmarks/pooled_cost.py [N] [n]`` (default 60 records of 2,000 samples).
"""

from __future__ import annotations

import sys
import tempfile
import time

import rockdec
from rockdec import estimation


def timed(records, dt) -> float:
    with tempfile.TemporaryDirectory() as cache:
        started = time.process_time()
        rockdec.estimate(records, dt=dt, cache=cache)
        return time.process_time() - started


def main(n_records: int = 60, n: int = 2000) -> None:
    theta = rockdec.simulate(0.85, n, seed=list(range(1, n_records + 1)))
    dt = theta.attrs["dt"]
    one = rockdec.simulate(0.85, n * n_records, seed=1, dt=dt)
    many_s = timed([theta.values[i] for i in range(n_records)], dt)
    one_s = timed(one.values, dt)
    sets = estimation.calibration_sets(n * n_records)
    per = (many_s - one_s) / ((n_records - 1) * sets)
    model_many = sum(estimation.stage_seconds(n * n_records, False, False, records=n_records).values())
    model_one = sum(estimation.stage_seconds(n * n_records, False, False).values())
    print(f"{n_records} records of {n} samples: {many_s:.1f} s of CPU; one record of {n * n_records}: {one_s:.1f} s "
          f"(ratio {many_s / one_s:.2f}; the cost model's ratio {model_many / model_one:.2f})")
    print(f"seconds per extra record and simulated set: {per:.2e} (model RECORD_SECONDS {estimation.RECORD_SECONDS:.1e})")


if __name__ == "__main__":
    main(*map(int, sys.argv[1:3]))

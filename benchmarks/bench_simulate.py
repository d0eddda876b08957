"""Simulator throughput against drawing its random numbers, the pure-Python step, and threads.

Run: ``python benchmarks/bench_simulate.py``. Prints steps/s and ratios measured in one
run (docs/method.md §3; issue: simulation <= 2x the cost of its random numbers, 2 threads >= 1.7x
one thread on 200 seeds). Nothing is asserted: the numbers are the result.
"""

from __future__ import annotations

import argparse
import time

import dask
import numpy as np

import tests_path  # noqa: F401  (tests/ on sys.path for the reference)
from rocking_reference import flight_reference

from rockdec.physics import loading, simulate


def best_of(repeats, func):
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        func()
        times.append(time.perf_counter() - start)
    return min(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=200)
    parser.add_argument("--points", type=int, default=6000)
    parser.add_argument("--burn-in", type=int, default=8087)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    dt, g, e, sigma_p = 0.003433, 1.0, 0.95, 0.003  # the paper scene's calibrated step
    seeds = np.arange(args.seeds)
    steps = args.seeds * (args.burn_in + args.points - 1)
    kw = dict(dt=dt, g=g, e=e, sigma_p=sigma_p, burn_in=args.burn_in)
    simulate.simulate_block(seeds[:2], 100, **kw)  # compile / load the numba cache

    def draw_only():
        buf = np.empty(args.burn_in + args.points - 1)
        for s in seeds:
            loading.series_rng(s).standard_normal(out=buf)

    t_draw = best_of(args.repeats, draw_only)
    t_one = best_of(args.repeats, lambda: simulate.simulate_block(seeds, args.points, **kw))
    lazy = simulate.simulation_dataset(seeds, args.points, chunk_seeds=max(1, args.seeds // 8), **kw).theta

    def threaded(n):
        with dask.config.set(scheduler="threads", num_workers=n):
            lazy.data.compute()

    t_dask1 = best_of(args.repeats, lambda: threaded(1))
    t_dask2 = best_of(args.repeats, lambda: threaded(2))
    # pure-Python reference step on a short stretch of one series
    n_ref = 20_000
    impulses = loading.series_rng(0).standard_normal(n_ref) * sigma_p

    def python_steps():
        theta = omega = 0.0
        for p in impulses:
            theta, omega = flight_reference(theta, omega, dt, g, e)
            omega += p

    t_py = best_of(1, python_steps) / n_ref * steps
    print(f"{args.seeds} seeds x ({args.burn_in} burn-in + {args.points}) = {steps:.3g} steps")
    print(f"draw normals only   : {t_draw:7.3f} s  {steps / t_draw:.3g} numbers/s")
    print(f"simulate, 1 thread  : {t_one:7.3f} s  {steps / t_one:.3g} steps/s  ratio to drawing {t_one / t_draw:.2f}")
    print(f"pure-Python step    : {t_py:7.1f} s (extrapolated from {n_ref} steps)  numba speed-up {t_py / t_one:.0f}x")
    print(f"dask, 1 thread      : {t_dask1:7.3f} s")
    print(f"dask, 2 threads     : {t_dask2:7.3f} s  speed-up {t_dask1 / t_dask2:.2f}x")


if __name__ == "__main__":
    main()

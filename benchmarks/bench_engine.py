"""Time one signature job of the `large` scene on each Dask engine, and project a cluster run.

A plain script (not a test): prints timings and ratios, never asserts them.

    python benchmarks/bench_engine.py [--part 0] [--repeat 2]

One job of the `large` scene (config/config.yaml: `replicates_per_job` replicates of
`series_per_replicate` series, simulated from their seeds and reduced to signature sums,
:func:`rockdec.pipeline.replicates.scene_cubes`) runs on the ``threads`` engine with 1 and 2
workers and on a local ``dask.distributed`` cluster (``processes:N``) with 1 and 2 worker
processes (cluster start-up included). Every engine gives the same sums bit for bit (checked
here too). The projection: the scene's jobs, each on a 2-core cluster node, at the measured
time per job.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from rockdec import engine
from rockdec.pipeline import config, layout, replicates
from rockdec.physics import run


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--part", type=int, default=0)
    parser.add_argument("--repeat", type=int, default=2, help="best of this many runs")
    args = parser.parse_args()
    scene = config.scene(config.load(), "large")
    rec, first = layout.part_records(scene["records"], args.part)
    readings = layout.compared_readings(scene["estimates"])
    contract = run.from_scene(scene)
    n_series = rec["replicates"] * rec["series_per_replicate"]
    print(f"one job of scene large: {rec['replicates']} replicates x {rec['series_per_replicate']} series x "
          f"{rec['n_points']} points ({n_series} series, burn-in {contract.burn_in} steps each)")
    times, reference = {}, None
    for scheduler, threads in (("threads", 1), ("threads", 2), ("processes:1", None), ("processes:2", None)):
        best = np.inf
        for _ in range(args.repeat):
            start = time.perf_counter()
            with engine.session(threads, scheduler):
                cube = replicates.scene_cubes(contract, rec, scene["signatures"], readings, first_replicate=first)[readings[0]]
            best = min(best, time.perf_counter() - start)
        same = reference is None or np.array_equal(cube["signature_sum"].values, reference)
        reference = cube["signature_sum"].values if reference is None else reference
        label = f"{scheduler}" + (f", {threads} worker(s)" if threads else "")
        times[label] = best
        print(f"  {label:<24} {best:7.2f} s   same sums as threads/1: {same}")
    t1, t2 = times["threads, 1 worker(s)"], times["threads, 2 worker(s)"]
    p1, p2 = times["processes:1"], times["processes:2"]
    print(f"  2 vs 1 worker: threads {t1 / t2:.2f} x, processes {p1 / p2:.2f} x")
    jobs = len(layout.signature_parts(scene["records"]))
    print(f"projection: {jobs} jobs of {t2:.1f} s on 2-core nodes: {jobs * t2 / 60:.1f} node-minutes; "
          f"{t2:.0f} s wall with {jobs} nodes, {jobs * t2 / 60:.1f} min on this one machine")


if __name__ == "__main__":
    main()

"""A long record: the signature cube of 1e8 points in time chunks (docs/method.md §4.4; issue 6),
and ``rockdec estimate`` on 2e7 points (issue 21): wall time, CPU time and peak memory.

Step ``write`` simulates one long series block by block (``tests/long_series.py``)
into a NetCDF file, never holding more than one block. Step ``analyse`` (a fresh process so
its peak RSS is its own) opens the file with Dask chunks in time and computes the signature cube
with the overlap handled by :func:`rockdec.rdd.signatures.signature_cube`; it also computes the same
cube on the first ``--check`` points in memory, chunked and whole, and prints their difference.
Step ``estimate`` runs ``rockdec estimate`` on the file (a fresh process, calibration cache
``--cache``; a missing calibration is built) and prints its wall and CPU seconds, the up-front
estimate of :func:`rockdec.estimation.cost` and the answer (true ``e`` 0.95).

Run: ``python benchmarks/long_record.py --points 100000000`` (write, analyse), or
``python benchmarks/long_record.py --points 2e7 --step write`` then ``--step estimate``.
Prints numbers; asserts nothing.
"""

from __future__ import annotations

import argparse
import resource
import subprocess
import sys
import time
from pathlib import Path

import dask
import netCDF4
import numpy as np
import xarray as xr

import tests_path  # noqa: F401  (tests/ on sys.path for long_series)
from long_series import long_series

from rockdec.pipeline import replicates
from rockdec.physics import simulate

DT, G, E, SIGMA_P = 0.003432651166459561, 1.0, 0.95, 0.003
STATS = {"sigma_y": 0.001992454115749987, "sigma_ydot": 0.03410016419092972, "g": G}


def write(path: Path, points: int, chunk: int, seed: int = 0) -> None:
    start = time.perf_counter()
    with netCDF4.Dataset(path, "w") as nc:
        nc.createDimension("seed", 1)
        nc.createDimension("time", points)
        var = nc.createVariable("theta", "f4", ("seed", "time"), zlib=True, complevel=1, chunksizes=(1, min(chunk, points)))
        var.units = "rad"
        nc.dt = DT
        done = 0
        for theta, _ in long_series(seed, points, chunk, dt=DT, g=G, e=E, sigma_p=SIGMA_P, burn_in=8087):
            var[0, done : done + theta.size] = theta
            done += theta.size
            print(f"\rwritten {done / points:6.1%}", end="", file=sys.stderr)
    print(file=sys.stderr)
    print(f"write: {points:.3g} points in {time.perf_counter() - start:.1f} s, {path.stat().st_size / 2**20:.0f} MiB on disk")


def cube(theta):
    scene = {"signatures": {"level": 2.0, "windows": [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0], "window_max": 0.28,
                            "v_level": 1.0, "dv_max": 0.28, "n_periods": 2.5, "both_signs": True}}
    return replicates.scene_signatures(theta, scene, STATS, np.zeros(theta.sizes["seed"], dtype=int), [0])


def analyse(path: Path, chunk: int, threads: int, check: int) -> None:
    start = time.perf_counter()
    with xr.open_dataset(path, chunks={"time": chunk}) as ds:
        theta = ds["theta"].astype(np.float64)
        theta.attrs["dt"] = DT
        with dask.config.set(scheduler="threads", num_workers=threads):
            result = cube(theta).compute()
        elapsed = time.perf_counter() - start
        small = ds["theta"].isel(time=slice(0, check)).astype(np.float64).load()
    small.attrs["dt"] = DT
    whole = cube(small)
    chunked = cube(small.chunk({"time": check // 7}))
    with dask.config.set(scheduler="sync"):
        chunked = chunked.compute()
    diff = float(np.nanmax(np.abs(whole["signature"].values - chunked["signature"].values)))
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    counts = result["count"].sel(trigger="a").values.ravel()
    print(f"analyse: {ds.sizes['time']:.3g} points in {elapsed:.1f} s with {threads} threads, chunks of {chunk:.3g}")
    print(f"peak RSS {peak:.0f} MiB; D_a triggers per window {counts}")
    print(f"chunked vs whole on the first {check:.3g} points: max |difference| of the signature {diff:.3g} rad")


def estimate(path: Path, cache: Path) -> None:
    import json
    import os

    from rockdec import estimation

    with xr.open_dataset(path) as ds:
        points = ds.sizes["time"]
    before, start = os.times(), time.perf_counter()
    out = subprocess.run([sys.executable, "-m", "rockdec", "estimate", str(path), "--json", "--cache", str(cache)],
                         capture_output=True, text=True, check=True)
    wall, after = time.perf_counter() - start, os.times()
    cpu = (after.children_user - before.children_user) + (after.children_system - before.children_system)
    peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    res = json.loads(out.stdout)
    print(out.stderr, file=sys.stderr)
    print(f"estimate: {points:.3g} points, wall {wall:.1f} s, CPU {cpu:.1f} s, peak RSS {peak:.0f} MiB; "
          f"up-front estimate {estimation.cost(points, False, False)[0]:.0f} s; calibration {res['calibration']}")
    print(f"e = {res['e']} ({res['estimator']}), 95 % interval {res['interval']} (true {E}); warnings {res['warnings']}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=float, default=1e8)
    parser.add_argument("--chunk", type=float, default=2e6)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--check", type=float, default=2e6)
    parser.add_argument("--file", default="/tmp/rockdec_long_record.nc")
    parser.add_argument("--step", choices=["all", "write", "analyse", "estimate"], default="all")
    parser.add_argument("--cache", default="/tmp/rockdec_long_record_cache")
    parser.add_argument("--seed", type=int, default=0, help="seed of the record written")
    args = parser.parse_args()
    path, points, chunk = Path(args.file), int(args.points), int(args.chunk)
    if args.step in ("all", "write"):
        write(path, points, chunk, args.seed)
    if args.step == "all":
        cmd = [sys.executable, __file__, "--step", "analyse", "--file", str(path), "--chunk", str(chunk),
               "--threads", str(args.threads), "--check", str(args.check)]
        subprocess.run(cmd, check=True)
    elif args.step == "analyse":
        analyse(path, chunk, args.threads, int(args.check))
    elif args.step == "estimate":
        estimate(path, Path(args.cache))


if __name__ == "__main__":
    main()

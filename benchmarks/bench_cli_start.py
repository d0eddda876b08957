"""Time how fast the ``rockdec`` command answers, against a bare Python start, in one run.

A plain script (not a test): prints timings and ratios, never asserts them.

    python benchmarks/bench_cli_start.py [--repeat 15]

Each case runs in a fresh interpreter (``python -m rockdec ...``), ``--repeat`` times in
turn with the others; the median and the fastest wall time are printed with their ratio to
``python -c pass`` (the floor every command pays) and the extra milliseconds over it. For
scale, the last case imports the numerical modules a command loads once it runs
(``rockdec.estimation``: numpy, scipy, numba; no xarray, pandas or Dask, which load only
where a function needs them), which ``--version``, ``--help`` and a refused option do not
wait for. ``bench_estimate.py`` times a whole warm ``rockdec estimate``.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time

CASES = {
    "python -c pass": ["-c", "pass"],
    "rockdec --version": ["-m", "rockdec", "--version"],
    "rockdec --help": ["-m", "rockdec", "--help"],
    "rockdec estimate --help": ["-m", "rockdec", "estimate", "--help"],
    "rockdec simulate --bogus (refused)": ["-m", "rockdec", "simulate", "--out", "x.nc", "--bogus"],
    "rockdec simulate --e 2 (refused value)": ["-m", "rockdec", "simulate", "--out", "x.nc", "--e", "2"],
    "import of a running command": ["-c", "import rockdec.cli, rockdec.estimation"],
}


def wall(args: list[str]) -> float:
    start = time.perf_counter()
    subprocess.run([sys.executable, *args], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=15, help="runs of each case (interleaved)")
    args = parser.parse_args()
    for case in CASES.values():  # warm the file cache and the bytecode
        wall(case)
    times = {name: [] for name in CASES}
    for _ in range(args.repeat):
        for name, case in CASES.items():
            times[name].append(wall(case))
    floor = statistics.median(times["python -c pass"])
    print(f"{'case':<36} {'median s':>9} {'best s':>8} {'x python':>9} {'+ ms':>7}")
    for name, runs in times.items():
        median = statistics.median(runs)
        print(f"{name:<36} {median:9.3f} {min(runs):8.3f} {median / floor:9.1f} {1000 * (median - floor):7.0f}")


if __name__ == "__main__":
    main()

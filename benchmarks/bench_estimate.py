"""Warm ``rockdec estimate`` (its calibration cached) against the analysis alone, in one run.

A plain script (not a test): prints timings and ratios, never asserts them.

    PYTHONPATH=src python benchmarks/bench_estimate.py [--samples 200000] [--repeat 5]

1. A simulated record of ``--samples`` samples at e = 0.85 (as ``tests/calibrate/test_estimate.py``
   makes them) is written as a CSV file, and its calibration built once into a temporary
   cache (``rockdec estimate``: the cold run, timed for scale).
2. **The command**: ``python -m rockdec estimate record.csv --cache DIR`` in a fresh
   interpreter, ``--repeat`` times: wall and CPU seconds (the child's ``user + sys``), and
   which of the heavy libraries it loaded (xarray, pandas, Dask, matplotlib).
3. **The analysis alone**, in this process with everything imported and numba's kernels
   loaded: reading the record and :func:`rockdec.rdd.measured.analyse` on it; and the whole
   estimate in process (:func:`rockdec.calibrate.inference.estimate`: analysis, cached calibration,
   belts), ``--repeat`` times each.

The ratio command / analysis is what starting Python, importing and loading the kernels
cost on top of the work; the import of the modules the command runs is timed alone too.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HEAVY = ("xarray", "pandas", "dask", "matplotlib")

PROBE = """
import sys
from rockdec.cli import main
code = main(sys.argv[1:])
print("loaded:", *[m for m in {heavy!r} if m in sys.modules], file=sys.stderr)
"""


def record(path: Path, n: int) -> Path:
    """A simulated record at e = 0.85 of ``n`` samples, written as ``time,theta``."""
    import numpy as np

    from rockdec.physics.simulate import calibrate_dt, simulate_block

    g, sigma_p, e = 1.0, 0.003, 0.85
    cal = calibrate_dt(e=e, g=g, sigma_p=sigma_p, points_per_cycle=75)
    theta, _ = simulate_block([11], n, dt=cal["dt"], g=g, e=e, sigma_p=sigma_p, burn_in=cal["burn_in"])
    np.savetxt(path, np.c_[np.arange(n) * cal["dt"], theta[0]], delimiter=",", header="time,theta", comments="", fmt="%.10g")
    return path


def child(args: list[str]) -> tuple[float, float, str]:
    """Wall and CPU seconds of ``python *args`` and its standard error."""
    start = time.perf_counter()
    proc = subprocess.Popen([sys.executable, *args], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    err = proc.stderr.read()
    _, status, usage = os.wait4(proc.pid, 0)
    if os.waitstatus_to_exitcode(status) != 0:
        sys.exit(f"python {' '.join(args)} failed:\n{err}")
    return time.perf_counter() - start, usage.ru_utime + usage.ru_stime, err


def timed(fn, repeat: int) -> tuple[float, float]:
    """Median wall and CPU seconds of ``fn()`` over ``repeat`` calls."""
    walls, cpus = [], []
    for _ in range(repeat):
        start, cpu = time.perf_counter(), time.process_time()
        fn()
        walls.append(time.perf_counter() - start)
        cpus.append(time.process_time() - cpu)
    return statistics.median(walls), statistics.median(cpus)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=200_000, help="samples of the record (default %(default)s)")
    parser.add_argument("--repeat", type=int, default=5, help="runs of each case (default %(default)s)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="rockdec_bench_estimate_") as folder:
        csv, cache = record(Path(folder) / "record.csv", args.samples), Path(folder) / "cache"
        command = ["-m", "rockdec", "estimate", str(csv), "--cache", str(cache), "--yes"]
        cold = child(command)
        runs = [child(["-c", PROBE.format(heavy=HEAVY), *command[2:]]) for _ in range(args.repeat)]
        imports = [child(["-c", "import rockdec.cli, rockdec.calibrate.inference"]) for _ in range(args.repeat)]

        from rockdec.calibrate import inference
        from rockdec.rdd import measured
        from rockdec.record import records

        def read():
            return records.read_records(csv)

        def analysis():
            recs = read()
            measured.analyse([r.theta for r in recs], recs[0].dt)

        def whole():
            inference.estimate(read(), cache_dir=cache)

        whole()  # numba's kernels and the libraries loaded before timing
        analysis_s = timed(analysis, args.repeat)
        whole_s = timed(whole, args.repeat)
    command_s = statistics.median(r[0] for r in runs), statistics.median(r[1] for r in runs)
    import_s = statistics.median(r[0] for r in imports), statistics.median(r[1] for r in imports)
    loaded = runs[-1][2].split("loaded:", 1)[1].strip()
    print(f"record: {args.samples} samples (CSV); medians of {args.repeat} runs\n")
    print(f"| case | wall s | CPU s |\n|---|---:|---:|")
    print(f"| cold `rockdec estimate` (builds the calibration) | {cold[0]:.2f} | {cold[1]:.2f} |")
    print(f"| warm `rockdec estimate` (calibration cached), fresh interpreter | {command_s[0]:.2f} | {command_s[1]:.2f} |")
    print(f"| import of rockdec.cli and rockdec.calibrate.inference, fresh interpreter | {import_s[0]:.2f} | {import_s[1]:.2f} |")
    print(f"| in process: read + rockdec.calibrate.inference.estimate (cached) | {whole_s[0]:.3f} | {whole_s[1]:.3f} |")
    print(f"| in process: read + rockdec.rdd.measured.analyse (the analysis alone) | {analysis_s[0]:.3f} | {analysis_s[1]:.3f} |")
    print(f"\nwarm command / analysis alone: {command_s[0] / analysis_s[0]:.2f} (wall), {command_s[1] / analysis_s[1]:.2f} (CPU)")
    print(f"warm command / estimate in process: {command_s[0] / whole_s[0]:.2f} (wall), {command_s[1] / whole_s[1]:.2f} (CPU)")
    print(f"heavy libraries the warm command loaded: {loaded or 'none'} (of {', '.join(HEAVY)})")


if __name__ == "__main__":
    main()

"""``rockdec estimate`` cold (calibration built) and warm (calibration cached) against the analysis alone, in one run.

A plain script (not a test): prints timings and ratios, never asserts them.

    PYTHONPATH=src python benchmarks/bench_estimate.py [--samples 200000] [--noise 0.03] [--repeat 5] [--cold 2] [--before OTHER/src]

1. A simulated record of ``--samples`` samples at e = 0.85 (as ``tests/calibrate/test_estimate.py``
   makes them; with ``--noise``, plus white sensor noise of that fraction of its rms) is
   written as a CSV file.
2. **Cold**: ``python -m rockdec estimate record.csv --cache DIR`` in a fresh interpreter with an
   empty cache, ``--cold`` times: it builds the calibration.
3. **Warm**: the same command with the calibration cached, ``--repeat`` times.
4. **Floors**, each in a fresh interpreter: importing the modules the command runs; reading
   the record and :func:`rockdec.rdd.measured.analyse` on it (what any estimate must do:
   Python, NumPy, numba and its kernels loaded from the cache, the analysis); and, in a
   process that has everything loaded, the analysis alone and the whole estimate
   (:func:`rockdec.estimation.estimate`, cached calibration), and the analysis and
   :func:`rockdec.record.record_measure.measure` on the record already read, medians of ``--repeat``.

5. **The cold build split**: a cold estimate in one process, the CPU seconds of each
   calibration grid-point task summed per Dask thread; the cold command's CPU less the
   tasks' is its serial part, so on idle cores it takes about that part plus the busiest
   thread's.

Wall seconds and CPU seconds (the child's ``user + sys``, every thread) of each. With
``--before`` the same cases run on a second source tree (``PYTHONPATH`` set to it), the two
trees alternating run by run so that both see the same load on a shared machine; the warm
answers of the two (``e``, interval, estimator, the selection and every estimator's value)
are compared. The ratios within one run are the result; absolute seconds on a shared
machine are not.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
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

FLOOR = """
import sys
from rockdec.record import records
from rockdec.rdd import measured
recs = records.read_records(sys.argv[1])
measured.analyse([r.theta for r in recs], recs[0].dt)
"""

IN_PROCESS = """
import json, statistics, sys, time
from rockdec import estimation
from rockdec.report.estimate_report import document
from rockdec.rdd import measured
from rockdec.record import records

def timed(fn, repeat):
    walls, cpus = [], []
    for _ in range(repeat):
        start, cpu = time.perf_counter(), time.process_time()
        fn()
        walls.append(time.perf_counter() - start)
        cpus.append(time.process_time() - cpu)
    return statistics.median(walls), statistics.median(cpus)

def analysis():
    recs = records.read_records(sys.argv[1])
    measured.analyse([r.theta for r in recs], recs[0].dt)

def whole():
    document(estimation.estimate(records.read_records(sys.argv[1]), cache_dir=sys.argv[2]))

recs = records.read_records(sys.argv[1])

def model():
    estimation.measure_model(recs, recs[0].dt)

def analysis_only():
    measured.analyse([r.theta for r in recs], recs[0].dt)

whole()  # numba's kernels and the libraries loaded before timing
n = int(sys.argv[3])
print(json.dumps({"analysis": timed(analysis, n), "estimate": timed(whole, n), "model": timed(model, n), "analyse": timed(analysis_only, n)}))
"""


COLD_SPLIT = """
import json, sys, tempfile, threading, time
from rockdec.calibrate import calibration
from rockdec import estimation
from rockdec.record import records

tasks = []
grid_point = calibration._grid_point

def timed_grid_point(*args):
    cpu = time.thread_time()
    out = grid_point(*args)
    tasks.append((threading.get_ident(), time.thread_time() - cpu))
    return out

calibration._grid_point = timed_grid_point
cpu = time.process_time()
with tempfile.TemporaryDirectory() as cache:
    estimation.estimate(records.read_records(sys.argv[1]), cache_dir=cache)
per_thread = {}
for thread, seconds in tasks:
    per_thread[thread] = per_thread.get(thread, 0.0) + seconds
print(json.dumps({"process": time.process_time() - cpu, "tasks": len(tasks), "threads": sorted(per_thread.values())}))
"""


def record(path: Path, n: int, noise: float = 0.0) -> Path:
    """A simulated record at e = 0.85 of ``n`` samples, plus white sensor noise of ``noise``
    times its rms, written as ``time,theta``."""
    import numpy as np

    from rockdec.physics.loading import add_sensor_noise
    from rockdec.physics.simulate import calibrate_dt, simulate_block

    g, sigma_p, e = 1.0, 0.003, 0.85
    cal = calibrate_dt(e=e, g=g, sigma_p=sigma_p, points_per_cycle=75)
    theta, _ = simulate_block([11], n, dt=cal["dt"], g=g, e=e, sigma_p=sigma_p, burn_in=cal["burn_in"])
    add_sensor_noise(theta, [11], noise * float(np.sqrt(np.mean(theta[0] ** 2))))
    np.savetxt(path, np.c_[np.arange(n) * cal["dt"], theta[0]], delimiter=",", header="time,theta", comments="", fmt="%.10g")
    return path


def child(args: list[str], src: str) -> tuple[float, float, str, str]:
    """Wall and CPU seconds of ``python *args`` with ``src`` first on the path (CPU: the
    child's ``user + sys``, every thread), its standard output and its standard error."""
    env = {**os.environ, "PYTHONPATH": src}
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    proc = subprocess.run([sys.executable, *args], capture_output=True, text=True, env=env)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        sys.exit(f"python {' '.join(args)} failed:\n{proc.stderr}")
    cpu = after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime
    return wall, cpu, proc.stdout, proc.stderr


def answer(out: str) -> dict:
    """What an estimate answers (JSON of ``rockdec estimate --json``): the parts compared between trees."""
    res = json.loads(out)
    return {
        "e": res["e"], "interval": res["interval"], "estimator": res["estimator"], "selection": res["selection"],
        "estimators": {k: (v["e"], v["interval"], v["raw"]) for k, v in res["estimators"].items()},
        "g": res["g"], "g_interval": res["g_interval"], "record_model": res["record_model"]["simulated"]["described"],
    }


def median(runs, k: int) -> float:
    return statistics.median(r[k] for r in runs)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=200_000, help="samples of the record (default %(default)s)")
    parser.add_argument("--noise", type=float, default=0.0, help="sensor noise of the record in its rms (default %(default)s)")
    parser.add_argument("--repeat", type=int, default=5, help="warm runs and floors of each tree (default %(default)s)")
    parser.add_argument("--cold", type=int, default=2, help="cold runs of each tree, each in an empty cache (default %(default)s)")
    parser.add_argument("--before", help="a second source tree (its src folder) to time alongside, e.g. a checkout of main")
    args = parser.parse_args()
    trees = {"this": str(Path(__file__).resolve().parents[1] / "src")}
    if args.before:
        trees["before"] = str(Path(args.before).resolve())
    runs: dict[str, dict[str, list]] = {t: {k: [] for k in ("cold", "warm", "import", "floor", "inproc")} for t in trees}
    answers = {}
    with tempfile.TemporaryDirectory(prefix="rockdec_bench_estimate_") as folder:
        csv = record(Path(folder) / "record.csv", args.samples, args.noise)
        caches = {t: Path(folder) / f"cache-{t}" for t in trees}

        def command(tree, cache):
            return ["-c", PROBE.format(heavy=HEAVY), "estimate", str(csv), "--cache", str(cache), "--yes", "--json"]

        for i in range(args.cold):
            for t, src in trees.items():
                runs[t]["cold"].append(child(command(t, Path(folder) / f"cold-{t}-{i}"), src))
        for t, src in trees.items():
            child(command(t, caches[t]), src)  # builds the cache of the warm runs
        for _ in range(args.repeat):
            for t, src in trees.items():
                runs[t]["warm"].append(child(command(t, caches[t]), src))
                runs[t]["import"].append(child(["-c", "import rockdec.cli, rockdec.estimation"], src))
                runs[t]["floor"].append(child(["-c", FLOOR, str(csv)], src))
        for t, src in trees.items():
            runs[t]["inproc"] = json.loads(child(["-c", IN_PROCESS, str(csv), str(caches[t]), str(args.repeat)], src)[2])
            runs[t]["split"] = json.loads(child(["-c", COLD_SPLIT, str(csv)], src)[2])
            answers[t] = answer(runs[t]["warm"][-1][2])

    print(f"record: {args.samples} samples (CSV); cold: medians of {args.cold} runs, the rest medians of {args.repeat}")
    print(f"load average at the end: {' '.join(f'{x:.1f}' for x in os.getloadavg())} on {os.cpu_count()} cores\n")
    head = " | ".join(f"{t} wall s | {t} CPU s" for t in trees)
    print(f"| case | {head} |\n|---|" + "---:|" * (2 * len(trees)))
    rows = [
        ("cold `rockdec estimate` (builds the calibration), fresh interpreter", "cold"),
        ("warm `rockdec estimate` (calibration cached), fresh interpreter", "warm"),
        ("import of rockdec.cli and rockdec.estimation, fresh interpreter", "import"),
        ("read + rockdec.rdd.measured.analyse, fresh interpreter (the floor of any estimate)", "floor"),
    ]
    for label, key in rows:
        print(f"| {label} | " + " | ".join(f"{median(runs[t][key], 0):.2f} | {median(runs[t][key], 1):.2f}" for t in trees) + " |")
    for label, key in (
        ("in process: read + estimation.estimate (cached)", "estimate"),
        ("in process: read + measured.analyse (the analysis alone)", "analysis"),
        ("in process: measured.analyse, the record already read", "analyse"),
        ("in process: record_measure.measure (the record's model), the record already read", "model"),
    ):
        print(f"| {label} | " + " | ".join(f"{runs[t]['inproc'][key][0]:.3f} | {runs[t]['inproc'][key][1]:.3f}" for t in trees) + " |")
    print()
    for t in trees:
        warm, cold, floor = (median(runs[t][k], 0) for k in ("warm", "cold", "floor"))
        warm_cpu, cold_cpu, floor_cpu = (median(runs[t][k], 1) for k in ("warm", "cold", "floor"))
        alone = runs[t]["inproc"]["analysis"]
        print(
            f"{t}: warm / fresh-interpreter floor {warm / floor:.2f} (wall), {warm_cpu / floor_cpu:.2f} (CPU); "
            f"warm / analysis alone {warm / alone[0]:.1f} (wall), {warm_cpu / alone[1]:.1f} (CPU); "
            f"cold / analysis alone {cold / alone[0]:.0f} (wall), {cold_cpu / alone[1]:.0f} (CPU); "
            f"cold CPU / wall {cold_cpu / cold:.2f}"
        )
        split = runs[t]["split"]
        busiest = max(split["threads"])
        serial = cold_cpu - sum(split["threads"])
        print(
            f"{t}: the calibration's {split['tasks']} grid-point tasks ran on {len(split['threads'])} threads, CPU s per thread "
            f"{', '.join(f'{x:.2f}' for x in split['threads'])} (in a cold estimate in process); the rest of the cold command "
            f"{serial:.2f} s of CPU: on idle cores about {serial:.2f} + {busiest:.2f} = {serial + busiest:.1f} s"
        )
        loaded = runs[t]["warm"][-1][3].split("loaded:", 1)[1].strip()
        print(f"{t}: heavy libraries the warm command loaded: {loaded or 'none'} (of {', '.join(HEAVY)})")
    if args.before:
        print(f"\nwarm / warm before: {median(runs['this']['warm'], 0) / median(runs['before']['warm'], 0):.2f} (wall), "
              f"{median(runs['this']['warm'], 1) / median(runs['before']['warm'], 1):.2f} (CPU); "
              f"cold / cold before: {median(runs['this']['cold'], 0) / median(runs['before']['cold'], 0):.2f} (wall), "
              f"{median(runs['this']['cold'], 1) / median(runs['before']['cold'], 1):.2f} (CPU)")
        same = answers["this"] == answers["before"]
        print("answers (e, interval, estimator, selection, every estimator, g): " + ("identical" if same else "DIFFER"))
        if not same:
            for key in answers["this"]:
                if answers["this"][key] != answers["before"][key]:
                    print(f"  {key}: this {answers['this'][key]} / before {answers['before'][key]}")


if __name__ == "__main__":
    main()

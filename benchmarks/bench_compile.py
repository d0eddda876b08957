"""What a first run on a fresh install compiles: numba's CPU seconds per family of kernels.

A plain script (not a test): prints CPU seconds, never asserts them.

    PYTHONPATH=src python benchmarks/bench_compile.py [--repeat 2] [--before OTHER/src]

Each family is timed in a fresh interpreter whose numba cache (``NUMBA_CACHE_DIR``) is an
empty temporary folder, on one thread: the CPU seconds of the first call of the family's
entry point (numba compiles its kernels and writes them to the cache), then of its compiled
kernels on a larger load (``work()``, about 0.2 s of CPU each, the best of three), so that a
change that compiles faster is seen not to run slower. The families, in the order a cold
``rockdec estimate`` meets them:

``numba's start``
    a one-line kernel: numba's compiler and LLVM target, paid once by the first kernel of a process;
``simulation``
    :func:`rockdec.physics.simulate.simulate_block` (the exact integrator, eqs. 21-24; its
    work: :func:`rockdec.physics.simulate.integrate` over 4e6 steps);
``signatures``
    :func:`rockdec.rdd.signatures.trigger_sums` on float64 records (both triggers of eq. 19);
``analysis``
    :func:`rockdec.rdd.measured.analyse` with the kernels above already compiled: the
    estimators of eqs. 25-27, ``e_v`` and ``g`` (its work:
    :func:`rockdec.rdd.estimators.window_estimates` on 3200 rows of signatures);
``record checks``
    :func:`rockdec.record.diagnostics.sums` (the checks of a measured record and of the
    calibration's sets; the record's model, :mod:`rockdec.record.record_measure`, is NumPy).

Each later family runs after the earlier ones in its interpreter, the earlier ones compiled
there but not counted, so a kernel two families share is counted once, in the first. With
``--before`` the same runs on a second source tree, the two trees alternating, so that both
see the same load on a shared machine, and the ratio of the compiled work of the two is
printed. Prints the middle run of ``--repeat`` (the later of two).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

FAMILIES = ("numba's start", "simulation", "signatures", "analysis", "record checks")

CHILD = r"""
import json, sys, time
import numpy as np
import numba
from rockdec.physics import simulate
from rockdec.physics.simulate import simulate_block
from rockdec.rdd import estimators, measured, signatures
from rockdec.record import diagnostics

DT = 0.0034
LEVELS = dict(a=0.004, a_widths=np.array([0.0005, 0.001]), v=0.03, v_widths=np.array([0.005, 0.01]), dt=DT, both_signs=True)

def start():
    numba.njit(lambda x: x + 1.0)(1.0)

def simulation():
    return simulate_block([1, 2], 20000, dt=DT, g=1.0, e=0.9, sigma_p=0.003, burn_in=2000)[0]

y = None

def signature_kernels():
    return signatures.trigger_sums(y, **LEVELS, n_lag=200)

def analysis():
    return measured.analyse([y[0]], DT)

def record_checks():
    return diagnostics.sums([y[0]])

def work():
    # the compiled kernels on a larger load, each about 0.2 s of CPU
    big = simulate_block(range(16), 100000, dt=DT, g=1.0, e=0.9, sigma_p=0.003, burn_in=2000)[0]
    impulses = np.random.default_rng(1).normal(0.0, 0.003, 4_000_000)
    theta, omega = np.empty(impulses.size + 1), np.empty(impulses.size + 1)
    sums, counts, _ = signatures.trigger_sums(big, **LEVELS, n_lag=200)
    sums, counts = np.tile(sums, (100, 1, 1, 1)), np.tile(counts, (100, 1, 1))
    repeat = lambda call, times: lambda: [call() for _ in range(times)]
    return [
        lambda: None,
        repeat(lambda: simulate.integrate(impulses, DT, 1.0, 0.9, 0.0, 0.0, 0, theta, omega, False), 8),
        repeat(lambda: signatures.trigger_sums(big, **LEVELS, n_lag=200), 8),
        repeat(lambda: estimators.window_estimates(sums, counts, DT), 16),
        repeat(lambda: diagnostics.sums(list(big)), 30),
    ]

steps = [start, simulation, signature_kernels, analysis, record_checks]
target = int(sys.argv[1])
times = {}
for k, step in enumerate(steps[: target + 1]):
    t = time.process_time()
    out = step()
    first = time.process_time() - t
    if k == 1:
        y = out
    if k == target:
        timed = work()[k]
        runs = []
        for _ in range(3):
            t = time.process_time()
            timed()
            runs.append(time.process_time() - t)
        times = {"first": first, "work": min(runs)}
print(json.dumps(times))
"""


def family(index: int, src: str) -> dict:
    """First call and compiled work of family ``index`` in a fresh interpreter with an empty numba cache."""
    with tempfile.TemporaryDirectory(prefix="rockdec_numba_") as cache:
        env = {**os.environ, "PYTHONPATH": src, "NUMBA_CACHE_DIR": cache, "NUMBA_NUM_THREADS": "1"}
        out = subprocess.run([sys.executable, "-c", CHILD, str(index)], env=env, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=2, help="runs of each family (default %(default)s)")
    parser.add_argument("--before", help="another source tree (its src/), timed in the same run")
    args = parser.parse_args()
    trees = {"this tree": str(Path(__file__).resolve().parents[1] / "src")} | ({"before": args.before} if args.before else {})
    firsts = {label: {name: [] for name in FAMILIES} for label in trees}
    for k in range(args.repeat):
        for label in (list(trees) if k % 2 == 0 else list(trees)[::-1]):
            for index, name in enumerate(FAMILIES):
                firsts[label][name].append(family(index, trees[label]))

    def middle(label, name, key):
        runs = sorted(r[key] for r in firsts[label][name])
        return runs[len(runs) // 2]

    print("| family | " + " | ".join(f"{label}: first call CPU s | {label}: compiled work CPU s" for label in trees)
          + (" | compiled work, this tree / before |" if len(trees) == 2 else " |"))
    print("|---|" + "---:|---:|" * len(trees) + ("---:|" if len(trees) == 2 else ""))
    for name in FAMILIES[1:]:
        cells = [f"{middle(label, name, 'first'):.2f} | {middle(label, name, 'work'):.3f}" for label in trees]
        if len(trees) == 2:
            cells.append(f"{middle('this tree', name, 'work') / middle('before', name, 'work'):.3f}")
        print(f"| {name} | " + " | ".join(cells) + " |")
    for label in trees:
        total = sum(middle(label, name, "first") for name in FAMILIES)
        print(f"{label}: numba's start {middle(label, FAMILIES[0], 'first'):.2f} s, {total:.2f} s of CPU compiling in all")


if __name__ == "__main__":
    main()

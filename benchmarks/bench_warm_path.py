"""A warm ``rockdec estimate --json`` against a plain analysis of the same record, fresh processes, in one run.

A plain script (not a test): prints timings and ratios, never asserts them.

    PYTHONPATH=src python benchmarks/bench_warm_path.py [--samples 200000] [--repeat 7] [--record FILE.csv]
        [--cache DIR] [--before OTHER/src]

1. The record: ``--record`` (a CSV ``time,theta``), or one simulated at e = 0.85 of
   ``--samples`` samples (``bench_estimate.record``) written as a CSV file.
2. The calibration: one cold ``rockdec estimate`` of each tree builds it in ``--cache`` (kept,
   so that a second run of this benchmark is warm from the start) or in a temporary folder.
3. ``--repeat`` rounds, each in fresh interpreters and in turn: ``python -m rockdec estimate
   RECORD --json --cache DIR --yes`` of this tree (and of ``--before``'s), then the plain
   analysis (:data:`PLAIN`): the record read by ``numpy.loadtxt``, its signatures by the
   tests' one-window-at-a-time reference (``tests/reference_signatures.py``), ``g`` off the
   largest window's free response, every estimator at every window by the tests' NumPy
   reference (``tests/reference_estimators.py``) and the line to zero window: what any
   program that reads such a record and analyses it must do, with none of the estimate's
   checks, record model or calibration.

Printed: each command's median wall and CPU seconds (the child's ``user + sys``) and the
median of the ratios warm / plain taken round by round (pairing keeps the ratio meaningful
when the load of a shared machine drifts); with ``--before``, the same for the other tree
and whether the two trees' JSON answers are byte-identical once the calibration's own
fields (its file name, which the source's fingerprint sets, and the seconds it took to
load) are left out.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
from pathlib import Path

from bench_estimate import child, record

TESTS = Path(__file__).resolve().parents[1] / "tests"

#: The plain analysis of a CSV record ``time,theta`` (argv: the record, the tests' folder).
PLAIN = """
import sys
import numpy as np
sys.path.insert(0, sys.argv[2])
from reference_estimators import reference_estimate_all
from reference_signatures import reference_per_window
from rockdec.rdd import signatures
from rockdec.rdd.estimators import extrapolate_to_zero
from rockdec.rdd.registry import ESTIMATORS

data = np.loadtxt(sys.argv[1], delimiter=",", skiprows=1)
dt = (data[-1, 0] - data[0, 0]) / (len(data) - 1)
y = data[:, 1] - data[:, 1].mean()
windows = np.asarray(signatures.DEFAULT_WINDOWS)
levels = signatures.trigger_levels(np.sqrt(np.mean(y**2)), np.sqrt(np.mean((np.diff(y) / dt) ** 2)), level=2.0,
                                   windows=windows, window_max=0.28, v_level=1.0, dv_max=0.28)
crossings = np.count_nonzero(np.diff(np.signbit(y)))
s = reference_per_window(y, "a", levels["a"], levels["a_widths"][-1:], int(np.ceil(4 * y.size / crossings)))
r = signatures.free_response(s.sum[-1] / s.count[-1])
k = np.flatnonzero(r <= 0.0)[0]
g = 2.0 * r[0] / ((k - 1 + r[k - 1] / (r[k - 1] - r[k])) * dt) ** 2
n_lag = signatures.lag_samples(2.5, levels["a"], g, dt)
sa = reference_per_window(y, "a", levels["a"], levels["a_widths"], n_lag, dt=dt)
sv = reference_per_window(y, "v", levels["v"], levels["v_widths"], n_lag, dt=dt)
rows = [reference_estimate_all(signatures.free_response(sa.sum[w] / sa.count[w]), sv.sum[w] / sv.count[w], dt)
        for w in range(windows.size)]
print({name: round(extrapolate_to_zero(windows, np.array([row[name].value for row in rows])).value, 4) for name in ESTIMATORS})
"""


def estimate_command(csv: Path, cache: Path) -> list[str]:
    return ["-m", "rockdec", "estimate", str(csv), "--cache", str(cache), "--yes", "--json"]


def answer(out: str) -> str:
    """The JSON of ``rockdec estimate --json`` without the calibration's file name and load
    time, as canonical text."""
    doc = json.loads(out)
    for key in ("file", "seconds"):
        doc["calibration"].pop(key, None)
    return json.dumps(doc, indent=2)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=200_000, help="samples of the simulated record (default %(default)s)")
    parser.add_argument("--record", type=Path, help="a CSV record time,theta instead of a simulated one")
    parser.add_argument("--repeat", type=int, default=7, help="rounds (default %(default)s)")
    parser.add_argument("--cache", type=Path, help="the calibration folder, kept (default: a temporary one)")
    parser.add_argument("--before", help="a second source tree (its src folder) to time alongside, e.g. a checkout of main")
    args = parser.parse_args()
    trees = {"this": str(Path(__file__).resolve().parents[1] / "src")}
    if args.before:
        trees["before"] = str(Path(args.before).resolve())
    with tempfile.TemporaryDirectory(prefix="rockdec_bench_warm_") as folder:
        csv = args.record or record(Path(folder) / "record.csv", args.samples)
        cache = args.cache or Path(folder) / "cache"
        for src in trees.values():
            child(estimate_command(csv, cache), src)  # builds the calibration if it is missing
        runs: dict[str, list] = {**{t: [] for t in trees}, "plain": []}
        for _ in range(args.repeat):
            for t, src in trees.items():
                runs[t].append(child(estimate_command(csv, cache), src))
            runs["plain"].append(child(["-c", PLAIN, str(csv), str(TESTS)], trees["this"]))
    print(f"record: {args.record or f'{args.samples} samples simulated at e = 0.85, CSV'}; medians of {args.repeat} rounds")
    print(f"load average at the end: {' '.join(f'{x:.1f}' for x in os.getloadavg())} on {os.cpu_count()} cores\n")
    print("| command, fresh interpreter | wall s | CPU s | wall / plain (paired) | CPU / plain (paired) |\n|---|---:|---:|---:|---:|")
    for t in (*trees, "plain"):
        label = "plain analysis (reference kernels)" if t == "plain" else f"warm `rockdec estimate --json`, {t} tree"
        wall, cpu = (statistics.median(r[k] for r in runs[t]) for k in (0, 1))
        ratios = [statistics.median(a[k] / b[k] for a, b in zip(runs[t], runs["plain"])) for k in (0, 1)]
        print(f"| {label} | {wall:.2f} | {cpu:.2f} | {ratios[0]:.2f} | {ratios[1]:.2f} |")
    print(f"\nplain analysis answered: {runs['plain'][-1][2].strip()}")
    if args.before:
        answers = {t: answer(runs[t][-1][2]) for t in trees}
        print("answers of the two trees (JSON without the calibration's file and load time): "
              + ("byte-identical" if answers["this"] == answers["before"] else "DIFFER"))


if __name__ == "__main__":
    sys.exit(main())

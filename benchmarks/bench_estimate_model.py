"""``rockdec estimate`` with the record's measured model against the paper's model, in one run.

A plain script (not a test): prints coverage, bias and timings, never asserts them.

    python benchmarks/bench_estimate_model.py [--records 20] [--cache DIR] [--out results.jsonl]

Records of a known ``e`` (default 0.9, 200,000 samples, ``g = sigma_p = 1``) are simulated
under four conditions (clean; sensor noise of 3 % of ``sigma_Y``; a low-pass load with its
corner at the rocking frequency; that load with 2 % noise) by
:func:`rockdec.physics.simulate.simulate_block` and :func:`rockdec.physics.loading.add_sensor_noise`, at the
step for which the analysis reads about 75 samples per cycle off them
(:func:`rockdec.calibrate.calibration.step_for`, on pilot seeds of their own), with seeds apart from
every calibration's. Each record is estimated twice by :func:`rockdec.estimation.estimate`:
with ``model=None`` (the record's model measured off it) and with ``model=PAPER`` (white
load, noise-free sensor). Per condition and model: records with a value, coverage of the
95 % interval (a record without a value counts as not covered), bias and spread of the
reported ``e``, the median width, which estimator was reported, and the calibrations built.

Bin error (``--bins K``): for the first ``K`` records of the noisy and coloured conditions,
the record is estimated again with its sensor noise, then its load's pole per sample,
declared one bin below and one above the bin its measurement falls in
(:func:`rockdec.calibrate.calibration.binned_model`); half the change of ``e`` over one bin bounds
what a value anywhere inside a bin moves it, printed as a share of the interval's width.

Timing (``--time``): one clean record, in this process: the analysis alone
(:func:`rockdec.rdd.measured.analyse`), then ``estimate`` with an empty cache (the
calibration built) and again (from the cache), each as a ratio to the analysis; then the
command ``rockdec estimate`` on the record as a CSV with the calibration cached (imports
and reading included).
"""

from __future__ import annotations

import argparse
import collections
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from rockdec.calibrate import calibration

from rockdec import estimation

from rockdec.report.estimate_report import document
from rockdec.rdd import measured
from rockdec.physics.loading import add_sensor_noise
from rockdec.physics.record_model import PAPER, Load, RecordModel, SensorNoise
from rockdec.record.records import Record
from rockdec.physics.simulate import simulate_block

#: Seeds of the records (apart from the calibration's, 2**61 on, and the pilots', 2**62 on).
SEED_OFFSET = 3 * 2**59

#: Condition -> (load corner in rocking frequencies or None, sensor noise in sigma_Y).
CONDITIONS = {
    "clean": (None, 0.0),
    "noise 3%": (None, 0.03),
    "corner 1x": (1.0, 0.0),
    "corner 1x + noise 2%": (1.0, 0.02),
}


def records_of(condition: str, e: float, n: int, count: int, index: int) -> tuple[list[np.ndarray], float]:
    """``count`` records of ``condition`` and their step."""
    corner, noise = CONDITIONS[condition]
    model = RecordModel(load=Load() if corner is None else Load("lowpass", corner))
    pole = model.load.pole(75.0)
    seed0 = SEED_OFFSET + index * 10**6
    dt, burn_in, _ = calibration.step_for(e, 75.0, [n], measured.DEFAULT_SETTINGS, seed0 + 500_000, model)
    out = []
    for k in range(count):
        theta = simulate_block([seed0 + k], n, dt=dt, g=1.0, e=e, sigma_p=1.0, burn_in=burn_in, pole=pole)[0]
        add_sensor_noise(theta, [seed0 + k], noise * float(np.sqrt(np.mean(theta**2))))
        out.append(theta[0])
    return out, dt


def one(theta: np.ndarray, dt: float, cache: str, model) -> dict:
    try:
        res = document(estimation.estimate([Record(theta, dt, "r")], cache_dir=cache, model=model))
    except ValueError as exc:
        return {"refused": str(exc)}
    rm = res["record_model"]
    return {
        "e": res["e"], "interval": res["interval"], "estimator": res["estimator"], "reason": res["reason"],
        "kind": rm["measured"]["kind"] if rm["measured"] else None, "simulated": rm["simulated"]["described"],
        "ppc": res["points_per_cycle"], "cached": res["calibration"]["cached"], "seconds": res["calibration"]["seconds"],
        "raw_e_v": res["estimators"]["e_v"]["raw"],
    }


def bin_error(theta: np.ndarray, dt: float, cache: str) -> dict:
    """Corrected ``e`` (default estimator's pick) at the record's measured bins and at the
    adjacent bins of its noise and of its load's pole (module docstring)."""
    import math

    base = document(estimation.estimate([Record(theta, dt, "r")], cache_dir=cache))
    sim, ppc = base["record_model"]["simulated"], base["points_per_cycle"]
    name = base["estimator"]
    out = {"e": base["e"], "width": None if base["e"] is None else base["interval"][1] - base["interval"][0], "estimator": name}
    if sim["sensor_noise"]["std"] > 0:
        for step in (-1, 1):
            sensor = SensorNoise(sim["sensor_noise"]["std"] * math.exp(step * calibration.NOISE_BIN))
            res = document(estimation.estimate([Record(theta, dt, "r")], cache_dir=cache, sensor=sensor))
            out[f"noise {step:+d}"] = res["estimators"][name]["e"] if name else None
    if sim["load"]["kind"] == "lowpass":
        rate = -math.log(sim["load_pole_per_sample"])
        for step in (-1, 1):
            load = Load("lowpass", rate * math.exp(step * calibration.POLE_BIN) * ppc / (2 * math.pi))
            res = document(estimation.estimate([Record(theta, dt, "r")], cache_dir=cache, load=load))
            out[f"pole {step:+d}"] = res["estimators"][name]["e"] if name else None
    return out


def summary(rows: list[dict], e: float) -> str:
    valued = [r for r in rows if r.get("e") is not None]
    covered = sum(r["interval"][0] <= e <= r["interval"][1] for r in valued)
    errors = [r["e"] - e for r in valued]
    widths = [r["interval"][1] - r["interval"][0] for r in valued]
    chosen = collections.Counter(r.get("estimator") for r in rows)
    kinds = collections.Counter(r.get("kind") for r in rows)
    built = sum(1 for r in rows if r.get("cached") is False)
    return (
        f"{len(valued)}/{len(rows)} valued, coverage {covered}/{len(rows)} = {covered / len(rows):.0%}, "
        f"bias {np.mean(errors) if errors else float('nan'):+.4f}, sd {np.std(errors, ddof=1) if len(errors) > 1 else float('nan'):.4f}, "
        f"median width {np.median(widths) if widths else float('nan'):.4f}; estimator {dict(chosen)}; measured kind {dict(kinds)}; "
        f"calibrations built {built}"
    )


def timing(e: float, n: int) -> None:
    (theta,), dt = records_of("clean", e, n, 1, 99)
    measured.analyse([theta], dt)  # kernels compiled and loaded
    start = time.perf_counter()
    measured.analyse([theta], dt)
    analysis = time.perf_counter() - start
    with tempfile.TemporaryDirectory() as cache:
        start = time.perf_counter()
        document(estimation.estimate([Record(theta, dt, "r")], cache_dir=cache))
        cold = time.perf_counter() - start
        start = time.perf_counter()
        document(estimation.estimate([Record(theta, dt, "r")], cache_dir=cache))
        warm = time.perf_counter() - start
        path = Path(cache) / "r.csv"
        np.savetxt(path, np.c_[np.arange(theta.size) * dt, theta], delimiter=",", header="time,theta", comments="", fmt="%.10g")
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "rockdec", "estimate", str(path), "--cache", cache], check=True, capture_output=True)
        command = time.perf_counter() - start
        start = time.perf_counter()
        subprocess.run([sys.executable, "-c", "pass"], check=True)
        python = time.perf_counter() - start
    print(
        f"timing: analysis {analysis:.2f} s; estimate cold {cold:.1f} s ({cold / analysis:.0f} x), warm {warm:.2f} s "
        f"({warm / analysis:.1f} x); rockdec estimate r.csv, warm, as a command: {command:.2f} s ({command / analysis:.1f} x; "
        f"python -c pass {python:.2f} s)",
        flush=True,
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=20)
    parser.add_argument("--e", type=float, default=0.9)
    parser.add_argument("--n-points", type=int, default=200_000)
    parser.add_argument("--conditions", nargs="*", default=list(CONDITIONS), help="(none: only --time)")
    parser.add_argument("--cache", default=None, help="calibration folder (default: a temporary one)")
    parser.add_argument("--out", default=None, help="write one JSON line per record here")
    parser.add_argument("--time", action="store_true", help="also time one record cold and warm")
    parser.add_argument("--bins", type=int, default=0, help="records per noisy or coloured condition to measure the bin error on")
    args = parser.parse_args()
    if args.time:
        timing(args.e, args.n_points)
    cache = args.cache or tempfile.mkdtemp(prefix="rockdec-bench-")
    out = open(args.out, "a") if args.out else None
    for condition in args.conditions:
        index = list(CONDITIONS).index(condition)
        if args.bins and condition != "clean":
            records, dt = records_of(condition, args.e, args.n_points, args.bins, index)
            for k, theta in enumerate(records):
                row = bin_error(theta, dt, cache)
                shifts = {key: value for key, value in row.items() if key.startswith(("noise", "pole"))}
                moves = {
                    kind: abs(shifts[f"{kind} +1"] - shifts[f"{kind} -1"]) / 4 / row["width"]
                    for kind in ("noise", "pole")
                    if row["width"] and shifts.get(f"{kind} +1") is not None and shifts.get(f"{kind} -1") is not None
                }
                print(f"{condition:>22} | bins, record {k}: {row}; half a bin moves e by {moves} of the interval's width", flush=True)
            continue
        records, dt = records_of(condition, args.e, args.n_points, args.records, index)
        rows = {"measured": [], "paper": []}
        for k, theta in enumerate(records):
            for label, model in (("measured", None), ("paper", PAPER)):
                row = one(theta, dt, cache, model)
                rows[label].append(row)
                if out:
                    out.write(json.dumps({"condition": condition, "record": k, "model": label, **row}) + "\n")
                    out.flush()
        for label in rows:
            print(f"{condition:>22} | {label:>8}: {summary(rows[label], args.e)}", flush=True)


if __name__ == "__main__":
    main()

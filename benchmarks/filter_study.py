"""Records through a low-pass filter after the block (issue 38): covered, declined or missed.

Records at ``e = 0.85`` (``rockdec.simulate``, and a few from the independent pure-Python
reference of ``tests/rocking_reference.py``, both 200,000 samples at 75 samples per rocking
cycle) are passed through Butterworth filters of orders 2, 3 and 4 and a first-order RC
stage, zero-phase (``scipy.signal.sosfiltfilt`` / ``filtfilt``) and causal (``sosfilt`` /
``lfilter``), with the corner at 3, 5, 10 and 20 times the rocking frequency (placed in Hz
at the requested 75 samples per cycle). Each record is estimated twice:

* undeclared (``rockdec.estimate`` with its defaults): must be declined with a reason or
  covered; a *confident miss* is an ``e`` whose interval does not hold 0.85;
* declared (``sensor_filter`` the same filter in Hz, ``load`` white, ``sensor_noise`` 0):
  its coverage.

Then the false alarms, on unfiltered records (white and low-pass loads of corners 3, 5 and
10 rocking frequencies, sensor noise 0 and 1 % of ``sigma_Y``, ``e`` 0.6-0.98), each estimated
whole: how often the steep-filter check before the calibration
(:func:`rockdec.estimation.filter_decline`, the roll-off floor of
:func:`rockdec.record.record_measure.rolloff`) declines ``e``, how often the calibrated check
``filtered`` (:func:`rockdec.record.diagnostics.impact_sharpness`) fires, and how often ``e``
is declined for either; and the declared-model check
(:func:`rockdec.estimation.declared_contradictions`) on records whose declaration is
right (and, beside them, on two that are wrong).

Run (the parts and filter kinds can run apart, in parallel)::

    nice -n 10 python benchmarks/filter_study.py --records 30 --declared 10 --out filter_study.md
    python benchmarks/filter_study.py --part filters --kinds rc --out rc.md
    python benchmarks/filter_study.py --part alarms --seeds 8 --out alarms.md

Writes a markdown table per part (appended as each configuration finishes); asserts nothing.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np
from scipy import signal

import rockdec
from rockdec.calibrate import calibration
from rockdec import estimation
from rockdec.physics.record_model import RecordModel, Load, SensorNoise, parse_sensor_filter
from rockdec.physics.simulate import default_burn_in, simulate_model
from rockdec.rdd import measured
from rockdec.record.records import Record
from rockdec.record import record_measure

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from rocking_reference import flight_reference  # noqa: E402

E_TRUE, N_POINTS, PPC = 0.85, 200_000, 75.0
KINDS = (("rc", 1), ("butterworth", 2), ("butterworth", 3), ("butterworth", 4))
CORNERS = (3.0, 5.0, 10.0, 20.0)
REFERENCE_EVERY = 10  # every tenth record of a configuration comes from the reference simulator


def reference_record(seed: int, dt: float) -> np.ndarray:
    """``N_POINTS`` samples of the random response from ``tests/rocking_reference.py``: an
    impulse ``N(0, 1)`` added to the angular velocity at the end of each step (``g = sigma_p =
    1``), the flight between steps impact by impact; a burn-in of 20 relaxation times dropped."""
    rng = np.random.default_rng(10_000 + seed)
    burn = default_burn_in(E_TRUE, PPC)
    theta, omega = 0.0, 0.0
    out = np.empty(N_POINTS)
    pushes = rng.standard_normal(burn + N_POINTS)
    for k in range(burn + N_POINTS):
        theta, omega = flight_reference(theta, omega + pushes[k], dt, 1.0, E_TRUE)
        if k >= burn:
            out[k - burn] = theta
    return out


def records(n: int) -> list[tuple[np.ndarray, float, str]]:
    """``n`` unfiltered records at ``E_TRUE``: ``(theta, dt, source)``."""
    out = []
    ref_dt = None
    for seed in range(n):
        if seed % REFERENCE_EVERY == REFERENCE_EVERY - 1:
            if ref_dt is None:
                ref_dt = calibration.step_for(E_TRUE, PPC, [N_POINTS], measured.DEFAULT_SETTINGS, 777)[0]
            out.append((reference_record(seed, ref_dt), ref_dt, "reference"))
        else:
            th = rockdec.simulate(E_TRUE, N_POINTS, seed=seed)
            out.append((th.values, float(th.attrs["dt"]), "simulate"))
    return out


def filtered(y: np.ndarray, dt: float, kind: str, order: int, corner: float, zero: bool) -> tuple[np.ndarray, str]:
    """``y`` through the filter (scipy.signal directly), and the filter as ``sensor_filter`` in Hz."""
    hz = corner / (dt * PPC)
    if kind == "rc":
        a = math.exp(-2.0 * math.pi * hz * dt)
        out = (signal.filtfilt if zero else signal.lfilter)([1.0 - a], [1.0, -a], y)
        text = f"rc:{hz:.8g}hz:{'zero-phase' if zero else 'causal'}"
    else:
        sos = signal.butter(order, 2.0 * hz * dt, output="sos")
        out = (signal.sosfiltfilt if zero else signal.sosfilt)(sos, y)
        text = f"butterworth:{order}:{hz:.8g}hz:{'zero-phase' if zero else 'causal'}"
    return out, text


def outcome(doc: dict) -> str:
    """``covered``, ``miss``, ``declined`` (the reason names ``sensor_filter``) or ``other``
    (declined for another reason)."""
    if doc["e"] is None:
        return "declined" if "`sensor_filter`" in (doc["reason"] or "") else "other"
    low, high = doc["interval"]
    return "covered" if low <= E_TRUE <= high else "miss"


def study_filters(n: int, n_declared: int, cache: Path, out, kinds=KINDS, noise: float = 0.0) -> None:
    """``noise``: sensor noise added after the filter, in units of the filtered record's rms
    (declared as such when the filter is)."""
    base = records(n)
    out.write(f"## Filtered records, e = 0.85, sensor noise {noise:.0%} after the filter\n\n| filter | corner (x rocking f) | phase | undeclared: covered / declined naming the filter / declined for another reason / confident miss "
              "| declared: covered / declined / miss | misses (e, interval) |\n|---|---|---|---|---|---|\n")
    out.flush()
    for kind, order in kinds:
        for corner in CORNERS:
            for zero in (True, False):
                started = time.perf_counter()
                counts = {"covered": 0, "declined": 0, "other": 0, "miss": 0}
                declared = {"covered": 0, "declined": 0, "other": 0, "miss": 0}
                missed = []
                for i, (y, dt, _) in enumerate(base):
                    z, text = filtered(y, dt, kind, order, corner, zero)
                    if noise:
                        z = z + noise * float(np.std(z)) * np.random.default_rng(i).standard_normal(z.size)
                    doc = rockdec.estimate(z, dt, cache=cache).to_dict()
                    counts[outcome(doc)] += 1
                    if outcome(doc) == "miss":
                        missed.append(f"{doc['e']:.3f} [{doc['interval'][0]:.3f}, {doc['interval'][1]:.3f}]")
                    if i < n_declared:
                        doc = rockdec.estimate(z, dt, cache=cache, sensor_filter=text, load="white", sensor_noise=f"{noise:.6%}").to_dict()
                        declared[outcome(doc)] += 1
                name = f"Butterworth {order}" if kind == "butterworth" else "RC"
                out.write(
                    f"| {name} | {corner:g} | {'zero-phase' if zero else 'causal'} | {counts['covered']} / {counts['declined']} / "
                    f"{counts['other']} / {counts['miss']} | {declared['covered']} / {declared['declined'] + declared['other']} / "
                    f"{declared['miss']} of {min(n, n_declared)} | "
                    f"{'; '.join(missed[:3])} |\n"
                )
                out.flush()
                print(f"{kind}{order} {corner} {zero}: {counts} {declared} {time.perf_counter() - started:.0f} s", file=sys.stderr, flush=True)


def clean_record(e: float, corner: float | None, seed: int, noise: float, steps: dict) -> tuple[np.ndarray, float]:
    """An unfiltered record of ``N_POINTS`` at ``e`` (white load, or low-pass at ``corner``),
    sensor noise ``noise`` of its rms; ``steps`` caches the step search."""
    model = RecordModel(load=Load("lowpass", corner) if corner else Load())
    if (e, corner) not in steps:
        steps[(e, corner)] = calibration.step_for(e, PPC, [N_POINTS], measured.DEFAULT_SETTINGS, 4242, model)
    dt, burn, _ = steps[(e, corner)]
    y = simulate_model("simplified", [seed], N_POINTS, dt=dt, g=1.0, e=e, sigma_p=1.0, burn_in=burn, **model.load.draw_options(PPC))[0][0]
    if noise:
        y = y + noise * float(np.std(y)) * np.random.default_rng(seed).standard_normal(y.size)
    return y, dt


def study_false_alarms(seeds: int, cache: Path, out) -> None:
    steps: dict = {}
    out.write("\n## The filter checks on unfiltered records (false alarms)\n\n| load | sensor noise | e | records | declined by the "
              "steep-filter check (floor f^%g) | lowest z of the floor | `filtered` fired | declined for a filter | answered, "
              "interval holds e |\n|---|---|---|---|---|---|---|---|---|\n" % record_measure.ROLLOFF_FLOOR)
    totals = np.zeros(4, dtype=int)
    for corner in (None, 3.0, 5.0, 10.0):
        for noise in (0.0, 0.01):
            for e in (0.6, 0.85, 0.95, 0.98):
                steep = fired = declined = covered = answered = 0
                zs = []
                for seed in range(seeds):
                    y, dt = clean_record(e, corner, 500 + seed, noise, steps)
                    doc = rockdec.estimate(y, dt, cache=cache).to_dict()
                    roll = doc["record_model"].get("filter_rolloff")
                    zs.append(roll["z"] if roll and roll["z"] is not None else math.nan)
                    structural = bool(roll and roll["detected"])
                    calibrated = bool(doc["diagnostics"].get("filtered", {}).get("fired"))
                    steep, fired = steep + structural, fired + calibrated
                    declined += doc["e"] is None and (structural or calibrated)
                    if doc["e"] is not None:
                        answered += 1
                        covered += doc["interval"][0] <= e <= doc["interval"][1]
                totals += (seeds, steep, fired, declined)
                out.write(f"| {'white' if corner is None else f'low-pass {corner:g}'} | {noise:.0%} | {e:g} | {seeds} | {steep} | "
                          f"{np.nanmin(zs):.1f} | {fired} | {declined} | {covered} of {answered} |\n")
                out.flush()
                print(f"alarms {corner} {noise} {e}: steep {steep} fired {fired} declined {declined}", file=sys.stderr, flush=True)
    n, steep, fired, declined = totals
    out.write(f"\nOver {n} unfiltered records: the steep-filter check declined {steep} ({steep / n:.1%}), `filtered` fired on "
              f"{fired} ({fired / n:.1%}), {declined} ({declined / n:.1%}) declined for a filter.\n")
    out.write("\n## Declared parts checked against the record\n\n| record | declared | records | noted |\n|---|---|---|---|\n")
    cases = (
        ("white, no noise", None, 0.0, {"load": Load(), "sensor": SensorNoise()}),
        ("white, 2 % noise", None, 0.02, {"load": Load(), "sensor": SensorNoise(0.02)}),
        ("low-pass 3, no noise", 3.0, 0.0, {"load": Load("lowpass", 3.0), "sensor": SensorNoise()}),
        ("low-pass 3, 2 % noise", 3.0, 0.02, {"load": Load("lowpass", 3.0), "sensor": SensorNoise(0.02)}),
        ("white, no noise (wrong)", None, 0.0, {"load": Load(), "sensor": SensorNoise(0.2)}),
        ("white, no noise (wrong)", None, 0.0, {"load": Load("lowpass", 3.0), "sensor": SensorNoise()}),
    )
    for label, corner, noise, declared in cases:
        noted, total = 0, 0
        for e in (0.6, 0.8, 0.9, 0.98):
            for seed in range(seeds):
                y, dt = clean_record(e, corner, 900 + seed, noise, steps)
                analysed = estimation.analyse([Record(y, dt, "record")])
                choice = estimation.choose_model(analysed, **declared)
                noted += bool(choice.notes)
                total += 1
        what = f"load {declared['load'].describe()}, noise {declared['sensor'].std:g} sigma_Y"
        out.write(f"| {label} | {what} | {total} | {noted} ({noted / total:.0%}) |\n")
        out.flush()


def main(argv=None) -> int:
    global N_POINTS
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=30, help="records per filter configuration (undeclared)")
    parser.add_argument("--declared", type=int, default=10, help="of them, estimated with the filter declared")
    parser.add_argument("--seeds", type=int, default=6, help="unfiltered records per e and load of the false-alarm parts")
    parser.add_argument("--cache", default="filter_study_cache", help="folder of stored calibrations")
    parser.add_argument("--out", default="filter_study.md", help="markdown file written")
    parser.add_argument("--part", choices=("all", "filters", "alarms"), default="all")
    parser.add_argument("--kinds", choices=("all", "rc", "butterworth"), default="all", help="filter kinds of the filters part")
    parser.add_argument("--n-points", type=int, default=N_POINTS, help="samples per record")
    parser.add_argument("--noise", type=float, default=0.0, help="sensor noise added after the filter (share of the record's rms)")
    args = parser.parse_args(argv)
    N_POINTS = args.n_points
    with open(args.out, "w") as out:
        out.write(f"# Filter study (benchmarks/filter_study.py, rockdec {rockdec.__version__}, {N_POINTS} samples a record)\n\n")
        if args.part in ("all", "alarms"):
            study_false_alarms(args.seeds, Path(args.cache), out)
        if args.part in ("all", "filters"):
            kinds = [k for k in KINDS if args.kinds in ("all", k[0])]
            study_filters(args.records, args.declared, Path(args.cache), out, kinds, args.noise)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

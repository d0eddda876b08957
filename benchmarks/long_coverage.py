"""Does the interval of a long record hold? Coverage on simulated records of known ``e`` longer
than :data:`rockdec.calibrate.calibration.LENGTH_CAP` (docs/explanation/estimate.md, "Long records").

The calibration is ``rockdec estimate``'s own for records of ``--samples`` read at
``--ppc`` samples per cycle (:func:`rockdec.calibrate.calibration.calibration_settings`: sets of
:data:`~rockdec.calibrate.calibration.LENGTH_CAP` samples on
:data:`~rockdec.calibrate.calibration.E_GRID_LONG`), built or read from ``OUT/cache``, where it
is named by what it simulates without the source's fingerprint (delete it after a change
to the simulator or the analysis). The test
records are ``--records`` records of ``--samples`` at each ``--e``, simulated and analysed exactly
like a calibration's sets (:func:`rockdec.calibrate.calibration._grid_point`) on seeds of their own
(:func:`rockdec.studies.belt_study.pool`'s, replica ``--replica``), stored in ``OUT``. Each record
gets every candidate's interval from the belt with its spread scaled to its length
(:func:`rockdec.calibrate.belt.belts`, :func:`rockdec.calibrate.calibration.spread_scale`) and the
candidate ``rockdec estimate`` reports (:func:`rockdec.estimation.select`).

Printed: the share of the test records on which each check of
:mod:`rockdec.record.diagnostics` fires (false alarms: the records are clean), and per ``e`` and estimator: coverage of the 95 % interval and its binomial sd, the mean
error of the corrected ``e`` over its sd across records (bias/sd), the offset of the records'
mean raw value from the belt's mean curve in units of the belt's spread (``curve_z``), median
width, and the wall and CPU seconds of the calibration and of the test records.

Run: ``python benchmarks/long_coverage.py --samples 20e6 --records 15 --replica 21 23 --out DIR``
(``--cap``: calibrate on records of another length than
:data:`~rockdec.calibrate.calibration.LENGTH_CAP`). Prints numbers; asserts nothing.
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np
import pandas as pd
import xarray as xr

from rockdec.calibrate import belt, calibration

from rockdec import estimation
from rockdec.rdd import measured, registry
from rockdec.record import diagnostics
from rockdec.studies import belt_study


def test_records(cal_settings: dict, samples: int, e_values, records: int, replica: int) -> xr.Dataset:
    """``records`` test records of ``samples`` at each of ``e_values`` (module docstring)."""
    settings = {**cal_settings, "lengths": [samples], "e_grid": [float(e) for e in e_values], "sets_per_e": records}
    import dask

    from rockdec import engine

    seed = calibration.CALIBRATION_SEED_OFFSET + replica * belt_study.SEED_STRIDE
    tasks = [dask.delayed(calibration._grid_point)(j, e, settings, seed) for j, e in enumerate(settings["e_grid"])]
    points = engine.compute(*tasks)
    return xr.Dataset(
        {"raw": (("e_true", "set", "name"), np.stack([raw for raw, _ in points])),
         "diagnostic": (("e_true", "set", "check"), np.stack([diag for _, diag in points]))},
        coords={"e_true": settings["e_grid"], "set": np.arange(records), "name": list(calibration.NAMES), "check": list(diagnostics.CHECKS)},
        attrs={"samples": samples, "replica": replica},
    )


def table(cal, test: xr.Dataset, scale: float) -> pd.DataFrame:
    """Coverage, bias/sd, ``curve_z`` and width per true ``e`` and candidate, and of the reported one."""
    belts = belt.belts(cal, scale)
    n_sets = int(cal["raw"].sizes["e_true"] * cal["raw"].sizes["set"])
    cover = {name: belt.calibration_coverage(cal, name, belt.belt(cal, name)) for name in registry.CANDIDATES}  # as estimation.estimate
    rows, alarms = [], []
    for e in test["e_true"].values:
        per_record = []
        for k in range(test.sizes["set"]):
            per = {}
            for name in registry.CANDIDATES:
                raw = float(test["raw"].sel(name=name, e_true=e).values[k])
                c = belt.correct(belts[name], raw)
                side = estimation.beyond(belts[name], raw, c)
                per[name] = {"e": None if side or not np.isfinite(c.value) else c.value, "beyond": side, "notes": list(c.notes),
                             "interval": [None if not np.isfinite(c.low) else c.low, None if not np.isfinite(c.high) else c.high],
                             "coverage": cover[name], "calibrated_range": [belts[name].e[0], belts[name].e[-1]]}
            chosen, _, _ = estimation.select(per, n_sets, belts)
            shown = per[chosen] if chosen else {"e": None, "interval": [None, None]}
            if "diagnostic" in test:
                limits = diagnostics.thresholds(cal, shown["e"], shown["interval"], measured.DEFAULT_SETTINGS["level"], 1.0 / scale**2)
                fired = diagnostics.judge(test["diagnostic"].sel(e_true=e).values[k], limits)
                alarms.append([fired[c].fired for c in diagnostics.CHECKS])
            per_record.append({**per, "reported": shown})
        for name in (*registry.CANDIDATES, "reported"):
            value = np.array([np.nan if r[name]["e"] is None else r[name]["e"] for r in per_record])
            low = np.array([np.nan if r[name]["interval"][0] is None else r[name]["interval"][0] for r in per_record])
            high = np.array([np.nan if r[name]["interval"][1] is None else r[name]["interval"][1] for r in per_record])
            hit = (low <= e) & (e <= high)
            n = hit.size
            cov = float(hit.mean())
            row = {"e_true": float(e), "estimator": name, "records": n, "coverage": cov, "binomial_sd": math.sqrt(0.95 * 0.05 / n),
                   "bias_over_sd": float(np.nanmean(value - e) / np.nanstd(value, ddof=1)) if np.isfinite(value).sum() > 1 else np.nan,
                   "median_width": float(np.nanmedian(high - low)), "no_interval": float(np.mean(~np.isfinite(low)))}
            if name != "reported":
                b = belts[name]
                raw = test["raw"].sel(name=name, e_true=e).values
                row["curve_z"] = float((np.nanmean(raw) - np.interp(e, b.e, b.mean)) / np.interp(e, b.e, b.spread))
            else:
                row["reported"] = ",".join(f"{k}:{sum(1 for r in per_record if r['reported'] is r[k])}" for k in registry.CANDIDATES)
            rows.append(row)
    if alarms:
        rate = np.mean(alarms, axis=0)
        print("false alarms on these clean records: " + ", ".join(f"{c} {r:.1%}" for c, r in zip(diagnostics.CHECKS, rate))
              + f" ({len(alarms)} records)")
    return pd.DataFrame(rows)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=float, default=2e7)
    parser.add_argument("--e", type=float, nargs="+", default=[0.85, 0.95])
    parser.add_argument("--records", type=int, default=15)
    parser.add_argument("--ppc", type=float, default=75.0)
    parser.add_argument("--replica", type=int, nargs="+", default=[21], help="seed bases of the test records (their sets are pooled)")
    parser.add_argument("--cap", type=float, default=calibration.LENGTH_CAP, help="samples of the calibration's records (LENGTH_CAP)")
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    samples = int(args.samples)
    calibration.LENGTH_CAP = int(args.cap)
    args.out.mkdir(parents=True, exist_ok=True)
    # stored by what it simulates, not by the source's fingerprint: reused across edits that change no number
    cal_settings = {**calibration.calibration_settings([samples], args.ppc), "pipeline": "study"}
    wall, cpu = time.perf_counter(), time.process_time()
    cal, cached = calibration.load_or_build(cal_settings, args.out / "cache")
    print(f"calibration ({'stored' if cached else 'built'}): {sum(cal_settings['lengths'])} samples x {len(cal_settings['e_grid'])} e x "
          f"{cal_settings['sets_per_e']} sets, wall {time.perf_counter() - wall:.0f} s, CPU {time.process_time() - cpu:.0f} s", flush=True)
    tests = []
    for replica in args.replica:
        path = args.out / f"test-{samples}-{replica}-{args.records}-{'_'.join(map(str, args.e))}-ppc{cal_settings['points_per_cycle']}.nc"
        if not path.is_file():
            wall, cpu = time.perf_counter(), time.process_time()
            test_records(cal_settings, samples, args.e, args.records, replica).to_netcdf(path)
            print(f"test records: {args.records} x {len(args.e)} of {samples} samples, wall {time.perf_counter() - wall:.0f} s, "
                  f"CPU {time.process_time() - cpu:.0f} s", flush=True)
        tests.append(xr.load_dataset(path))
    test = xr.concat(tests, "set").assign_coords(set=np.arange(sum(t.sizes["set"] for t in tests)))
    scale = calibration.spread_scale(cal_settings, samples)
    with pd.option_context("display.width", 250, "display.max_columns", 20):
        print(f"spread scale {scale:.4f}")
        print(table(cal, test, scale).round(4).to_string(index=False))


if __name__ == "__main__":
    main()

"""Is the reported interval as wide as the scatter under sensor noise at high ``e``?

A plain script (not a test): prints measurements, never asserts them.

    python benchmarks/noise_high_e.py --e 0.95 0.98 --noise 0.03 0.05 --records 80 --cache DIR --out DIR

For each true ``e`` and sensor noise (a share of the record's rms), ``--records`` records of
``--n-points`` samples at the coverage study's sampling (:func:`rockdec.studies.coverage.stage`),
made by the compiled kernel or (``--simulator reference``) by tests/rocking_vectorised.py with
each record's angle and time scaled at random (a block of another ``g``; the tool measures
``g``), go through :func:`rockdec.studies.coverage.estimate_record`, the path of
``rockdec estimate`` with the record model measured. Per cell it prints the reported
interval's coverage and its median width over 3.92 times the spread of the reported ``e``
about the truth (:func:`rockdec.studies.coverage.sharpness`, and its robust reading), and the same for each
candidate estimator's own interval over the same records, with the sensor noise the tool
read against the true one. Each record's row (every estimator's corrected value, interval
and raw value, the noise read, the calibration used) goes to ``<out>/<simulator>_e<E>_noise<N>.csv``,
so that a belt variant can be read offline: ``--read`` reports stored cells, and with
``--sets N`` reads their records again through calibrations of ``N`` sets per ``e``
(:func:`reread`).
Seeds start at :data:`SEED_OFFSET`, apart from the study's, the fresh records' and the
calibrations'.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from rockdec import engine
from rockdec.rdd import registry
from rockdec.studies import coverage

#: Seeds of this bench's records start here (the study's at 2**60, the fresh records' at 2**59).
SEED_OFFSET = 2**58

#: Largest factor by which a reference record's angle, and its time, are scaled (log-uniform).
SCALE_RANGE = 3.0


def _rows(simulate, seeds, n_points, staged, e, noise, cache, scaled) -> list[dict]:
    theta = simulate(seeds, n_points, dt=staged["dt"], e=e, burn_in=staged["burn_in"], pole=staged["pole"], noise=noise)
    out = []
    for seed, row in zip(seeds, theta):
        angle, time = np.exp(np.random.default_rng(int(seed)).uniform(-1, 1, 2) * math.log(SCALE_RANGE)) if scaled else (1.0, 1.0)
        got = coverage.estimate_record(row * angle, staged["dt"] * time, f"record {seed}", cache, coverage.MEASURED)
        r = {"seed": int(seed), "e_hat": got["e"], "low": got["low"], "high": got["high"], "reported_by": got["estimator"],
             "reason": got["reason"], "noise_read": got["noise_read"], "ppc_read": got["points_per_cycle"],
             "calibration": got["calibration"], "warnings": " | ".join(got["warnings"])}
        for name, (value, low, high, raw) in got["per"].items():
            r.update({f"{name}_e": value, f"{name}_low": low, f"{name}_high": high, f"{name}_raw": raw})
        out.append(r)
    return out


def cell(simulator: str, e: float, noise: float, records: int, n_points: int, cache: Path, batch: int = 10) -> pd.DataFrame:
    """The records of one cell, a row each (module docstring)."""
    import dask

    reference = Path(__file__).resolve().parents[1] / "tests" / "rocking_vectorised.py"
    simulate = coverage.simulator_of(f"{simulator}_clean_e0.9", reference)
    seed0 = SEED_OFFSET + int(round(1000 * e)) * 10**7 + int(round(1000 * noise)) * 10**5 + (simulator == "reference") * 10**9
    staged = coverage.stage(e, n_points, None, seed0 + 9 * 10**4)
    seeds = seed0 + np.arange(records)
    tasks = [dask.delayed(_rows)(simulate, seeds[i:i + batch], n_points, staged, e, noise, cache, simulator == "reference")
             for i in range(0, records, batch)]
    return pd.DataFrame([r for part in engine.compute(*tasks) for r in part]).assign(e_true=e, noise=noise, simulator=simulator)


def report(df: pd.DataFrame) -> None:
    e = float(df["e_true"].iloc[0])

    def line(label, value, low, high):
        ok = np.isfinite(value) & np.isfinite(low) & np.isfinite(high)
        cov = float(np.mean((low[ok] <= e) & (e <= high[ok]))) if ok.any() else math.nan
        width = high[ok] - low[ok]
        return (f"  {label:>10}: n {ok.sum():3d}, coverage {100 * cov:5.1f} %, width/(3.92 sd) "
                f"{coverage.sharpness(e, value[ok], width):.2f} (robust {coverage.sharpness(e, value[ok], width, robust=True):.2f}), "
                f"bias {np.mean(value[ok]) - e:+.4f}")

    print(f"{df['simulator'].iloc[0]} e = {e:g}, noise {df['noise'].iloc[0]:g}: noise read median "
          f"{np.nanmedian(df['noise_read']):.4f} (sd {np.nanstd(df['noise_read']):.4f}); reported by "
          f"{df['reported_by'].value_counts().to_dict()}")
    print(line("reported", df["e_hat"].to_numpy(float), df["low"].to_numpy(float), df["high"].to_numpy(float)))
    for name in registry.CANDIDATES:
        if f"{name}_e" in df:
            print(line(name, df[f"{name}_e"].to_numpy(float), df[f"{name}_low"].to_numpy(float), df[f"{name}_high"].to_numpy(float)))
    sys.stdout.flush()


def reread(df: pd.DataFrame, cache: Path, sets: int) -> pd.DataFrame:
    """The records of ``df`` read again through calibrations of ``sets`` sets per ``e``:
    each record's calibration settings (stored in the file it used) with ``sets_per_e``
    replaced, built into ``cache`` (other settings, other seeds: independent sets), and the
    raw value of the estimator it reported inverted through that calibration's belt
    (:func:`rockdec.studies.coverage.recorrect`'s inverter). The estimator reported stays;
    a record with a null ``e`` stays null."""
    import json

    from rockdec.calibrate import calibration, ncread

    out, files = df.copy(), {}
    invert = coverage._Inverter(cache, int(df.attrs.get("n_points", 200_000)))
    for k, row in df.iterrows():
        if not isinstance(row["reported_by"], str) or not np.isfinite(row["e_hat"]):
            continue
        if row["calibration"] not in files:
            settings = json.loads(ncread.read(cache / row["calibration"]).attrs["settings"])
            settings["sets_per_e"] = sets
            files[row["calibration"]] = f"calibration-{calibration.settings_hash(settings)}.nc"
            calibration.load_or_build(settings, cache)
        name = row["reported_by"]
        out.loc[k, ["e_hat", "low", "high"]] = invert(files[row["calibration"]], name, float(row[f"{name}_raw"]))
    return out


def main() -> None:
    """Run the cells the arguments name, or (``--read``) report cells stored before."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--e", type=float, nargs="+", default=[0.95, 0.98])
    parser.add_argument("--noise", type=float, nargs="+", default=[0.03, 0.05])
    parser.add_argument("--simulator", choices=("kernel", "reference"), default="kernel")
    parser.add_argument("--records", type=int, default=80)
    parser.add_argument("--n-points", type=int, default=200_000)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--cache", type=Path, required=True, help="calibration folder (shared between runs)")
    parser.add_argument("--out", type=Path, required=True, help="folder for each cell's CSV")
    parser.add_argument("--read", action="store_true", help="report the cells stored in --out, simulate nothing")
    parser.add_argument("--sets", type=int, help="with --read: read the records again through calibrations of this many sets per e")
    args = parser.parse_args()
    if args.read:
        for e in args.e:
            for noise in args.noise:
                df = pd.read_csv(args.out / f"{args.simulator}_e{e:g}_noise{noise:g}.csv")
                if args.sets:
                    with engine.session(args.threads):
                        df = reread(df, args.cache, args.sets)
                    print(f"read again through calibrations of {args.sets} sets per e:")
                report(df)
        return
    args.out.mkdir(parents=True, exist_ok=True)
    with engine.session(args.threads):
        for e in args.e:
            for noise in args.noise:
                df = cell(args.simulator, e, noise, args.records, args.n_points, args.cache)
                df.to_csv(args.out / f"{args.simulator}_e{e:g}_noise{noise:g}.csv", index=False)
                report(df)


if __name__ == "__main__":
    main()

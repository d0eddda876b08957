"""Does the belt's interval hold at every ``e``? A test bed made of calibration record sets.

A calibration's record sets are records of known ``e`` analysed exactly like a measured
record (:func:`rockdec.calibrate.calibration.grid_tasks`), so calibrations built with identical
settings but different seed bases are independent samples of the same distribution: one
serves as the belt, the sets of the others as test records, at the calibration's grid and
at any other ``e`` (:func:`pool` draws sets on any grid of ``e``). The coverage of the 95 %
interval per ``e`` then comes from hundreds of sets without any analysis code of its own
(:func:`coverage`, and :func:`g_coverage` for ``g``'s interval; :func:`study` over several
belts). Run it as ``python -m rockdec.studies.belt_study --samples 200000 --pool-sets 120 200 200 200
--replicas 1 3 5 6 --out DIR`` (it prints each estimator's coverage at each ``e``; the pools are stored in
``DIR``, so a second run does not simulate them again; docs/explanation/studies/coverage.md,
"The belt alone").
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import xarray as xr

from rockdec.calibrate import belt, calibration
from rockdec import engine
from rockdec.rdd import measured, registry

__all__ = ["SEED_STRIDE", "TEST_E", "pool", "study"]

#: Seed bases of the test bed: the calibration's, moved by multiples of this (far apart
#: from the calibration's own seeds, the study's and the scenes').
SEED_STRIDE = 2**50

#: True ``e`` of the test bed: the calibration's grid and values between its points.
TEST_E = tuple(sorted({*calibration.E_GRID, 0.45, 0.55, 0.65, 0.72, 0.78, 0.82, 0.865, 0.895, 0.92, 0.94, 0.957, 0.972, 0.985}))


def pool(e_values, sets: int, n_points: int, points_per_cycle: float = 75.0, replica: int = 1) -> xr.Dataset:
    """``sets`` calibration record sets of one record of ``n_points`` at each ``e`` of
    ``e_values``, seed base ``calibration.CALIBRATION_SEED_OFFSET + replica * SEED_STRIDE``
    (``replica = 0``: the seeds of the calibration of these settings,
    :func:`rockdec.calibrate.calibration.seed_base`); ``raw(e_true, set, name)`` as
    :func:`rockdec.calibrate.calibration.build` stores it."""
    settings = {**calibration.calibration_settings([n_points], points_per_cycle), "e_grid": [float(e) for e in e_values], "sets_per_e": int(sets)}
    base = calibration.CALIBRATION_SEED_OFFSET + replica * SEED_STRIDE if replica else calibration.seed_base(settings)
    values = np.stack([raw for raw, _ in engine.compute(*calibration.grid_tasks(settings, base))])  # (raw, the checks' statistics)
    return xr.Dataset(
        {"raw": (("e_true", "set", "name"), values, {"units": "1", "long_name": "zero-window estimate on a simulated record set (g in units of the true g)"})},
        coords={"e_true": ("e_true", np.asarray(settings["e_grid"])), "set": ("set", np.arange(sets)), "name": ("name", list(calibration.NAMES))},
        attrs={"n_points": int(n_points), "points_per_cycle": float(points_per_cycle), "replica": int(replica)},
    )


def coverage(cal: xr.Dataset, test: xr.Dataset, names=registry.CANDIDATES) -> pd.DataFrame:
    """Per true ``e`` of ``test`` and estimator: coverage of the 95 % interval of the belt
    of ``cal`` (:func:`rockdec.calibrate.belt.correct`) over the test sets, and its median width;
    a set with no interval counts as not covered (``no_interval``: their share)."""
    rows = []
    for name in names:
        b = belt.belt(cal, name)
        for e in test["e_true"].values:
            low, high = belt.intervals(b, test["raw"].sel(name=name, e_true=e).values)
            rows.append(
                {
                    "estimator": str(name),
                    "e_true": float(e),
                    "records": int(low.size),
                    "coverage": float(np.mean((low <= e) & (e <= high))),
                    "median_width": float(np.nanmedian(high - low)) if np.isfinite(low).any() else float("nan"),
                    "no_interval": float(np.mean(~np.isfinite(low))),
                }
            )
    return pd.DataFrame(rows)


def g_coverage(cal: xr.Dataset, test: xr.Dataset, name: str = registry.DEFAULT_ESTIMATOR) -> pd.DataFrame:
    """Per true ``e`` of ``test``: coverage of the 95 % interval of ``g``
    (:func:`rockdec.calibrate.belt.g_interval`, ``e`` corrected with estimator ``name``) over the
    test sets that get one (their ``g`` row is in units of the true ``g``, so the interval
    must hold 1), its median relative width, and the share of sets with no interval (``e``
    not held inside the calibrated range, :func:`rockdec.calibrate.belt.held_e`); NaN coverage when
    none has one."""
    b, g_belt = belt.belt(cal, name), belt.belt(cal, measured.G_NAME)
    band = belt.g_band(cal, name, b, g_belt)
    rows = []
    for e in test["e_true"].values:
        ends = belt.g_intervals(b, g_belt, band, test["raw"].sel(name=name, e_true=e).values, test["raw"].sel(name=measured.G_NAME, e_true=e).values)
        rows.append(
            {
                "e_true": float(e),
                "records": int(ends.shape[0]),
                "coverage": float(np.sum((ends[:, 0] <= 1.0) & (1.0 <= ends[:, 1])) / np.isfinite(ends[:, 0]).sum()) if np.isfinite(ends[:, 0]).any() else float("nan"),
                "median_width": float(np.nanmedian(ends[:, 1] - ends[:, 0])) if np.isfinite(ends).any() else float("nan"),
                "no_interval": float(np.mean(~np.isfinite(ends[:, 0]))),
            }
        )
    return pd.DataFrame(rows)


def study(pools: list[xr.Dataset], grid=calibration.E_GRID, sets: int = calibration.SETS_PER_E, names=registry.CANDIDATES,
          blocks: int = 4, e_range=(0.6, 0.98)) -> pd.DataFrame:
    """Coverage per true ``e`` and estimator (and ``g``, as ``name = "g"``) of belts built from
    blocks of ``sets`` sets at the ``grid`` of one pool (up to ``blocks`` per pool), each
    tested on the sets of every other pool at the ``e`` of ``e_range``; mean over the
    belts, and the 10 % and 90 % points of a single belt's coverage."""
    frames = []
    for i, own in enumerate(pools):
        others = xr.concat([p for j, p in enumerate(pools) if j != i], "set")
        test = others.sel(e_true=[e for e in others["e_true"].values if e_range[0] - 1e-9 <= e <= e_range[1] + 1e-9])
        for k in range(min(blocks, own.sizes["set"] // sets)):
            cal = own.sel(e_true=list(grid)).isel(set=slice(k * sets, (k + 1) * sets))
            frames += [coverage(cal, test, names), g_coverage(cal, test).assign(estimator=measured.G_NAME)]
    rows = pd.concat(frames).groupby(["estimator", "e_true"])
    return pd.DataFrame({
        "coverage": rows["coverage"].mean(), "p10": rows["coverage"].quantile(0.1), "p90": rows["coverage"].quantile(0.9),
        "median_width": rows["median_width"].mean(), "no_interval": rows["no_interval"].mean(), "belts": rows.size(),
        "test_sets": rows["records"].first(),
    }).reset_index()


def main(argv=None) -> int:
    """``python -m rockdec.studies.belt_study --samples 200000 --pool-sets 120 200 200 200 --out DIR``:
    draws the pools (stored in ``DIR``, reused when present) and prints :func:`study`."""
    import argparse
    from pathlib import Path

    parser = argparse.ArgumentParser(prog="python -m rockdec.studies.belt_study", description=main.__doc__)
    parser.add_argument("--samples", type=int, default=200_000)
    parser.add_argument("--pool-sets", type=int, nargs="+", default=[120, 200, 200, 200], help="sets per e of each pool")
    parser.add_argument("--replicas", type=int, nargs="+", help="seed base of each pool (default 1, 2, ...)")
    parser.add_argument("--blocks", type=int, default=4)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    pools = []
    for replica, sets in zip(args.replicas or range(1, len(args.pool_sets) + 1), args.pool_sets):
        path = args.out / f"pool-{args.samples}-{replica}-{sets}.nc"
        if not path.is_file():
            pool(TEST_E, sets, args.samples, replica=replica).to_netcdf(path)
        pools.append(xr.load_dataset(path))
    table = study(pools, blocks=args.blocks)
    with pd.option_context("display.width", 200, "display.max_rows", 500):
        print(table.pivot(index="e_true", columns="estimator", values="coverage").round(3))
        print(table.round(4).to_string(index=False))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

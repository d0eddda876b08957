"""Time the batched estimator kernel against the per-signature reference, on the same signatures.

A plain script (not a test): prints timings, never asserts them.

    python benchmarks/bench_estimators.py [--series 2000] [--points 6000] [--windows 10]

The signatures are like the paper's: ``--series`` stationary series of ``--points`` samples
at about 75 samples per rocking cycle at amplitude ``sigma_Y`` (``rockdec.physics.simulate``,
e = 0.95, the step from the scale law as in ``bench_signatures.py``), one ``D_a`` and one
``D_v`` signature per series and window (package defaults: level ``2 sigma_Y``, lags 2.5
periods at amplitude ``a``, so ``lag_pos`` about 266 and ``lag`` about 531). Every free
response and ``D_v`` signature goes through

- the reference, :func:`reference_estimators.reference_estimate_all` (``tests/``), one Python call per
  signature;
- the batch kernel :func:`rockdec.rdd.estimators._estimate_rows`, all signatures in one call;
- :func:`rockdec.rdd.estimators.estimate_cube` on the labelled cube, NumPy and Dask (chunks of
  ``--chunk`` series over the cores);

and the largest difference between the reference and the kernel is printed with the count
of NaN that differ.
"""

from __future__ import annotations

import argparse
import os
import time

import dask
import numpy as np
import xarray as xr

import tests_path  # noqa: F401  (tests/ on sys.path for the reference)
from bench_signatures import best_of, rocking_record  # benchmarks/ is on sys.path
from reference_estimators import reference_estimate_all

from rockdec.rdd import estimators, registry, signatures
from rockdec.physics import simulate
from rockdec.rdd.fits import DEFAULT_FIT_POINTS



def paper_cube(n_series, n_points, n_windows):
    """Per-series signature cube of a simulated record (:func:`bench_signatures.rocking_record`),
    its ``dt`` and its samples per cycle at ``sigma_Y``."""
    theta, dt, sigma_y, sigma_ydot, _, g, _ = rocking_record(n_series, n_points)
    points_per_cycle = simulate.pilot_statistics(theta, dt, g)["points_per_cycle"]
    theta = xr.DataArray(theta, dims=("seed", "time"), attrs={"dt": dt})
    windows = np.arange(1, n_windows + 1) / n_windows
    cube = signatures.signature_cube(theta, sigma_y=sigma_y, sigma_ydot=sigma_ydot, windows=windows, g=g)
    return cube, dt, points_per_cycle


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--series", type=int, default=2000)
    parser.add_argument("--points", type=int, default=6000)
    parser.add_argument("--windows", type=int, default=10)
    parser.add_argument("--chunk", type=int, default=250, help="series per Dask chunk")
    parser.add_argument("--repeat", type=int, default=3, help="best of this many runs (the reference runs once)")
    args = parser.parse_args(argv)

    t0 = time.perf_counter()
    cube, dt, ppc = paper_cube(args.series, args.points, args.windows)
    free = cube["free_response"]
    dv = cube["signature"].sel(trigger="v", drop=True)
    r = np.ascontiguousarray(free.values.reshape(-1, free.sizes["lag_pos"]))
    d = np.ascontiguousarray(dv.values.reshape(-1, dv.sizes["lag"]))
    n = r.shape[0]
    empty = int(np.isnan(r).any(axis=1).sum())
    print(
        f"signatures: {args.series} series x {args.windows} windows = {n}, lag_pos {r.shape[1]}, lag {d.shape[1]} "
        f"({ppc:.1f} samples per cycle at sigma_Y; {empty} windows without a trigger); built in {time.perf_counter() - t0:.1f} s"
    )

    estimators.estimate_all(r[0], d[0], dt)  # compile (or load the cache) outside the timings
    estimators.estimate_cube(free.isel(seed=slice(0, 2)), dv.isel(seed=slice(0, 2)), dt)

    def reference():
        return np.array([[est.value for est in reference_estimate_all(r[i], d[i], dt).values()] for i in range(n)])

    t_ref, ref = best_of(1, reference)
    t_rows, (values, _) = best_of(args.repeat, lambda: estimators._estimate_rows(r, d, dt, DEFAULT_FIT_POINTS, estimators._COLUMNS))
    t_cube, _ = best_of(args.repeat, lambda: estimators.estimate_cube(free, dv, dt))
    chunked = (free.chunk({"seed": args.chunk}), dv.chunk({"seed": args.chunk}))
    with dask.config.set(scheduler="threads"):
        t_dask, _ = best_of(args.repeat, lambda: estimators.estimate_cube(*chunked, dt)["e_hat"].compute())

    complete = ~(np.isnan(r).any(axis=1) | np.isnan(d).any(axis=1))  # windows with triggers in both
    t_ref_c, _ = best_of(1, lambda: [reference_estimate_all(r[i], d[i], dt) for i in np.flatnonzero(complete)])
    rc, dc = r[complete], d[complete]
    t_rows_c, _ = best_of(args.repeat, lambda: estimators._estimate_rows(rc, dc, dt, DEFAULT_FIT_POINTS, estimators._COLUMNS))

    values = values[:, : len(registry.ESTIMATORS)]  # the estimators of e (the kernel's last column is g)
    both = np.isfinite(ref) & np.isfinite(values)
    diff = np.abs(values[both] - ref[both])
    print(
        f"agreement: {both.sum()} finite values, max |diff| {diff.max():.2e}, "
        f"max rel {np.max(diff / np.abs(ref[both])):.2e}, NaN that differ {int((np.isnan(ref) != np.isnan(values)).sum())}"
    )
    per = 1e3 / n
    print(f"all {n} signatures:")
    print(f"  {'path':54}{'s':>9}{'ms/signature':>14}{'ratio':>9}")
    print(f"  {'reference_estimate_all, one call per signature':54}{t_ref:>9.3f}{t_ref * per:>14.4f}{1.0:>9.1f}")
    for name, t in (
        ("_estimate_rows, one batch", t_rows),
        ("estimate_cube, NumPy", t_cube),
        (f"estimate_cube, Dask ({args.chunk} series/chunk, {os.cpu_count()} cores)", t_dask),
    ):
        print(f"  {name:54}{t:>9.3f}{t * per:>14.4f}{t_ref / t:>9.1f}")
    m = int(complete.sum())
    print(f"the {m} signatures with triggers in every lag (the empty ones fail at once):")
    print(f"  {'reference_estimate_all, one call per signature':54}{t_ref_c:>9.3f}{t_ref_c * 1e3 / m:>14.4f}{1.0:>9.1f}")
    print(f"  {'_estimate_rows, one batch':54}{t_rows_c:>9.3f}{t_rows_c * 1e3 / m:>14.4f}{t_ref_c / t_rows_c:>9.1f}")

    e_hat = estimators.estimate_cube(free, dv, dt)["e_hat"]
    t_ext, _ = best_of(args.repeat, lambda: estimators.extrapolate(e_hat))
    print(f"extrapolate over {e_hat.size // e_hat.sizes['window']} rows of {args.windows} windows: {t_ext:.4f} s")


if __name__ == "__main__":
    main()

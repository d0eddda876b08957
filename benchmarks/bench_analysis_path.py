"""One analysis path: the analysis core against the two paths it replaced, answers and time.

The two paths as they stood before the core (commit 5bc118d) live here, and only here, for
this comparison:

- ``analyse_two_paths``: ``rockdec.rdd.measured.analyse`` with its own per-record sums, its own
  loop over the windows (one ``estimate_all`` and one ``half_cycle`` a window) and its own
  extrapolation loop;
- ``cube_estimates_two_paths``: the workflow's estimates (``estimate_cube`` on the cube's
  free responses and ``D_v`` signatures, the mean per replicate, ``extrapolate`` with the
  trigger counts gathered by name).

Checks (exit status 1 when one fails):

1. ``measured.analyse`` gives the same ``raw`` values (every estimator and ``g``), window
   curves and counts as ``analyse_two_paths`` to 1e-12 on simulated records of several
   lengths (a short one with empty windows), ``e`` and seeds, with ``g`` read off the record
   and given, both weightings, two records pooled and a record with a gap of NaN;
2. the workflow's estimates of a signature cube (``--cube``, default the paper scene's
   ``results/paper/signatures.nc``) equal ``cube_estimates_two_paths`` to 1e-12, both
   weightings.

Times (best of ``--repeat``, both paths taking turns in this one run, so the ratio is the result):
``measured.analyse`` on one 200,000-sample record (the calibration's analysis) and the
estimates of the cube (``rockdec.pipeline.replicates.scene_estimates``'s two extrapolations).

Run: ``PYTHONPATH=src python benchmarks/bench_analysis_path.py [--cube results/paper/signatures.nc]``.
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import xarray as xr

from rockdec.rdd import estimators, measured, registry, signatures
from rockdec import io
from rockdec.pipeline import replicates
from rockdec.physics.models import period_from_g
from rockdec.physics.simulate import calibrate_dt, simulate_block

G, SIGMA_P = 1.0, 0.003
TOLERANCE = 1e-12


# --------------------------------------------------------------------------- the two paths (5bc118d)


def _pooled_sums(records, trigger, target, widths, n_lag, dt, both_signs):
    total, count = None, None
    for y in records:
        if trigger == "a":
            s = signatures.extremum_sums(y, target, widths, n_lag, both_signs=both_signs)
        else:
            s = signatures.crossing_sums(y, target, widths, n_lag, dt, both_signs=both_signs)
        total = s.sum if total is None else total + s.sum
        count = s.count if count is None else count + s.count
    return total, count


def _half_cycle_g(r, dt):
    h = estimators.half_cycle(r, dt)
    return 2.0 * h.c1 / h.t1**2 if not h.reason else np.nan


def analyse_two_paths(records, dt, settings=None, g=None):
    """``measured.analyse`` of commit 5bc118d (its refusals left out): ``(raw, per_window, count)``."""
    opts = {**measured.DEFAULT_SETTINGS, **(settings or {})}
    records = [np.asarray(y, dtype=np.float64) - np.nanmean(y) for y in records]
    sigma_y = float(np.sqrt(np.nanmean(np.concatenate([y**2 for y in records]))))
    sigma_ydot = float(np.sqrt(np.nanmean(np.concatenate([(np.diff(y) / dt) ** 2 for y in records]))))
    windows = np.asarray(opts["windows"], dtype=np.float64)
    a = opts["level"] * sigma_y
    a_widths = windows * opts["window_max"] * a
    shortest = min(y.size for y in records)
    g_first = np.nan
    if g is None:
        cap = (shortest - 1) // 2
        n_lag = min(int(np.ceil(4 * measured._crossing_interval(records))), cap)
        while True:
            total, count = _pooled_sums(records, "a", a, a_widths[-1:], n_lag, dt, opts["both_signs"])
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", signatures.NoTriggerWarning)
                r = signatures.free_response(signatures.mean_signature(total[None], count[None], triggers=("a",))[0, -1])
            g_first = measured._sampled_crossing_g(r, dt)
            if np.isfinite(g_first) or n_lag >= cap or not count.any():
                break
            n_lag = min(2 * n_lag, cap)
    lag_g = g if g is not None else g_first
    n_lag = signatures.lag_samples(opts["n_periods"], a, lag_g, dt)
    v = opts["v_level"] * sigma_ydot
    sum_a, count_a = _pooled_sums(records, "a", a, a_widths, n_lag, dt, opts["both_signs"])
    sum_v, count_v = _pooled_sums(records, "v", v, windows * opts["dv_max"] * v, n_lag, dt, opts["both_signs"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", signatures.NoTriggerWarning)
        sig = signatures.mean_signature(np.stack([sum_a, sum_v]), np.stack([count_a, count_v]), windows=windows)
    r_all = signatures.free_response(sig[0])
    names = list(registry.ESTIMATORS) + [measured.G_NAME]
    per_window = {name: np.full(windows.size, np.nan) for name in names}
    for w in range(windows.size):
        for name, est in estimators.estimate_all(r_all[w], sig[1, w], dt, opts["fit_points"]).items():
            per_window[name][w] = est.value
        per_window[measured.G_NAME][w] = _half_cycle_g(r_all[w], dt)
    raw = {measured.G_NAME: per_window[measured.G_NAME][-1]}
    count = {"a": count_a, "v": count_v}
    for name in registry.ESTIMATORS:
        weight = count[registry.trigger(name)] if opts["weights"] == "count" else None
        raw[name] = estimators.extrapolate_to_zero(windows, per_window[name], weight).value
    assert float(period_from_g(sigma_y, lag_g) / dt) > 0
    return raw, per_window, count


def cube_estimates_two_paths(cube, fit_points, weights):
    """``replicates.replicate_curves`` then ``replicates.extrapolated`` of commit 5bc118d: ``e_hat0``."""
    per_group = estimators.estimate_cube(
        cube["free_response"], cube["signature"].sel(trigger="v", drop=True), float(cube.attrs["dt"]), fit_points=fit_points
    )["e_hat"]
    dim = replicates.series_dim(cube)
    e_hat = per_group.groupby(cube["replicate"]).mean(dim, skipna=True)
    count = cube["count"].groupby(cube["replicate"]).sum(dim)
    if weights == "count":
        w = xr.concat(
            [count.sel(trigger=registry.trigger(name), drop=True) for name in e_hat["estimator"].values], dim=e_hat["estimator"]
        ).astype(float)
        return estimators.extrapolate(e_hat, weights=w)["e_hat0"]
    return estimators.extrapolate(e_hat)["e_hat0"]


# --------------------------------------------------------------------------- checks and times


def record(e, n, seed):
    cal = calibrate_dt(e=e, g=G, sigma_p=SIGMA_P, points_per_cycle=75)
    theta, _ = simulate_block([seed], n, dt=cal["dt"], g=G, e=e, sigma_p=SIGMA_P, burn_in=cal["burn_in"])
    return theta[0], cal["dt"]


def differs(a, b) -> float:
    """Largest difference of ``a`` and ``b``, relative where ``|b| > 1``; inf where only one is NaN."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if not np.array_equal(np.isnan(a), np.isnan(b)):
        return np.inf
    ok = ~np.isnan(b)
    return float(np.max(np.abs(a[ok] - b[ok]) / np.maximum(1.0, np.abs(b[ok])), initial=0.0))


def records_of(e, n, seed, kind):
    """One record (``kind`` "one"), its halves pooled ("halves") or it with a gap of NaN ("gap")."""
    theta, dt = record(e, n, seed)
    if kind == "halves":
        return [theta[: n // 2], theta[n // 2 :]], dt
    if kind == "gap":
        theta[n // 3 : n // 3 + 500] = np.nan
    return [theta], dt


def check_records(cases) -> bool:
    worst = 0.0
    for e, n, seed, given_g, weights, kind in cases:
        records, dt = records_of(e, n, seed, kind)
        settings = {"weights": weights}
        got = measured.analyse(records, dt, settings, g=given_g)
        raw, per_window, count = analyse_two_paths(records, dt, settings, g=given_g)
        d = max(
            differs([got.raw[k] for k in raw], list(raw.values())),
            max(differs(got.per_window[k], per_window[k]) for k in per_window),
            max(differs(got.count[k], count[k]) for k in count),
        )
        worst = max(worst, d)
        empty = int((got.count["a"] == 0).sum() + (got.count["v"] == 0).sum())
        print(f"  e={e:<5} n={n:<7} seed={seed:<3} {kind:<6} g={'given' if given_g else 'read':<5} weights={weights:<6} "
              f"largest difference {d:.1e}  (e_v raw {got.raw['e_v']:.6f}, {empty} empty windows)")
    print(f"records: largest difference {worst:.1e} (tolerance {TOLERANCE:g})")
    return worst <= TOLERANCE


def check_cube(cube, fit_points) -> bool:
    worst = 0.0
    for weights in ("window", "count"):
        got = replicates.extrapolated(replicates.replicate_curves(cube, fit_points=fit_points), weights)["e_hat0"]
        expected = cube_estimates_two_paths(cube, fit_points, weights)
        d = differs(got.transpose(*expected.dims).values, expected.values)
        worst = max(worst, d)
        print(f"  cube, weights={weights:<6} largest difference {d:.1e} over {expected.size} values")
    return worst <= TOLERANCE


def best_of(repeat, *funcs):
    """Best time of each of ``funcs`` over ``repeat`` rounds, the funcs taking turns within a
    round (so a change of the machine's load falls on both)."""
    times = [[] for _ in funcs]
    for _ in range(repeat):
        for func, spent in zip(funcs, times):
            start = time.perf_counter()
            func()
            spent.append(time.perf_counter() - start)
    return [min(spent) for spent in times]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cube", default="results/paper/signatures.nc", help="a signature cube (the paper scene's)")
    parser.add_argument("--fit-points", type=int, default=5)
    parser.add_argument("--points", type=int, default=200_000, help="samples of the timed record")
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args(argv)

    print("1. measured.analyse against the two paths")
    cases = [
        (0.95, 20_000, 1, None, "window", "one"), (0.95, 200_000, 2, None, "window", "one"),
        (0.9, 60_000, 3, None, "count", "one"), (0.8, 40_000, 4, G, "window", "one"),
        (0.7, 100_000, 5, None, "window", "one"), (0.6, 30_000, 6, G, "count", "one"),
        (0.85, 150_000, 7, None, "count", "one"), (0.5, 50_000, 8, None, "window", "one"),
        (0.95, 3_000, 10, None, "count", "one"), (0.9, 80_000, 11, None, "window", "halves"),
        (0.9, 60_000, 12, None, "count", "gap"),
    ]
    ok = check_records(cases)

    cube = None
    if Path(args.cube).exists():
        print(f"2. the estimates of {args.cube} against the two paths")
        with io.open_dataset(args.cube) as ds:
            cube = ds.load()
        ok &= check_cube(cube, args.fit_points)
    else:
        print(f"2. skipped: no cube at {args.cube} (run the workflow first)")

    print(f"3. times, best of {args.repeat}")
    theta, dt = record(0.95, args.points, 9)
    measured.analyse([theta], dt), analyse_two_paths([theta], dt)  # compile (or load the cache) outside the timings
    t_old, t_new = best_of(args.repeat, lambda: analyse_two_paths([theta], dt), lambda: measured.analyse([theta], dt))
    print(f"  measured.analyse, {args.points} samples: two paths {t_old * 1e3:.1f} ms, core {t_new * 1e3:.1f} ms, "
          f"ratio core/two paths {t_new / t_old:.2f}")
    if cube is not None:
        def old():
            for weights in ("window", "count"):
                cube_estimates_two_paths(cube, args.fit_points, weights)

        def new():
            curves = replicates.replicate_curves(cube, fit_points=args.fit_points)
            for weights in ("window", "count"):
                replicates.extrapolated(curves, weights)

        old(), new()
        t_old, t_new = best_of(args.repeat, old, new)
        print(f"  cube estimates ({cube.sizes[replicates.series_dim(cube)]} signatures): two paths {t_old * 1e3:.1f} ms, "
              f"core {t_new * 1e3:.1f} ms, ratio core/two paths {t_new / t_old:.2f}")
    print("all answers equal to 1e-12" if ok else "ANSWERS DIFFER")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())

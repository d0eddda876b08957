"""Time the one-pass signature kernels against the per-window reference.

A plain script (not a test): prints timings, never asserts them.

    python benchmarks/bench_signatures.py [--series 2000] [--points 6000] [--windows 10]
    python benchmarks/bench_signatures.py --threads [--chunk 250] [--groups 1000 10]

The record is like the paper's: ``--series`` stationary series of ``--points`` samples at
about 75 samples per rocking cycle at amplitude ``sigma_Y``, simulated by
``rockdec.physics.simulate.simulate_block`` (exact event-driven rocking, e = 0.95) or, with
``--source ar2`` or when that simulator is missing, by a linear oscillator under white
noise (AR(2), 75 samples per period). Trigger settings are the package defaults: level
``2 sigma_Y``, ``da_max = 0.28 a``, windows ``da_max * (1..W)/W``, lags 2.5 periods at
amplitude ``a`` (eq. 5), ``D_v`` at ``v = sigma_Ydot`` with ``dv_max = 0.28 v``.

``--threads`` times ``signature_cube`` on Dask chunks of ``--chunk`` series pooled into
groups of ``--groups`` series (1000 as in the paper's scene, 10 as in its groups of ten),
with the threaded scheduler on 1 and on 2 workers (and, as the bound, the kernels
alone on a thread pool of 1 and 2 threads), two ways: per-series sums then an
xarray groupby (the path before the kernels summed groups) and the kernels summing
each chunk's groups (``group=``). Runs are interleaved; it prints the best and the
median of ``--repeat`` runs and the ratios.
"""

from __future__ import annotations

import argparse
import math
import os
import time
import warnings
from concurrent.futures import ThreadPoolExecutor

import dask
import numpy as np
import xarray as xr
import tests_path  # noqa: F401  (tests/ on sys.path for the reference)
from reference_signatures import reference_per_window
from scipy.signal import lfilter

from rockdec.rdd.signatures import (
    NoTriggerWarning,
    _finish,
    crossing_sums,
    extremum_sums,
    lag_samples,
    signature_cube,
)

POINTS_PER_CYCLE = 75.0


def rocking_record(n_series, n_points, e=0.95, g=1.0, sigma_p=1.0):
    """Stationary rocking series from ``rockdec.physics.simulate`` and their ``(dt, sigma_y, sigma_ydot, L)``.

    The step comes from the scale law ``sigma_Y = c S^2 / g^3`` with ``c = 290`` (near its
    value at e = 0.95) instead of a pilot calibration; the achieved samples per cycle are
    printed.
    """
    from rockdec.physics import simulate

    dt = sigma_p / g * math.sqrt(4.0 * math.sqrt(2.0 * 290.0) / POINTS_PER_CYCLE)
    burn_in = simulate.default_burn_in(e, POINTS_PER_CYCLE)
    theta, _ = simulate.simulate_block(np.arange(n_series), n_points, dt=dt, g=g, e=e, sigma_p=sigma_p, burn_in=burn_in)
    stats = simulate.pilot_statistics(theta, dt, g)
    n_lag = lag_samples(2.5, 2.0 * stats["sigma_y"], g, dt)
    source = f"rockdec.physics.simulate (e = {e}, {stats['points_per_cycle']:.1f} samples per cycle at sigma_Y)"
    return theta, dt, stats["sigma_y"], stats["sigma_ydot"], n_lag, g, source


def ar2_record(n_series, n_points, zeta=0.05, seed=0):
    """Linear-oscillator stand-in: AR(2) series, 75 samples per period, lags 2.5 periods."""
    w = 2 * np.pi / POINTS_PER_CYCLE
    r = np.exp(-zeta * w)
    a = [1.0, -2 * r * np.cos(w * np.sqrt(1 - zeta**2)), r * r]
    burn = int(10 / (zeta * w))
    eps = np.random.default_rng(seed).standard_normal((n_series, n_points + burn))
    y = lfilter([1.0], a, eps, axis=-1)[:, burn:]
    source = f"AR(2) linear oscillator (zeta = {zeta}, {POINTS_PER_CYCLE:.0f} samples per period)"
    return y, 1.0, y.std(), np.diff(y, axis=-1).std(), round(2.5 * POINTS_PER_CYCLE), None, source


def best_of(repeat, func):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = func()
        times.append(time.perf_counter() - t0)
    return min(times), out


def kernel_scaling(y, a, a_widths, v, v_widths, n_lag, dt, chunk, repeat):
    """The kernels alone, without Dask or xarray: chunks of series each summed into one row,
    on a thread pool of 1 and of 2 threads (the bound for the Dask runs)."""
    blocks = [y[i : i + chunk] for i in range(0, y.shape[0], chunk)]

    def one(block):
        rows_to = np.zeros(block.shape[0], dtype=np.int64)
        extremum_sums(block, a, a_widths, n_lag, rows_to=rows_to)
        crossing_sums(block, v, v_widths, n_lag, dt, rows_to=rows_to)

    times = {1: [], 2: []}
    for _ in range(repeat):
        for workers in (1, 2):
            with ThreadPoolExecutor(workers) as pool:
                t0 = time.perf_counter()
                list(pool.map(one, blocks))
                times[workers].append(time.perf_counter() - t0)
    t1, t2 = min(times[1]), min(times[2])
    print(f"kernels alone, {len(blocks)} chunks on a thread pool: 1 thread {t1:.3f} s, 2 threads {t2:.3f} s, ratio {t1 / t2:.2f}")


def thread_scaling(theta, kw, group_sizes, repeat):
    """Time the grouped cube, per-series + groupby against in-kernel groups, on 1 and 2 threads.

    Building the lazy cube (graph construction, serial) and computing it are timed apart;
    ``cpu/wall`` of the 2-thread compute shows how much of the second core was had (the
    machine may be shared).
    """
    n = theta.sizes["seed"]
    print(f"signature_cube on {n} series in chunks of {theta.chunksizes['seed'][0]}, threaded scheduler")
    for size in group_sizes:
        group = xr.DataArray(np.arange(n) // size, dims="seed", coords={"seed": theta["seed"]})
        builds = {
            # the path before the kernels summed groups: per-series sums, then xarray's groupby
            "per-series + groupby": lambda: _finish(
                signature_cube(theta, **kw)[["signature_sum", "count", "skipped"]].groupby(group.rename("group")).sum()
            ),
            "in-kernel groups": lambda: signature_cube(theta, **kw, group=group),
        }
        build, compute, cpu = ({(name, w): [] for name in builds for w in (1, 2)} for _ in range(3))
        results = {}
        for _ in range(repeat):  # interleaved: the machine's load drifts
            for name, make in builds.items():
                for workers in (1, 2):
                    with dask.config.set(scheduler="threads", num_workers=workers):
                        t0 = time.perf_counter()
                        lazy = make()
                        t1, c1 = time.perf_counter(), time.process_time()
                        results[name] = lazy.compute()
                        t2, c2 = time.perf_counter(), time.process_time()
                    build[name, workers].append(t1 - t0)
                    compute[name, workers].append(t2 - t1)
                    cpu[name, workers].append((c2 - c1) / (t2 - t1))
        old, new = results.values()
        rel = float(np.abs(old.signature_sum - new.signature_sum).max() / np.abs(old.signature_sum).max())
        same = bool((old["count"] == new["count"]).all() and (old["skipped"] == new["skipped"]).all())
        print(f"groups of {size} ({n // size} groups): counts equal {same}, max |sum difference| / max |sum| {rel:.1e}")
        total = {key: min(np.add(build[key], compute[key])) for key in build}
        best = {key: min(t) for key, t in compute.items()}
        head = ("build s", "compute 1 thr", "compute 2 thr", "cpu/wall 2", "total 1 thr", "total 2 thr", "total 1/2", "compute 1/2")
        print(f"  {'path':22}" + "".join(f"{h:>15}" for h in head))
        for name in builds:
            cells = (
                min(build[name, 1]),
                best[name, 1],
                best[name, 2],
                np.median(cpu[name, 2]),
                total[name, 1],
                total[name, 2],
                total[name, 1] / total[name, 2],
                best[name, 1] / best[name, 2],
            )
            print(f"  {name:22}" + "".join(f"{cell:>15.3f}" for cell in cells))
        for w in (1, 2):
            ratio = total["per-series + groupby", w] / total["in-kernel groups", w]
            print(f"  old / new, build + compute on {w} thread(s): {ratio:.2f}")
    print(f"  (best of {repeat} runs)")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--series", type=int, default=2000)
    parser.add_argument("--points", type=int, default=6000)
    parser.add_argument("--windows", type=int, default=10)
    parser.add_argument("--repeat", type=int, default=3, help="best of this many runs")
    parser.add_argument("--source", choices=["auto", "simulate", "ar2"], default="auto")
    parser.add_argument("--threads", action="store_true", help="time the grouped cube on 1 and 2 Dask threads instead")
    parser.add_argument("--chunk", type=int, default=250, help="series per Dask chunk (--threads)")
    parser.add_argument("--groups", type=int, nargs="+", default=[1000, 10], help="series per group (--threads)")
    args = parser.parse_args(argv)

    use_sim = args.source == "simulate"
    if args.source == "auto":
        try:
            from rockdec.physics import simulate

            use_sim = hasattr(simulate, "simulate_block")
        except ImportError:
            use_sim = False
    t0 = time.perf_counter()
    y, dt, sigma_y, sigma_ydot, n_lag, g, source = (rocking_record if use_sim else ar2_record)(args.series, args.points)
    print(f"record: {args.series} x {args.points} from {source}; generated in {time.perf_counter() - t0:.1f} s")

    rel = np.arange(1, args.windows + 1) / args.windows
    a, v = 2.0 * sigma_y, sigma_ydot
    if args.threads:
        theta = xr.DataArray(y, dims=("seed", "time"), coords={"seed": np.arange(args.series)}, attrs={"dt": dt})
        kw = dict(sigma_y=sigma_y, sigma_ydot=sigma_ydot, windows=rel, n_lag=n_lag)
        with warnings.catch_warnings():  # compile (or load the cache) outside the timings; few triggers
            warnings.simplefilter("ignore", NoTriggerWarning)
            signature_cube(theta[:2, :500], **dict(kw, n_lag=5), group=xr.DataArray([0, 0], dims="seed"))
        kernel_scaling(y, a, rel * 0.28 * a, v, rel * 0.28 * v, n_lag, dt, args.chunk, args.repeat)
        thread_scaling(theta.chunk({"seed": args.chunk}), kw, args.groups, args.repeat)
        return
    cases = {
        "D_a": (lambda: extremum_sums(y, a, rel * 0.28 * a, n_lag), lambda: reference_per_window(y, "a", a, rel * 0.28 * a, n_lag)),
        "D_v": (
            lambda: crossing_sums(y, v, rel * 0.28 * v, n_lag, dt),
            lambda: reference_per_window(y, "v", v, rel * 0.28 * v, n_lag, dt=dt),
        ),
    }
    extremum_sums(y[:2, :500], a, rel, 5)  # compile (or load the cache) outside the timings
    reference_per_window(y[:2, :500], "v", v, rel, 5, dt=dt)
    width = 2 * n_lag + 1
    print(f"lags: 2L+1 = {width}, windows: {args.windows}, best of {args.repeat}")
    print(f"{'trigger':8}{'triggers':>10}{'one-pass s':>12}{'per-window s':>14}{'ratio':>8}{'one-pass trig*lag/s':>22}")
    for name, (one_pass, per_window) in cases.items():
        t_one, res = best_of(args.repeat, one_pass)
        t_ref, ref = best_of(args.repeat, per_window)
        assert np.array_equal(res.count, ref.count)
        n_trig = int(res.count[..., -1].sum())
        print(f"{name:8}{n_trig:>10}{t_one:>12.3f}{t_ref:>14.3f}{t_ref / t_one:>8.1f}{n_trig * width / t_one:>22.3e}")

    theta = xr.DataArray(y, dims=("seed", "time"), attrs={"dt": dt})
    kw = dict(sigma_y=sigma_y, sigma_ydot=sigma_ydot, windows=rel, n_lag=n_lag)
    t_cube, _ = best_of(args.repeat, lambda: signature_cube(theta, **kw))
    threads = os.cpu_count()
    t_dask, _ = best_of(args.repeat, lambda: signature_cube(theta.chunk({"seed": 250}), **kw).compute())
    print(f"signature_cube, both triggers: NumPy {t_cube:.3f} s; Dask (chunks of 250 series, {threads} cores) {t_dask:.3f} s")


if __name__ == "__main__":
    main()

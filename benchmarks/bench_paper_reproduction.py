"""The paper run from empty against an independent reproduction of its eq. 28 table, in one run.

Each is timed in a fresh process (wall seconds, and CPU seconds of the process and the
children it waited for, ``os.wait4``), in turns over ``--repeat`` rounds (the project
first in odd rounds, the reproduction first in even ones), so that both see the same load
on a shared machine:

1. **The project**: ``snakemake --cores N`` from an empty ``results/`` in a temporary copy
   of the workflow, default scene ``paper`` (:func:`bench_paper.paper_run`, whose no-op
   rerun is not counted). Numba's cache is whatever the run finds (its state is printed:
   the index files under ``NUMBA_CACHE_DIR`` or under the tree's ``src/``); with
   ``--cold-numba`` each run, and each reproduction, gets an empty ``NUMBA_CACHE_DIR`` of
   its own, as in a fresh clone.
2. **The reproduction**: the same work from the scene's settings in ``config/config.yaml``
   only (no output of the project is read), with the tests' reference implementations:
   ``tests/rocking_vectorised.py`` simulates every series (plain NumPy, its own random
   numbers and seeds), ``tests/reference_signatures.py`` sums the Random Decrement
   signatures window by window (it calls the package's signature kernel once per
   window), ``tests/reference_estimators.py`` reads every estimator at every window, and
   the window-weighted line to zero window (paper §5) is written here. The scene has no
   ``dt``, so the step is the scale law's (docs/explanation/method/simulation.md §3.4,
   ``sigma_Y = c S^2/g^3``, ``T(sigma_Y) = 4 sqrt(2 sigma_Y/g) = N dt``) with ``c`` measured
   by a pilot of the same simulator (2 x 256 series of 4000 points after the burn-in of
   ``20 N/(1 - e^4)`` steps) at the step of the first guess ``c = 290``; ``sigma_Y`` and
   the sampled slope's ``sigma_Ydot`` of the pilot, carried to the chosen step by the scale
   law, set the triggers. Replicates x series x points as the scene's, on ``--processes``
   processes (multiprocessing, a replicate a task).

Prints, for every round, both times and the ratio project / reproduction (wall and CPU;
the result: their medians over the rounds), then both eq. 28 tables side by side with
their difference in standard errors, ``(mean_project - mean_reproduction) /
sqrt(std_p^2/n_p + std_r^2/n_r)``, and the project's step (its ``run.json``, printed
beside the reproduction's, never read by it).

Run: ``PYTHONPATH=src python benchmarks/bench_paper_reproduction.py`` (``--cores``,
``--processes``, ``--repeat``, ``--cold-numba``, ``--scene``). Measures; asserts nothing.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shutil
import statistics
import sys
import tempfile
from pathlib import Path

from bench_paper import REPO, paper_run, timed

TESTS = REPO / "tests"

#: Defaults of the scene's ``signatures`` section (src/rockdec/scene_schema.yaml).
SIGNATURE_DEFAULTS = {"level": 2.0, "windows": [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0], "window_max": 0.28,
                      "v_level": 1.0, "dv_max": 0.28, "n_periods": 2.5, "both_signs": True}
#: The first guess of the scale law's number ``c`` at e = 0.95 (docs/explanation/method/simulation.md §3.4).
C_GUESS = 290.0
#: The pilot: tasks x series of points after the burn-in.
PILOT = (2, 256, 4000)
#: Series summed at once into a replicate's signature (memory: this many x windows x lags).
CHUNK = 250
#: First seed of the reproduction's series (its simulator's streams are its own anyway).
SEED0 = 10_000_000


def step_for(c: float, sigma_p: float, g: float, n: float) -> float:
    """The step giving ``n`` samples per cycle at ``sigma_Y = c S^2/g^3`` (module docstring)."""
    return sigma_p / g * math.sqrt(4.0 * math.sqrt(2.0 * c) / n)


def pilot(task: tuple) -> tuple[float, float]:
    """Mean square of theta and of its sampled slope over one task's pilot series."""
    import numpy as np
    from rocking_vectorised import simulate_records

    seeds, n_points, dt, g, e, sigma_p, burn_in = task
    theta = simulate_records(seeds, n_points, dt=dt, g=g, e=e, sigma_p=sigma_p, burn_in=burn_in)
    return float(np.mean(theta**2)), float(np.mean((np.diff(theta, axis=1) / dt) ** 2))


def replicate(task: tuple) -> dict:
    """One replicate: its series simulated, pooled into one signature per trigger and window,
    every estimator at every window and the window-weighted line to zero window."""
    import numpy as np
    from reference_estimators import reference_estimate_all
    from reference_signatures import reference_per_window
    from rocking_vectorised import simulate_records

    seeds, p = task
    theta = simulate_records(seeds, p["n_points"], dt=p["dt"], g=p["g"], e=p["e"], sigma_p=p["sigma_p"], burn_in=p["burn_in"])
    sums, counts = {}, {}
    for trigger in ("a", "v"):
        parts = [reference_per_window(theta[i:i + CHUNK], trigger, p[trigger], p[f"{trigger}_widths"], p["n_lag"], dt=p["dt"],
                                      both_signs=p["both_signs"]) for i in range(0, len(seeds), CHUNK)]
        sums[trigger] = sum(part.sum.sum(axis=0) for part in parts)
        counts[trigger] = sum(part.count.sum(axis=0) for part in parts)
    with np.errstate(invalid="ignore", divide="ignore"):
        d_a, d_v = (sums[t] / counts[t][:, None] for t in ("a", "v"))
    n_lag = p["n_lag"]
    r = 0.5 * (d_a[:, n_lag:] + d_a[:, n_lag::-1])  # the even part of D_a: the free response (eq. 20)
    windows = np.asarray(p["windows"])
    curves = {}
    for k in range(windows.size):
        fit = {"fit_points": p["fit_points"]} if p["fit_points"] else {}  # else the estimators' default
        for name, est in reference_estimate_all(r[k], d_v[k], p["dt"], **fit).items():
            curves.setdefault(name, []).append(est.value)
    out = {}
    for name, y in curves.items():
        trigger = "v" if name == "e_v" else "a"
        w = windows if p["weights"] == "window" else counts[trigger].astype(float)
        y = np.asarray(y)
        keep = np.isfinite(y) & (w > 0)
        x, y, w = windows[keep], y[keep], w[keep]
        if x.size < 2:
            out[name] = math.nan
            continue
        xm, ym = np.average(x, weights=w), np.average(y, weights=w)
        slope = np.sum(w * (x - xm) * (y - ym)) / np.sum(w * (x - xm) ** 2)
        out[name] = float(ym - slope * xm)
    return out


def reproduce(scene_name: str, processes: int, out: Path) -> None:
    """The reproduction of the module docstring, in this process and ``processes`` workers;
    writes its settings and every replicate's zero-window estimates to ``out`` (JSON)."""
    import multiprocessing

    import numpy as np
    import yaml

    sys.path.insert(0, str(TESTS))
    scene = yaml.safe_load((REPO / "config" / "config.yaml").read_text())["scenes"][scene_name]
    system, excitation, records = scene["system"], scene["excitation"], scene["records"]
    sig = {**SIGNATURE_DEFAULTS, **scene.get("signatures", {})}
    e, sigma_p, n = system["e"], excitation["sigma_p"], excitation["points_per_cycle"]
    g = system["nu"] ** 2 * system["theta_cr"]
    burn_in = int(math.ceil(20.0 * n / (1.0 - e**4)))
    with multiprocessing.get_context("fork").Pool(processes) as pool:
        dt0 = excitation.get("dt") or step_for(C_GUESS, sigma_p, g, n)
        tasks, per_task, points = PILOT
        moments = pool.map(pilot, [(SEED0 - (k + 1) * per_task + np.arange(per_task), points, dt0, g, e, sigma_p, burn_in)
                                   for k in range(tasks)])
        sigma_y0 = math.sqrt(np.mean([m[0] for m in moments]))
        sigma_ydot0 = math.sqrt(np.mean([m[1] for m in moments]))
        c = sigma_y0 * dt0**2 * g**3 / sigma_p**4
        dt = excitation.get("dt") or step_for(c, sigma_p, g, n)
        sigma_y, sigma_ydot = sigma_y0 * (dt0 / dt) ** 2, sigma_ydot0 * dt0 / dt
        a, v = sig["level"] * sigma_y, sig["v_level"] * sigma_ydot
        windows = np.asarray(sig["windows"], dtype=float)
        settings = {
            "e": e, "g": g, "sigma_p": sigma_p, "dt": dt, "burn_in": burn_in, "n_points": records["n_points"], "c": c,
            "sigma_y": sigma_y, "sigma_ydot": sigma_ydot, "a": a, "v": v, "windows": windows.tolist(),
            "a_widths": (windows * sig["window_max"] * a).tolist(), "v_widths": (windows * sig["dv_max"] * v).tolist(),
            "n_lag": int(round(sig["n_periods"] * 4.0 * math.sqrt(2.0 * a / g) / dt)), "both_signs": bool(sig["both_signs"]),
            "fit_points": scene.get("estimates", {}).get("fit_points"), "weights": scene.get("estimates", {}).get("weights", "window"),
        }
        n_series = records["series_per_replicate"]
        estimates = pool.map(replicate, [(SEED0 + k * n_series + np.arange(n_series), settings)
                                         for k in range(records["replicates"])], chunksize=1)
        pool.close()
        pool.join()
    out.write_text(json.dumps({"settings": settings, "replicates": estimates}))


def numba_cache(env: dict) -> str:
    """Numba's cache as a run with ``env`` finds it, in words."""
    where = env.get("NUMBA_CACHE_DIR") or os.environ.get("NUMBA_CACHE_DIR")
    folder = Path(where) if where else REPO / "src"
    found = len(list(folder.rglob("*.nbi"))) if folder.exists() else 0
    return f"warm ({found} index files under {folder})" if found else f"empty ({folder})"


def table_rows(path: Path) -> dict:
    """``estimator -> (n, mean, std)`` of a ``table.csv``."""
    import csv

    with open(path) as f:
        return {row["estimator"]: (int(float(row["n"])), float(row["mean"]), float(row["std"])) for row in csv.DictReader(f)}


def stats(values: list) -> tuple[int, float, float]:
    """``(n, mean, std with ddof 1)`` of the finite values."""
    finite = [v for v in values if math.isfinite(v)]
    return len(finite), statistics.fmean(finite) if finite else math.nan, statistics.stdev(finite) if len(finite) > 1 else math.nan


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="paper")
    parser.add_argument("--cores", type=int, default=2, help="snakemake --cores (default %(default)s)")
    parser.add_argument("--processes", type=int, default=2, help="processes of the reproduction (default %(default)s)")
    parser.add_argument("--repeat", type=int, default=1, help="rounds (default %(default)s)")
    parser.add_argument("--cold-numba", action="store_true", help="an empty NUMBA_CACHE_DIR for every run")
    parser.add_argument("--reproduce", type=Path, help=argparse.SUPPRESS)  # the child: the reproduction, its JSON here
    args = parser.parse_args()
    if args.reproduce:
        reproduce(args.scene, args.processes, args.reproduce)
        return
    base = Path(tempfile.mkdtemp(prefix="rockdec_bench_reproduction_"))
    rounds = []
    try:
        for k in range(args.repeat):
            row = {}

            def env_for(what):
                if not args.cold_numba:
                    return {}
                folder = base / f"numba_{what}_{k}"
                folder.mkdir()
                return {"NUMBA_CACHE_DIR": str(folder)}

            def project():
                env = env_for("project")
                row["project_cache"] = numba_cache(env)
                run = paper_run(REPO, base / f"project_{k}", args.cores, args.scene, env)
                row["project"] = (run["wall"], run["cpu"])
                row["table"] = table_rows(run["root"] / "results" / args.scene / "table.csv")
                row["project_dt"] = json.loads((run["root"] / "results" / args.scene / "run.json").read_text()).get("dt", math.nan)

            def independent():
                env = {**env_for("reproduction"), "PYTHONPATH": str(REPO / "src")}
                row["reproduction_cache"] = numba_cache(env)
                out = base / f"reproduction_{k}.json"
                command = [sys.executable, __file__, "--reproduce", str(out), "--scene", args.scene, "--processes", str(args.processes)]
                row["reproduction"] = timed(command, env)
                row["result"] = json.loads(out.read_text())

            for step in ((project, independent) if k % 2 == 0 else (independent, project)):
                step()
            rounds.append(row)
            print(f"round {k + 1}: project {row['project'][0]:.1f} s, reproduction {row['reproduction'][0]:.1f} s",
                  file=sys.stderr, flush=True)
    finally:
        shutil.rmtree(base, ignore_errors=True)
    for k, row in enumerate(rounds):
        (pw, pc), (rw, rc) = row["project"], row["reproduction"]
        print(f"round {k + 1}: project (snakemake --cores {args.cores}, numba cache {row['project_cache']}) {pw:.1f} s wall, "
              f"{pc:.1f} s CPU; reproduction ({args.processes} processes, numba cache {row['reproduction_cache']}) "
              f"{rw:.1f} s wall, {rc:.1f} s CPU; project / reproduction {pw / rw:.2f} wall, {pc / rc:.2f} CPU")
    walls = [r["project"][0] / r["reproduction"][0] for r in rounds]
    cpus = [r["project"][1] / r["reproduction"][1] for r in rounds]
    print(f"project / reproduction (median of {len(rounds)}): {statistics.median(walls):.2f} wall, {statistics.median(cpus):.2f} CPU")
    last = rounds[-1]
    s = last["result"]["settings"]
    print(f"reproduction's step: dt = {s['dt']:.6g} s (scale law, c = {s['c']:.1f} from its pilot), burn-in {s['burn_in']} steps, "
          f"sigma_Y = {s['sigma_y']:.4g} rad, sigma_Ydot = {s['sigma_ydot']:.4g} rad/s, L = {s['n_lag']} lags; "
          f"the project's step (its run.json, printed only): dt = {last['project_dt']:.6g} s")
    print("\n| estimator | project mean | project std | reproduction mean | reproduction std | difference / SE |")
    print("|---|---:|---:|---:|---:|---:|")
    for name, (n_p, mean_p, std_p) in last["table"].items():
        n_r, mean_r, std_r = stats([rep[name] for rep in last["result"]["replicates"]])
        se = math.sqrt(std_p**2 / n_p + std_r**2 / n_r) if n_p and n_r else math.nan
        print(f"| {name} | {mean_p:.4f} | {std_p:.4f} | {mean_r:.4f} | {std_r:.4f} | {(mean_p - mean_r) / se:+.2f} |")


if __name__ == "__main__":
    main()

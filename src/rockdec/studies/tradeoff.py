"""Speed against accuracy: what each knob of a scene costs and what it buys.

Every knob of :data:`KNOBS` is moved one at a time away from a base scene (the ``tradeoff``
scene of ``config/config.yaml``, :func:`base_settings`, :func:`configurations`); each
configuration is run end to end for every replicate (:func:`run_study`) and measured twice:
its **cost** in CPU seconds of the process (the step calibration of a density reported
apart, ``calibration_cpu_s``) and the **accuracy** of each estimator against the scene's
``e`` (:func:`rockdec.report.tables.bias_row`: ``bias``, ``std``, ``rmse`` and
``ci95 = |bias| + 1.96 std``). :func:`pareto_front` and :func:`recommend` pick among the
configurations run; the table is :func:`study_table`, its Markdown
:func:`rockdec.report.tables.tradeoff_markdown`, its plot
:func:`rockdec.studies.figures.pareto_figure`. The model is always the simplified one
(eq. 4), whose response depends only on ``e`` and the sampling density.

Explanation: docs/explanation/studies/beyond.md (speed against accuracy: the measures and
the choices the study makes).
"""

from __future__ import annotations

import copy
import json
import time
import warnings
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pandas as pd
import xarray as xr

from rockdec import engine
from rockdec.pipeline import replicates
from rockdec.physics import fixed_step, run
from rockdec.report import tables
from rockdec.physics.run import Run

__all__ = [
    "ACCURACY_CLASSES", "CRITERIA", "KNOBS", "SETTING_COLUMNS", "base_settings", "configurations",
    "knob_settings", "pareto_front", "recommend", "run_study", "study_table", "variant_scene",
]

KNOBS = {
    "points_per_cycle": (5, 10, 20, 35, 75, 150, 300, 1000),
    "n_points": (1500, 3000, 6000, 12000),
    "series_per_replicate": (25, 50, 100, 200, 400),
    "n_windows": (2, 5, 10),
    "level": (1.5, 2.0, 2.5),
    "n_periods": (1.0, 2.5),
    "simulator": ("exact", "fixed_step"),
    "fixed_step_points_per_cycle": (75, 150, 300, 1000),
}
"""Knob -> values, each moved alone from the base scene. ``points_per_cycle``: samples per
cycle at ``sigma_Y`` (eq. 5, sets ``dt``); ``n_points``: points per series (at the base
density); ``series_per_replicate``: series pooled into one signature; ``n_windows``: window
sizes of the zero-window extrapolation; ``level``: trigger level ``a/sigma_Y``;
``n_periods``: lag range in periods at ``a`` (it matters for ``e_g``; the others move only
through the triggers lost at the record ends); ``simulator``;
``fixed_step_points_per_cycle``: the fixed-step simulator at another density."""

SETTINGS = ("simulator", "points_per_cycle", "n_points", "series_per_replicate", "n_windows", "level", "n_periods")
"""The settings that make up a configuration (one per knob; the last knob sets two)."""

ACCURACY_CLASSES = (0.005, 0.01, 0.02, 0.05)
"""Half-widths of the accuracy classes of :func:`recommend` ("e within +-0.01 (95 %)")."""

CRITERIA = ("ci95", "rmse")
"""What :func:`recommend` can hold to a tolerance."""

ACCURACY_COLUMNS = ["n", "mean", "bias", "std", "rmse", "ci95"]
"""The replicate statistics (:func:`rockdec.report.tables.bias_row`) of :func:`study_table`."""

SETTING_COLUMNS = ["kind", "points_per_cycle", "n_points", "series_per_replicate", "n_windows", "level", "n_periods"]
"""Columns of :func:`study_table` that identify a configuration."""

MAX_CHUNK_POINTS = 2_000_000
"""Largest number of samples in one Dask chunk (seeds per chunk shrink for long series)."""


# --------------------------------------------------------------------------- configurations


def base_settings(scene: dict) -> dict:
    """The configuration of the scene itself (see :data:`SETTINGS`)."""
    sig = scene["signatures"]
    return {
        "simulator": "exact",
        "points_per_cycle": float(scene["excitation"]["points_per_cycle"]),
        "n_points": int(scene["records"]["n_points"]),
        "series_per_replicate": int(scene["records"]["series_per_replicate"]),
        "n_windows": len(sig["windows"]),
        "level": float(sig["level"]),
        "n_periods": float(sig["n_periods"]),
    }


def knob_settings(base: dict, knob: str, value) -> dict:
    """``base`` with one knob moved to ``value``."""
    if knob == "fixed_step_points_per_cycle":
        return {**base, "simulator": fixed_step.KIND, "points_per_cycle": float(value)}
    if knob not in base:
        raise ValueError(f"unknown knob '{knob}'; known knobs: {', '.join(KNOBS)}")
    if knob == "simulator" and value not in ("exact", fixed_step.KIND):
        raise ValueError(f"unknown simulator '{value}'; use 'exact' or '{fixed_step.KIND}'")
    return {**base, knob: type(base[knob])(value)}


def configurations(scene: dict, knobs: dict | None = None) -> list[tuple[str, str, dict]]:
    """``(knob, value label, settings)`` for every knob value, in the order of ``knobs``.

    A value equal to the base's appears under its knob; its settings equal
    :func:`base_settings`, so it is run once (see :func:`run_study`).
    """
    base = base_settings(scene)
    knobs = KNOBS if knobs is None else knobs
    return [(knob, _label(value), knob_settings(base, knob, value)) for knob, values in knobs.items() for value in values]


def _label(value) -> str:
    return value if isinstance(value, str) else f"{value:g}"


def _key(settings: dict) -> tuple:
    return tuple(settings[name] for name in SETTINGS)


def variant_scene(scene: dict, settings: dict) -> dict:
    """A copy of ``scene`` run with ``settings`` (module docstring: how each knob applies)."""
    base = base_settings(scene)
    out = copy.deepcopy(scene)
    density = settings["points_per_cycle"] / base["points_per_cycle"]
    n_points = max(2, int(round(settings["n_points"] * density)))
    out["excitation"]["points_per_cycle"] = settings["points_per_cycle"]
    rec = out["records"]
    rec["n_points"] = n_points
    rec["series_per_replicate"] = settings["series_per_replicate"]
    rec["chunk_seeds"] = max(1, min(rec["chunk_seeds"], MAX_CHUNK_POINTS // n_points))
    sig = out["signatures"]
    if settings["n_windows"] != len(sig["windows"]):
        n = settings["n_windows"]
        sig["windows"] = [round(k / n, 12) for k in range(1, n + 1)]
    sig["level"] = settings["level"]
    sig["n_periods"] = settings["n_periods"]
    return out


# --------------------------------------------------------------------------- calibration


def _calibrate(scene: dict, points_per_cycle: float, simulators: set, pilot: dict) -> dict:
    """The run at one density, per simulator (:func:`rockdec.physics.run.from_scene` of the scene at
    that density, then :func:`rockdec.physics.run.with_model` for the fixed-step integrator), and the
    CPU s of this thread: ``{simulator: (run, cpu_s)}``."""
    start = time.thread_time()
    at_density = copy.deepcopy(scene)
    at_density["model"] = "simplified"
    at_density["excitation"].update(points_per_cycle=points_per_cycle, dt=None)
    exact = run.from_scene(at_density, pilot=pilot)
    out = {"exact": exact}
    if fixed_step.KIND in simulators:
        out[fixed_step.KIND] = run.with_model(exact, "fixed_step", pilot)
    cpu = time.thread_time() - start
    return {kind: (entry, cpu) for kind, entry in out.items()}


def calibrations(scene: dict, settings: list[dict], threads: int = 1, pilot: dict | None = None) -> dict:
    """Calibration of every density the configurations use, computed once each.

    Returns ``{(points_per_cycle, simulator): (run, calibration_cpu_s)}``
    (:class:`rockdec.physics.run.Run`); the densities run in ``threads`` threads (the kernels
    release the GIL).
    """
    pilot = run.PILOT if pilot is None else pilot
    wanted: dict[float, set] = {}
    for s in settings:
        wanted.setdefault(s["points_per_cycle"], set()).add(s["simulator"])
    # longest first, so the threads finish together
    order = sorted(wanted, reverse=True)
    with ThreadPoolExecutor(max_workers=max(1, threads)) as pool:
        results = list(pool.map(lambda ppc: _calibrate(scene, ppc, wanted[ppc], pilot), order))
    return {(ppc, kind): entry for ppc, result in zip(order, results) for kind, entry in result.items()}


# --------------------------------------------------------------------------- one configuration


def configuration_estimates(scene: dict, settings: dict, contract: Run, threads: int = 1) -> tuple[xr.DataArray, float, float]:
    """Run one configuration end to end; returns ``(e_hat0(estimator, replicate), cpu_s, wall_s)``.

    ``contract`` is the run of :func:`calibrations` for its density and simulator. Timed:
    graph construction, simulation, signatures (Dask threads: the cost is CPU seconds of
    this process, so the study stays on threads whatever :mod:`rockdec.engine` says),
    estimates and extrapolation.
    """
    start_cpu, start_wall = time.process_time(), time.perf_counter()
    variant = variant_scene(scene, settings)
    reading, options = variant["estimates"]["reading"], variant["estimates"]
    with engine.session(threads, scheduler="threads"):  # CPU seconds of this process: threads only
        cube = replicates.scene_cubes(contract, variant["records"], variant["signatures"], [reading], threads=threads)[reading]
    e_hat0 = replicates.replicate_estimates(cube, fit_points=options["fit_points"], weights=options["weights"])["e_hat0"]
    return e_hat0, time.process_time() - start_cpu, time.perf_counter() - start_wall


def _warm_up(scene: dict, calibration: dict, simulators: set) -> None:
    """Compile (or load) every numba kernel once, so no configuration pays for it."""
    small = copy.deepcopy(scene)
    small["records"].update(replicates=1, series_per_replicate=2, n_points=2000, chunk_seeds=2)
    for kind in simulators:
        settings = {**base_settings(small), "simulator": kind}
        contract = next(entry for (_, k), (entry, _) in calibration.items() if k == kind)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            configuration_estimates(small, settings, contract)


# --------------------------------------------------------------------------- the study


def run_study(
    scene: dict, knobs: dict | None = None, threads: int = 1, pilot: dict | None = None, progress=None
) -> xr.Dataset:
    """Every configuration of ``knobs`` (default :data:`KNOBS`) from ``scene``, cost and estimates.

    Returns a Dataset with dimension ``config`` (one per knob value, the base repeated under
    each knob that lists it, flagged ``base = 1``, computed once): ``e_hat0(config,
    estimator, replicate)``, ``cpu_s``, ``wall_s``, ``calibration_cpu_s`` and the
    calibration (``dt``, ``burn_in``, ``sigma_y``, ``sigma_ydot``, achieved
    ``points_per_cycle_at_sigma_y``) per configuration; coordinates ``knob``, ``value`` and
    every setting. Attributes: ``model`` (always ``"simplified"``, see the module
    docstring), ``e_target``, ``replicates``, ``threads``, ``knobs``.
    ``progress``, a callable taking a string, hears of each step (the rule's log).
    """
    say = progress if progress is not None else (lambda text: None)
    if scene.get("model", "simplified") == "housner":
        raise ValueError(
            "the speed/accuracy study runs the simplified model (eq. 4) only; set the scene's model to "
            "'simplified' or 'auto' (the study then runs eq. 4 at every amplitude)"
        )
    configs = configurations(scene, knobs)
    base_key = _key(base_settings(scene))
    unique: dict[tuple, dict] = {}
    for _, _, settings in configs:
        unique.setdefault(_key(settings), settings)
    say(f"{len(configs)} configurations, {len(unique)} distinct; calibrating the step")
    cal = calibrations(scene, list(unique.values()), threads=threads, pilot=pilot)
    for (ppc, kind), entry in sorted(cal.items()):
        say(f"calibration {ppc:g} points per cycle, {kind}: {entry}")
    _warm_up(scene, cal, {s["simulator"] for s in unique.values()})
    results = {}
    for key, settings in unique.items():
        results[key] = configuration_estimates(scene, settings, cal[(settings["points_per_cycle"], settings["simulator"])][0], threads)
        say(f"{settings}: {results[key][1]:.2f} CPU s, {results[key][2]:.2f} s wall")
    rows = [results[_key(s)] for _, _, s in configs]
    cals = [cal[(s["points_per_cycle"], s["simulator"])] for _, _, s in configs]
    runs, cal_cpu = [c[0] for c in cals], [c[1] for c in cals]
    variants = [variant_scene(scene, s) for _, _, s in configs]
    e_hat0 = xr.concat([r[0] for r in rows], dim="config")
    e_hat0.attrs = {"units": "1", "long_name": "estimate of e extrapolated to zero window, per replicate"}

    def per_config(values, units, long_name, dtype=float):
        return ("config", np.asarray(values, dtype=dtype), {"units": units, "long_name": long_name})

    ds = xr.Dataset(
        {
            "e_hat0": e_hat0,
            "cpu_s": per_config([r[1] for r in rows], "s", "CPU time of the configuration (all threads)"),
            "wall_s": per_config([r[2] for r in rows], "s", "wall-clock time of the configuration"),
            "calibration_cpu_s": per_config(
                cal_cpu, "s", "CPU time of the one-off step calibration at this density"
            ),
            "dt": per_config([r.dt for r in runs], "s", "time step"),
            "burn_in": per_config([r.burn_in for r in runs], "1", "steps discarded before recording", dtype=np.int64),
            "sigma_y": per_config([r.sigma_y for r in runs], "rad", "stationary response standard deviation (pilot)"),
            "sigma_ydot": per_config([r.sigma_ydot for r in runs], "rad s-1", "std of the sampled slope (pilot)"),
            "points_per_cycle_at_sigma_y": per_config(
                [r.points_per_cycle for r in runs], "1", "achieved samples per cycle at sigma_Y of the simulator used (eq. 5)"
            ),
        },
        coords={
            "config": ("config", [f"{k}={v}" for k, v, _ in configs], {"long_name": "knob=value"}),
            "knob": ("config", [k for k, _, _ in configs], {"long_name": "the knob moved from the base scene"}),
            "value": ("config", [v for _, v, _ in configs], {"long_name": "value of the knob"}),
            "base": ("config", np.array([_key(s) == base_key for _, _, s in configs], dtype=np.int8),
                     {"long_name": "1 where the configuration is the base scene"}),
            "simulator": ("config", [s["simulator"] for _, _, s in configs], {"long_name": "simulator kind"}),
            "points_per_cycle": ("config", [s["points_per_cycle"] for _, _, s in configs],
                                 {"units": "1", "long_name": "target samples per cycle at sigma_Y (sets dt)"}),
            "n_points": ("config", [v["records"]["n_points"] for v in variants], {"units": "1", "long_name": "points per series"}),
            "series_per_replicate": ("config", [s["series_per_replicate"] for _, _, s in configs],
                                     {"units": "1", "long_name": "series pooled per replicate"}),
            "n_windows": ("config", [s["n_windows"] for _, _, s in configs], {"units": "1", "long_name": "window sizes"}),
            "level": ("config", [s["level"] for _, _, s in configs], {"units": "1", "long_name": "trigger level a/sigma_Y"}),
            "n_periods": ("config", [s["n_periods"] for _, _, s in configs],
                          {"units": "1", "long_name": "lag range in periods at amplitude a"}),
            "fit_points": ("config", [v["estimates"]["fit_points"] for v in variants],
                           {"units": "1", "long_name": "points per side of the e_v slope fits"}),
        },
        attrs={
            "model": "simplified",
            "e_target": float(scene["system"]["e"]),
            "replicates": int(scene["records"]["replicates"]),
            "threads": int(threads),
            "knobs": json.dumps({k: list(v) for k, v in (KNOBS if knobs is None else knobs).items()}),
        },
    )
    return ds


# --------------------------------------------------------------------------- statistics


def study_table(ds: xr.Dataset) -> pd.DataFrame:
    """The tidy table: one row per (configuration, estimator).

    Columns: ``knob, value, kind, base, cpu_s, cpu_s_per_replicate, estimator, n,
    replicates, mean, bias, std, rmse, ci95``, then the configuration's settings
    (``points_per_cycle, n_points, series_per_replicate, n_windows, level, n_periods,
    dt``) and ``calibration_cpu_s``.
    """
    e_target = float(ds.attrs["e_target"])
    n_rep = ds.sizes["replicate"]
    rows = []
    for i in range(ds.sizes["config"]):
        c = ds.isel(config=i)
        head = {
            "knob": str(c["knob"].values),
            "value": str(c["value"].values),
            "kind": str(c["simulator"].values),
            "base": bool(c["base"].values),
            "cpu_s": float(c["cpu_s"]),
            "cpu_s_per_replicate": float(c["cpu_s"]) / n_rep,
        }
        tail = {
            "points_per_cycle": float(c["points_per_cycle"]),
            "n_points": int(c["n_points"]),
            "series_per_replicate": int(c["series_per_replicate"]),
            "n_windows": int(c["n_windows"]),
            "level": float(c["level"]),
            "n_periods": float(c["n_periods"]),
            "dt": float(c["dt"]),
            "calibration_cpu_s": float(c["calibration_cpu_s"]),
        }
        for name in ds["estimator"].values:
            stats = tables.bias_row(c["e_hat0"].sel(estimator=name).values, e_target)
            accuracy = {k: stats[k] for k in ACCURACY_COLUMNS}
            rows.append({**head, "estimator": str(name), "replicates": n_rep, **accuracy, **tail})
    table = pd.DataFrame(rows)
    table.attrs["e_target"] = e_target
    return table


def recommend(table: pd.DataFrame, tolerance=ACCURACY_CLASSES, criterion: str = "ci95") -> pd.DataFrame:
    """The cheapest configuration within ``tolerance`` for each estimator (and tolerance).

    ``criterion = "ci95"`` (default): ``|bias| + 1.96 std <= tolerance``, i.e. "``e`` within
    ``+-tolerance`` (95 %)" for one replicate's estimate; ``"rmse"``: ``rmse <= tolerance``.
    Only configurations with an estimate in every replicate (``n == replicates``) qualify;
    the cheapest is the one of least ``cpu_s``. ``tolerance`` is a number or a sequence.
    Returns one row per (tolerance, estimator): ``tolerance, estimator, criterion, knob,
    value, kind, cpu_s, cpu_s_per_replicate, bias, std, rmse, ci95``; ``knob`` is
    ``"none"`` (and the numbers NaN) when no configuration qualifies.
    """
    if criterion not in CRITERIA:
        raise ValueError(f"unknown criterion '{criterion}'; use one of {CRITERIA}")
    tolerances = [float(tolerance)] if np.ndim(tolerance) == 0 else [float(t) for t in tolerance]
    cols = ["knob", "value", "kind", "cpu_s", "cpu_s_per_replicate", "bias", "std", "rmse", "ci95"]
    complete = table[(table["n"] == table["replicates"]) & np.isfinite(table[criterion])]
    rows = []
    for tol in tolerances:
        for name in pd.unique(table["estimator"]):
            passing = complete[(complete["estimator"] == name) & (complete[criterion] <= tol)]
            row = {"tolerance": tol, "estimator": name, "criterion": criterion}
            if passing.empty:
                row.update({c: np.nan for c in cols}, knob="none", value="", kind="")
            else:
                # stable sort: among equal costs (the base under several knobs) the first listed
                best = passing.sort_values("cpu_s", kind="stable").iloc[0]
                row.update({c: best[c] for c in cols})
                if bool(best.get("base", False)):
                    row.update(knob="base", value="")
            rows.append(row)
    return pd.DataFrame(rows, columns=["tolerance", "estimator", "criterion", *cols])


def pareto_front(cost, error) -> np.ndarray:
    """Indices of the Pareto-optimal points (no other point is both cheaper and more accurate), by cost.

    Points with a non-finite cost or error are left out; of points with equal cost only
    the most accurate can be on the front.
    """
    cost, error = np.asarray(cost, dtype=float), np.asarray(error, dtype=float)
    idx = np.flatnonzero(np.isfinite(cost) & np.isfinite(error))
    idx = idx[np.lexsort((error[idx], cost[idx]))]
    front, best = [], np.inf
    for i in idx:
        if error[i] < best:
            front.append(i)
            best = error[i]
    return np.asarray(front, dtype=int)

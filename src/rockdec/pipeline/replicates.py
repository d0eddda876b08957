"""Replicates and the readings of the paper's sizes (docs/method.md §8).

A scene's seeds form ``replicates`` of ``series_per_replicate`` series. A *reading* says
how a replicate's series become signatures and estimates:

``pooled``
    all series of the replicate pool their triggers into one signature (the default:
    it reproduces the paper's spreads, eq. 28, and its ``e_g``);
``per_series``
    one signature per series for the first 100 series (paper §5: "each point averages
    100 values"), the replicate's estimate at each window is the mean of the 100;
``groups_of_10``
    one signature per 10 consecutive series (the pooling of the paper's fig. 2c), the
    replicate's estimate the mean over its groups.

Extrapolation to zero window then runs per replicate on the window curve (paper §5).

All readings come from one pass over the series (:func:`scene_cubes`): signature sums pool
exactly by adding (docs/method.md §4.4), so the pass sums each series into the finest
partition every reading can be built from -- one *unit* per series that some reading keeps
alone, otherwise the largest block of series that every reading pools together -- and each
reading's signatures are sums of units.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import xarray as xr

from rockdec import engine
from rockdec.pipeline import series
from rockdec.rdd import estimators, signatures
from rockdec.report import tables
from rockdec.pipeline.layout import READINGS, scene_seeds
from rockdec.physics.record_model import carried_attrs
from rockdec.physics.run import Run

__all__ = [
    "READINGS", "extrapolated", "gathered", "pass_units", "reading_curves", "reading_groups",
    "readings_estimates", "replicate_curves", "replicate_estimates", "scene_cubes", "scene_estimates",
    "scene_signatures", "series_dim", "variant_cubes",
]

PER_SERIES_LIMIT = 100
"""Series per replicate in the ``per_series`` reading (the paper's 100 values a point)."""


def reading_groups(seeds: np.ndarray, reading: str) -> tuple[np.ndarray, np.ndarray]:
    """The group of every seed under a reading, and the replicate of every group.

    ``seeds`` is ``(replicate, series)``. Returns ``(group_of_seed, replicate_of_group)``:
    ``group_of_seed`` follows ``seeds.ravel()``, with labels 0..G-1 in seed order and -1
    for a seed the reading leaves out.
    """
    n_rep, n_series = seeds.shape
    if reading == "pooled":
        size, used = n_series, n_series
    elif reading == "per_series":
        size, used = 1, min(PER_SERIES_LIMIT, n_series)
    elif reading == "groups_of_10":
        size = 10
        used = (n_series // size) * size
        if used == 0:
            raise ValueError(f"the groups_of_10 reading needs at least 10 series per replicate; the scene has {n_series}")
    else:
        raise ValueError(f"unknown reading '{reading}'; use pooled, per_series or groups_of_10")
    per_rep = used // size
    group = np.full((n_rep, n_series), -1, dtype=np.int64)
    group[:, :used] = (np.arange(n_rep)[:, None] * per_rep + np.arange(used)[None, :] // size)
    return group.ravel(), np.repeat(np.arange(n_rep), per_rep)


def pass_units(seeds: np.ndarray, readings) -> tuple[np.ndarray, dict]:
    """The units of one pass that serves every reading of ``readings`` (module docstring).

    Returns ``(unit_of_seed, groups)``: ``unit_of_seed`` follows ``seeds.ravel()`` (-1 for a
    seed no reading uses); ``groups[reading] = (group_of_unit, replicate_of_group)``, with
    ``group_of_unit`` -1 for a unit the reading leaves out.
    """
    labels = {reading: reading_groups(seeds, reading) for reading in readings}
    stacked = np.stack([labels[r][0] for r in readings])
    used = np.any(stacked >= 0, axis=0)
    keys, inverse = np.unique(stacked[:, used].T, axis=0, return_inverse=True)
    unit_of_seed = np.full(stacked.shape[1], -1, dtype=np.int64)
    unit_of_seed[used] = inverse.ravel()
    return unit_of_seed, {r: (keys[:, k], labels[r][1]) for k, r in enumerate(readings)}


def series_dim(cube: xr.Dataset) -> str:
    """The dimension that holds a cube's signatures: ``seed`` (one a series) or ``group``."""
    return "seed" if "seed" in cube.dims else "group"


def scene_signatures(
    theta: xr.DataArray, settings: dict, *, sigma_y: float, sigma_ydot: float, g: float,
    group: np.ndarray | None, replicate_of_group=None,
) -> xr.Dataset:
    """The signature cube of ``theta(seed, time)`` under a scene's ``signatures`` settings.

    ``group=None`` keeps one signature per series: the cube's ``seed`` dimension holds the
    seeds, and ``replicate_of_group`` gives each seed's replicate; otherwise the sums of
    the series of each group label are pooled (``replicate_of_group=None``: no
    ``replicate`` coordinate). ``sigma_y``, ``sigma_ydot`` (stationary, of
    the run) and ``g`` set one trigger level and lag range for every series
    (docs/method.md §4.4).
    """
    cube = signatures.signature_cube(
        theta,
        sigma_y=sigma_y,
        sigma_ydot=sigma_ydot,
        level=settings["level"],
        windows=settings["windows"],
        window_max=settings["window_max"],
        v_level=settings["v_level"],
        dv_max=settings["dv_max"],
        n_periods=settings["n_periods"],
        g=g,
        both_signs=settings["both_signs"],
        group=None if group is None else xr.DataArray(group, dims="seed", coords={"seed": theta["seed"]}),
    )
    if replicate_of_group is None:
        return cube
    dim = series_dim(cube)
    return cube.assign_coords(replicate=(dim, np.asarray(replicate_of_group), {"long_name": f"replicate of the {dim}"}))


def scene_cubes(run: Run, records: dict, settings: dict, readings, series_files=(), threads: int = 1, first_replicate: int = 0,
                sums_only=()) -> dict:
    """The signature cube of every reading of ``readings``, from one pass over the series.

    Every series is simulated from its seed under ``run`` (Dask over seeds, chunks of
    ``records["chunk_seeds"]``) or, with ``series_files`` (the per-replicate files of
    ``store_series: all``), read back; either way it is analysed as float32 stores it
    (:func:`rockdec.pipeline.series.as_recorded`), so both give the same cubes bit for bit. The
    series are reduced at once to the sums of the pass's units (:func:`pass_units`), which
    add up to each reading's groups. Computed on the engine of :mod:`rockdec.engine`
    (``threads`` threads by default, each block's unit sums written into the cube's arrays as
    it ends, :func:`rockdec.engine.compute_in_place`; the readings are then pooled on
    as many threads).
    Each cube's attributes hold the run
    (:meth:`rockdec.physics.run.Run.to_attrs`) and its ``reading``. ``first_replicate`` numbers
    the replicates of a part of a scene (:func:`rockdec.pipeline.layout.part_records`) as the
    whole scene does. The cubes of the readings in ``sums_only`` hold the sums and counts
    only (:func:`rockdec.rdd.signatures.pool`, ``finish=False``): all that their window
    curves read (:func:`replicate_curves`).
    """
    return variant_cubes(run, records, [settings], readings, series_files, threads, first_replicate, sums_only)[0]


def variant_cubes(run: Run, records: dict, variants, readings, series_files=(), threads: int = 1, first_replicate: int = 0,
                  sums_only=()) -> list[dict]:
    """:func:`scene_cubes` for several signature settings ``variants`` at once: one Dask
    graph, so each series is simulated (or read) once for all of them."""
    seeds = scene_seeds(records)
    unit_of_seed, groups = pass_units(seeds, list(readings))
    # the series unit after unit (each unit's in seed order): each block of series then holds
    # units in label order, which the cube keeps, instead of the units' parts to be sorted by label
    used = np.flatnonzero(unit_of_seed >= 0)
    used = used[np.argsort(unit_of_seed[used], kind="stable")]
    chunk_seeds = records["chunk_seeds"]
    if len(series_files):
        theta = series.stored_theta(series_files, seeds.ravel()[used], chunk_seeds)
    else:
        theta = series.as_recorded(run.dataset(seeds.ravel()[used], records["n_points"], chunk_seeds=chunk_seeds)["theta"])
    # only the sums of the units: their signatures would be computed and thrown away
    lazy = [
        scene_signatures(theta, settings, sigma_y=run.sigma_y, sigma_ydot=run.sigma_ydot, g=run.g, group=unit_of_seed[used])[
            list(signatures.SUM_VARS)
        ]
        for settings in variants
    ]

    def reading_cube(units, reading):
        group_of_unit, replicate_of_group = groups[reading]
        cube = signatures.pool(units, "group", by=group_of_unit, finish=reading not in sums_only)
        cube = cube.assign_coords(replicate=("group", replicate_of_group + first_replicate, {"long_name": "replicate of the group"}))
        cube.attrs.update({**run.to_attrs(), "reading": reading})
        return cube

    return [
        dict(zip(groups, _each(lambda reading, units=units: reading_cube(units, reading), list(groups), threads)))
        for units in engine.compute_in_place(*lazy, threads=threads)
    ]


def _each(func, items: list, threads: int) -> list:
    """``[func(item) for item in items]``, on ``threads`` threads when there are several items
    (each reading's NumPy work on the pass's cores: most of it releases the GIL). The items
    are independent, so the results do not depend on the threads."""
    if threads <= 1 or len(items) <= 1:
        return [func(item) for item in items]
    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(min(threads, len(items)), thread_name_prefix="rockdec-reading") as pool:
        return list(pool.map(func, items))


def gathered(cubes: list[xr.Dataset], curves: list[xr.Dataset]) -> tuple[xr.Dataset, xr.Dataset]:
    """The whole scene from its parts (:func:`rockdec.pipeline.layout.part_records`): the cubes one
    after another along ``group`` (renumbered), the window curves along ``replicate``."""
    cube = xr.concat(cubes, dim="group", data_vars="minimal", coords="minimal", compat="override", combine_attrs="override")
    cube = cube.assign_coords(group=("group", np.arange(cube.sizes["group"]), cubes[0]["group"].attrs))
    return cube, xr.concat(curves, dim="replicate", data_vars="minimal", coords="minimal", compat="override", combine_attrs="override")


def replicate_curves(cube: xr.Dataset, *, fit_points: int) -> xr.Dataset:
    """Every estimator on every signature of ``cube``, averaged per replicate: the window curves.

    The analysis core (:func:`rockdec.rdd.estimators.window_estimates`, through
    :func:`rockdec.rdd.estimators.window_cube`) on each group's (or series') sums and counts;
    ``e_hat(estimator, replicate, window)``: NaN-aware mean over the groups (or series) of
    a replicate; ``count(replicate, trigger, window)``: triggers pooled in the replicate.
    The cube's load and sensor attributes are carried on (:func:`rockdec.physics.record_model.carried_attrs`).
    """
    dt = float(cube.attrs["dt"])
    per_group = estimators.window_cube(cube, fit_points)["e_hat"]
    dim = series_dim(cube)
    e_hat = per_group.groupby(cube["replicate"]).mean(dim, skipna=True)
    e_hat.attrs = per_group.attrs
    count = cube["count"].groupby(cube["replicate"]).sum(dim)
    count.attrs = {"units": "1", "long_name": "triggers pooled in the replicate"}
    return xr.Dataset({"e_hat": e_hat, "count": count}, attrs={"fit_points": fit_points, "dt": dt, **carried_attrs(cube.attrs)})


def extrapolated(curves: xr.Dataset, weights: str = "window") -> xr.Dataset:
    """The window curves of :func:`replicate_curves` extrapolated to zero window.

    ``e_hat0(estimator, replicate)`` and its standard error from
    :func:`rockdec.rdd.estimators.extrapolate`, weighted by the window size (paper §5) or by
    the replicate's trigger count (``weights="count"``), as
    :func:`rockdec.rdd.estimators.extrapolation_weights` decides; the curves are kept.
    """
    e_hat, count = curves["e_hat"], curves["count"]
    out = estimators.extrapolate(e_hat, weights, count).assign(e_hat=e_hat, count=count)
    out.attrs.update({**curves.attrs, "weights": weights})
    return out


def replicate_estimates(cube: xr.Dataset, *, fit_points: int, weights: str = "window") -> xr.Dataset:
    """Estimates per replicate and their zero-window extrapolation: :func:`extrapolated` of
    :func:`replicate_curves`."""
    return extrapolated(replicate_curves(cube, fit_points=fit_points), weights)


def scene_estimates(cube: xr.Dataset, options: dict) -> tuple[xr.Dataset, pd.DataFrame]:
    """Rule `estimates`: the estimates of a signature cube, and its table beside the paper.

    ``options`` is a scene's ``estimates`` section (``fit_points``, ``weights``); the true
    ``e`` is the run's, from the cube's attributes, and is stored as ``e_target``. The table
    adds the replicate mean and std of the other extrapolation weighting (window size or
    trigger count, :func:`rockdec.report.tables.with_alternative`).
    """
    curves = replicate_curves(cube, fit_points=options["fit_points"])
    est = extrapolated(curves, options["weights"])
    other_weights = "count" if options["weights"] == "window" else "window"
    alternative = extrapolated(curves, other_weights)
    e_target = float(cube.attrs["e"])
    est.attrs["e_target"] = e_target
    table = tables.summary_table(est["e_hat0"], e_target)
    return est, tables.with_alternative(table, alternative["e_hat0"], f"{other_weights}_weights", e_target)


def reading_curves(cubes: dict, fit_points: int, threads: int = 1) -> xr.Dataset:
    """The window curves (:func:`replicate_curves`) of every reading's cube, along ``reading``
    in the order of :data:`READINGS`, on ``threads`` threads (a reading each); ``e_target``
    from the run."""
    names = [r for r in READINGS if r in cubes]
    each = _each(lambda r: replicate_curves(cubes[r], fit_points=fit_points), names, threads)
    curves = xr.concat(each, dim=pd.Index(names, name="reading"))
    curves.attrs["e_target"] = float(next(iter(cubes.values())).attrs["e"])
    return curves


def readings_estimates(curves: xr.Dataset, weights: str) -> tuple[xr.Dataset, pd.DataFrame]:
    """Rule `table_readings`: every reading's estimates side by side, and their table.

    ``curves`` from :func:`reading_curves`; the result holds ``e_hat0`` and its standard
    error per reading, extrapolated with ``weights``.
    """
    e_target = float(curves.attrs["e_target"])
    combined = extrapolated(curves, weights)[["e_hat0", "e_hat0_stderr"]]
    combined.attrs = {"e_target": e_target, **carried_attrs(curves.attrs)}
    table = pd.concat(
        [tables.summary_table(combined["e_hat0"].sel(reading=r), e_target).assign(reading=str(r)) for r in combined["reading"].values],
        ignore_index=True,
    )
    return combined, table[["reading"] + [c for c in table.columns if c != "reading"]]

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
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import xarray as xr

from rockdec import estimators, series, signatures, simulate, tables

READINGS = ("pooled", "per_series", "groups_of_10")
"""The readings, in the order tables list them."""

PER_SERIES_LIMIT = 100
"""Series per replicate in the ``per_series`` reading (the paper's 100 values a point)."""


def grouping(seeds: np.ndarray, reading: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Seeds used by a reading and their labels.

    ``seeds`` is ``(replicate, series)``. Returns ``(used_seeds, group_of_seed,
    replicate_of_group)``, 1-D arrays: group labels run 0..G-1 in seed order.
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
    used_seeds = seeds[:, :used]
    per_rep = used // size
    group = np.repeat(np.arange(n_rep * per_rep), size)
    return used_seeds.ravel(), group, np.repeat(np.arange(n_rep), per_rep)


def series_dim(cube: xr.Dataset) -> str:
    """The dimension that holds a cube's signatures: ``seed`` (one a series) or ``group``."""
    return "seed" if "seed" in cube.dims else "group"


def scene_signatures(
    theta: xr.DataArray, scene: dict, stats: dict, group: np.ndarray | None, replicate_of_group
) -> xr.Dataset:
    """The scene's signature cube of ``theta(seed, time)``, summed within groups.

    ``group=None`` keeps one signature per series: the cube's ``seed`` dimension holds the
    seeds, and ``replicate_of_group`` gives each seed's replicate. ``stats`` holds the
    stationary ``sigma_y``, ``sigma_ydot`` and ``g`` of the scene (one trigger level for
    every series, docs/method.md §4.4).
    """
    sig = scene["signatures"]
    cube = signatures.signature_cube(
        theta,
        sigma_y=stats["sigma_y"],
        sigma_ydot=stats["sigma_ydot"],
        level=sig["level"],
        windows=sig["windows"],
        window_max=sig["window_max"],
        v_level=sig["v_level"],
        dv_max=sig["dv_max"],
        n_periods=sig["n_periods"],
        g=stats["g"],
        both_signs=sig["both_signs"],
        group=None if group is None else xr.DataArray(group, dims="seed", coords={"seed": theta["seed"]}),
    )
    dim = series_dim(cube)
    return cube.assign_coords(replicate=(dim, np.asarray(replicate_of_group), {"long_name": f"replicate of the {dim}"}))


def replicate_estimates(cube: xr.Dataset, *, fit_points: int, weights: str = "window") -> xr.Dataset:
    """Estimates per replicate and their zero-window extrapolation.

    ``e_hat(estimator, replicate, window)``: every estimator on every group's signature,
    averaged over the groups of a replicate (NaN-aware); ``e_hat0(estimator, replicate)``
    and its standard error from :func:`rockdec.estimators.extrapolate`, weighted by the
    window size (paper §5) or by the replicate's trigger count (``weights="count"``).
    """
    dt = float(cube.attrs["dt"])
    per_group = estimators.estimate_cube(
        cube["free_response"], cube["signature"].sel(trigger="v", drop=True), dt, fit_points=fit_points
    )["e_hat"]
    dim = series_dim(cube)
    e_hat = per_group.groupby(cube["replicate"]).mean(dim, skipna=True)
    e_hat.attrs = per_group.attrs
    count = cube["count"].groupby(cube["replicate"]).sum(dim)
    if weights == "count":
        # e_v rests on the D_v triggers, every other estimator on the D_a triggers
        w = xr.concat(
            [count.sel(trigger="v" if name == "e_v" else "a", drop=True) for name in e_hat["estimator"].values],
            dim=e_hat["estimator"],
        ).astype(float)
        extrap = estimators.extrapolate(e_hat, weights=w)
    else:
        extrap = estimators.extrapolate(e_hat)
    out = extrap.assign(e_hat=e_hat, count=count)
    out["count"].attrs = {"units": "1", "long_name": "triggers pooled in the replicate"}
    out.attrs.update({"weights": weights, "fit_points": fit_points, "dt": dt})
    return out


def reading_cube(simulation_attrs: dict, scene: dict, reading: str, series_files=()) -> xr.Dataset:
    """Lazy signature cube of a reading, every series regenerated from its seed or read back.

    ``simulation_attrs`` are the global attributes of the scene's simulation file (step,
    burn-in, stationary statistics); the series are simulated chunk by chunk (Dask over
    seeds) and reduced to signature sums at once, so no full record is ever stored. With
    ``series_files`` (the per-replicate files of ``store_series: all``) the series are read
    from them instead; both ways give the same cube bit for bit (see :mod:`rockdec.series`).
    """
    used, group, replicate_of_group = grouping(simulate.scene_seeds(scene), reading)
    chunk_seeds = scene["records"]["chunk_seeds"]
    if len(series_files):
        theta = series.stored_theta(series_files, used, chunk_seeds)
    else:
        theta = series.as_recorded(simulate.regenerate(simulation_attrs, used, chunk_seeds=chunk_seeds)["theta"])
    cube = scene_signatures(theta, scene, simulation_attrs, group, replicate_of_group)
    cube.attrs["reading"] = reading
    return cube


def estimate_options(scene: dict) -> dict:
    """Keyword arguments of :func:`replicate_estimates` from a scene's ``estimates`` section."""
    return {"fit_points": scene["estimates"]["fit_points"], "weights": scene["estimates"]["weights"]}


def scene_estimates(cube: xr.Dataset, scene: dict) -> tuple[xr.Dataset, pd.DataFrame]:
    """Rule `estimates`: the scene's estimates of a signature cube, and its table beside the paper.

    The table adds the replicate mean and std of the other extrapolation weighting
    (window size or trigger count, :func:`rockdec.tables.with_alternative`).
    """
    options = estimate_options(scene)
    est = replicate_estimates(cube, **options)
    other_weights = "count" if options["weights"] == "window" else "window"
    alternative = replicate_estimates(cube, **{**options, "weights": other_weights})
    e_target = scene["system"]["e"]
    table = tables.summary_table(est["e_hat0"], e_target)
    return est, tables.with_alternative(table, alternative["e_hat0"], f"{other_weights}_weights", e_target)


def readings_estimates(own: xr.Dataset, other: xr.Dataset, scene: dict) -> tuple[xr.Dataset, pd.DataFrame]:
    """Rule `table_readings`: the scene's own reading beside the other readings, and their table.

    ``own`` holds the scene's estimates, ``other`` the ``e_hat0`` of the other readings
    (dimension ``reading``); the result lists every reading of :data:`READINGS`, in
    that order.
    """
    own_reading = own[["e_hat0", "e_hat0_stderr"]].expand_dims(reading=[scene["estimates"]["reading"]])
    combined = xr.concat([own_reading, other], dim="reading").sel(reading=list(READINGS))
    e_target = scene["system"]["e"]
    table = pd.concat(
        [tables.summary_table(combined["e_hat0"].sel(reading=r), e_target).assign(reading=r) for r in READINGS],
        ignore_index=True,
    )
    return combined, table[["reading"] + [c for c in table.columns if c != "reading"]]

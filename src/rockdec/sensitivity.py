"""Which of the paper's unstated choices move which estimator (docs/method.md §8).

One choice at a time is moved away from the scene's setting: the lag range (rocking
periods at amplitude ``a``, eq. 5), the mirrored triggers (minima at ``-a``), and the trigger
level ``a / sigma_Y``. Every variant reads the same simulated series (one Dask graph, so
each chunk is simulated once), so differences between variants are not sampling noise
between different records.
"""

from __future__ import annotations

import copy

import dask
import pandas as pd
import xarray as xr

from rockdec import replicates, tables

CHOICES = {
    "lag range 1.5 periods": ("n_periods", 1.5),
    "lag range 3.5 periods": ("n_periods", 3.5),
    "maxima only": ("both_signs", False),
    "level 1.5 sigma_Y": ("level", 1.5),
    "level 2.5 sigma_Y": ("level", 2.5),
}
"""Variant name -> (signature setting, value); every other setting stays the scene's."""


def variant_scenes(scene: dict) -> dict[str, dict]:
    """The scene itself (``"as configured"``) and one copy per entry of :data:`CHOICES`."""
    out = {"as configured": scene}
    for name, (key, value) in CHOICES.items():
        variant = copy.deepcopy(scene)
        variant["signatures"][key] = value
        out[name] = variant
    return out


def choice_estimates(simulation_attrs: dict, scene: dict, threads: int = 1, series_files=()) -> xr.Dataset:
    """``e_hat0(choice, estimator, replicate)`` for every variant, from one simulation pass
    (or one pass over ``series_files``, see :func:`rockdec.replicates.reading_cube`)."""
    reading = scene["estimates"]["reading"]
    variants = variant_scenes(scene)
    cubes = [replicates.reading_cube(simulation_attrs, variant, reading, series_files) for variant in variants.values()]
    with dask.config.set(scheduler="threads", num_workers=threads):
        cubes = dask.compute(*cubes)
    est = [replicates.replicate_estimates(cube, **replicates.estimate_options(scene))["e_hat0"] for cube in cubes]
    return xr.concat(est, dim=pd.Index(list(variants), name="choice")).to_dataset(name="e_hat0")


def choice_table(est: xr.Dataset, e_target: float) -> pd.DataFrame:
    """Mean, std and bias per (choice, estimator), and the shift of the mean from the scene's."""
    rows = []
    for choice in est["choice"].values:
        table = tables.summary_table(est["e_hat0"].sel(choice=choice), e_target)
        rows.append(table[["estimator", "n", "mean", "std", "bias"]].assign(choice=str(choice)))
    out = pd.concat(rows, ignore_index=True)
    base = out[out["choice"] == "as configured"].set_index("estimator")["mean"]
    out["shift"] = out["mean"] - out["estimator"].map(base)
    return out[["choice", "estimator", "n", "mean", "std", "bias", "shift"]]

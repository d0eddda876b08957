"""Which of the paper's unstated choices move which estimator (docs/method.md §8).

One choice at a time is moved away from the scene's setting: the lag range (rocking
periods at amplitude ``a``, eq. 5), the mirrored triggers (minima at ``-a``), and the trigger
level ``a / sigma_Y``. Every variant reads the same simulated series (one Dask graph, so
each chunk is simulated once), so differences between variants are not sampling noise
between different records.
"""

from __future__ import annotations

import pandas as pd
import xarray as xr

from rockdec.pipeline import replicates
from rockdec.report import tables
from rockdec.physics.run import Run

__all__ = ["CHOICES", "choice_estimates", "choice_table"]

CHOICES = {
    "lag range 1.5 periods": ("n_periods", 1.5),
    "lag range 3.5 periods": ("n_periods", 3.5),
    "maxima only": ("both_signs", False),
    "level 1.5 sigma_Y": ("level", 1.5),
    "level 2.5 sigma_Y": ("level", 2.5),
}
"""Variant name -> (signature setting, value); every other setting stays the scene's."""


def variant_settings(settings: dict) -> dict[str, dict]:
    """A scene's signature settings as configured (``"as configured"``) and one copy per
    entry of :data:`CHOICES`."""
    out = {"as configured": settings}
    for name, (key, value) in CHOICES.items():
        out[name] = {**settings, key: value}
    return out


def choice_estimates(run: Run, records: dict, settings: dict, options: dict, threads: int = 1, series_files=()) -> xr.Dataset:
    """``e_hat0(choice, estimator, replicate)`` for every variant of the signature
    ``settings``, from one pass over the series (:func:`rockdec.pipeline.replicates.variant_cubes`);
    ``options`` is the scene's ``estimates`` section."""
    reading = options["reading"]
    variants = variant_settings(settings)
    cubes = replicates.variant_cubes(run, records, list(variants.values()), [reading], series_files, threads)
    est = [replicates.replicate_estimates(c[reading], fit_points=options["fit_points"], weights=options["weights"])["e_hat0"] for c in cubes]
    out = xr.concat(est, dim=pd.Index(list(variants), name="choice")).to_dataset(name="e_hat0")
    out.attrs["e_target"] = run.e
    return out


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

"""Where the simplified model stops being good enough: a sweep of ``sigma_Y / theta_cr`` (docs/method.md §2.4).

For each amplitude ratio the noise is set so that the simplified model's response has
``sigma_Y = ratio * theta_cr`` at the scene's points per cycle (the scale law of
:func:`rockdec.physics.simulate.calibrate_dt`: ``sigma_Y = c S^2/g^3``), then the same seeds and the
same step are simulated with the simplified model (eq. 4) and the linearized Housner model
(eq. 2) and both go through the same signatures and estimators. Series that overturn (Housner
only) are NaN from the fall on; the signatures skip their segments and the table counts them.
"""

from __future__ import annotations

import copy

import numpy as np
import pandas as pd
import xarray as xr

from rockdec.pipeline import replicates
from rockdec.physics import run
from rockdec.report import tables
from rockdec.physics.models import MODELS, noise_for_amplitude, scale_constant
from rockdec.physics.record_model import Load
from rockdec.validate import InputError

__all__ = ["sweep", "sweep_table"]

RATIOS = (0.002, 0.005, 0.01, 0.02, 0.03, 0.05)
"""``sigma_Y / theta_cr`` of the sweep; eqs. 3 and 5 differ by 2 % near 3 sigma_Y = 0.047 theta_cr."""


def noise_for_ratios(scene: dict, ratios) -> list[float]:
    """The impulse std giving ``sigma_Y = ratio * theta_cr`` for the simplified model, per ratio.

    With ``dt`` calibrated to ``N`` points per cycle the scale law gives ``sigma_p`` in closed
    form (:func:`rockdec.physics.models.noise_for_amplitude`), and its number ``c`` does not depend
    on ``sigma_p`` (scale invariance, docs/method.md §3.4); ``c`` is measured once from the
    simplified model's run at the scene's own noise (:func:`rockdec.physics.run.from_scene`). The law
    is the white load's: a coloured load is refused.
    """
    system, exc = scene["system"], scene["excitation"]
    if Load.from_dict(exc.get("load")).kind != "white":
        raise InputError("the amplitude sweep sets the noise by the white-noise scale law; give the scene a white load")
    contract = run.from_scene({**scene, "model": "simplified", "excitation": {**exc, "dt": None}})
    c = scale_constant(contract.sigma_y, contract.dt, contract.g, exc["sigma_p"])
    return [noise_for_amplitude(c, r * system["theta_cr"], contract.g, exc["points_per_cycle"]) for r in ratios]


def sweep(scene: dict, ratios=RATIOS, threads: int = 1) -> xr.Dataset:
    """``e_hat0(ratio, model, estimator, replicate)``, the measured ``sigma_y_ratio(ratio, model)``
    and ``skipped_fraction(ratio, model)`` (triggers lost to overturned stretches);
    attribute ``e_target``, the scene's ``e``."""
    out = []
    options = scene["estimates"]
    reading = options["reading"]
    for sigma_p in noise_for_ratios(scene, ratios):
        per_model = []
        base = copy.deepcopy(scene)
        base["excitation"]["sigma_p"] = sigma_p
        for model in MODELS:
            contract = run.from_scene({**base, "model": model})
            cube = replicates.scene_cubes(contract, base["records"], base["signatures"], [reading], threads=threads)[reading]
            est = replicates.replicate_estimates(cube, fit_points=options["fit_points"], weights=options["weights"])
            skipped = float(cube["skipped"].sel(trigger="a").isel(window=-1).sum())
            counted = float(cube["count"].sel(trigger="a").isel(window=-1).sum())
            per_model.append(
                est[["e_hat0"]].assign(
                    sigma_y_ratio=contract.sigma_y / contract.theta_cr,
                    skipped_fraction=skipped / max(skipped + counted, 1.0),
                )
            )
        out.append(xr.concat(per_model, dim=pd.Index(list(MODELS), name="model")))
    ds = xr.concat(out, dim=pd.Index(list(ratios), name="ratio"))
    ds["ratio"].attrs = {"units": "1", "long_name": "target sigma_Y / theta_cr of the simplified model"}
    ds["sigma_y_ratio"].attrs = {"units": "1", "long_name": "measured sigma_Y / theta_cr of the model's pilot"}
    ds["skipped_fraction"].attrs = {"units": "1", "long_name": "D_a triggers lost to overturned (NaN) stretches"}
    ds.attrs["e_target"] = float(scene["system"]["e"])
    return ds


def sweep_table(ds: xr.Dataset) -> pd.DataFrame:
    """Per (ratio, model, estimator): mean, std, bias against ``ds.attrs["e_target"]``; for
    Housner rows the paired drift.

    Both models ran the same seeds, so the replicate-by-replicate difference
    ``housner - simplified`` removes most of the sampling noise: ``drift`` is its mean and
    ``drift_se`` its standard error.
    """
    e_target = float(ds.attrs["e_target"])
    rows = []
    for ratio in ds["ratio"].values:
        for model in ds["model"].values:
            sub = ds.sel(ratio=ratio, model=model)
            table = tables.summary_table(sub["e_hat0"], e_target)[["estimator", "n", "mean", "std", "bias"]]
            if model == "housner":
                diff = (sub["e_hat0"] - ds["e_hat0"].sel(ratio=ratio, model="simplified")).transpose("estimator", "replicate")
                n = diff.notnull().sum("replicate")
                table["drift"] = diff.mean("replicate").values
                table["drift_se"] = (diff.std("replicate", ddof=1) / np.sqrt(n)).values
            else:
                table["drift"] = table["drift_se"] = np.nan
            rows.append(table.assign(ratio=float(ratio), model=str(model), skipped=float(sub["skipped_fraction"])))
    out = pd.concat(rows, ignore_index=True)
    return out[["ratio", "model", "estimator", "n", "mean", "std", "bias", "drift", "drift_se", "skipped"]]

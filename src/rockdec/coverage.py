"""Does the interval of ``rockdec estimate`` hold? Coverage on simulated records of known ``e``.

Records are simulated at a true ``e`` (``g = sigma_p = 1``, the step calibrated to a given
number of samples per cycle at ``sigma_Y``, eq. 5), each goes through exactly what a
measured record goes through (:func:`rockdec.measured.analyse`, then the calibration
selected by its own length and sampling, :mod:`rockdec.calibration`), and the study
records how often each estimator's 95 % interval holds the true ``e``, the bias and
spread of the corrected value, and the error of the corrected ``g``.

Coloured load (paper §6's open question): the same, with the impulses low-pass filtered
(:class:`rockdec.record_model.Load`), corner at ``corner`` times the rocking frequency
``1/T(sigma_Y)``, and the *white-noise* calibration: how far the white assumption carries.
"""

from __future__ import annotations

import sys
import warnings

import dask
import numpy as np
import pandas as pd
import xarray as xr

from rockdec import belt, calibration, engine, measured, registry
from rockdec.registry import DEFAULT_ESTIMATOR
from rockdec.record_model import Load
from rockdec.simulate import STEP_ITERATIONS, calibrate_dt, simulate_block

#: Seeds of the study's records start here (apart from calibration and pilot seeds).
STUDY_SEED_OFFSET = 2**60


def _record_batch(e: float, seeds, n_points: int, cal: dict, pole: float) -> list[measured.Analysis]:
    theta, _ = simulate_block(seeds, n_points, dt=cal["dt"], g=1.0, e=e, sigma_p=1.0, burn_in=cal["burn_in"], pole=pole)
    out = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for row in theta:
            try:
                out.append(measured.analyse([row], cal["dt"]))
            except ValueError:
                out.append(None)
    return out


def run(e_values, n_records: int, n_points: int, cache_dir, *, points_per_cycle: float = 75.0, corner: float | None = None, batch: int = 20) -> xr.Dataset:
    """The study for each true ``e`` of ``e_values``: ``n_records`` records of ``n_points``.

    Returns ``raw``, ``e_hat``, ``low``, ``high`` ``(e_true, record, estimator)`` and
    ``g_hat`` ``(e_true, record)`` (in units of the true ``g``, corrected with the default
    estimator). Records are analysed in Dask tasks of ``batch``; calibrations are built
    as their settings come up and stored in ``cache_dir`` for reuse.
    """
    e_values = [float(e) for e in e_values]
    names = list(registry.ESTIMATORS)
    shape = (len(e_values), n_records, len(names))
    raw, e_hat, low, high = (np.full(shape, np.nan) for _ in range(4))
    g_hat = np.full(shape[:2], np.nan)
    load = Load() if corner is None else Load("lowpass", corner)
    pole = load.pole(points_per_cycle)
    by_hash: dict = {}
    for i, e in enumerate(e_values):
        cal = calibrate_dt(e=e, g=1.0, sigma_p=1.0, points_per_cycle=points_per_cycle, pole=pole, iterations=STEP_ITERATIONS[load.kind])
        seed0 = STUDY_SEED_OFFSET + i * 10**7
        tasks = [
            dask.delayed(_record_batch)(e, np.arange(start, min(start + batch, n_records)) + seed0, n_points, cal, pole)
            for start in range(0, n_records, batch)
        ]
        analyses = [a for part in engine.compute(*tasks) for a in part]
        print(f"coverage: e = {e}: {n_records} records of {n_points} samples analysed; correcting", file=sys.stderr, flush=True)
        for k, analysis in enumerate(analyses):
            if analysis is None:
                continue
            key = calibration.calibration_settings([n_points], analysis.points_per_cycle)
            h = calibration.settings_hash(key)
            if h not in by_hash:
                by_hash[h] = belt.belts(calibration.load_or_build(key, cache_dir)[0])
            for j, name in enumerate(names):
                c = belt.correct(by_hash[h][name], analysis.raw[name])
                raw[i, k, j], e_hat[i, k, j], low[i, k, j], high[i, k, j] = analysis.raw[name], c.value, c.low, c.high
            e_default = e_hat[i, k, names.index(DEFAULT_ESTIMATOR)]
            g_hat[i, k] = belt.correct_g(by_hash[h][measured.G_NAME], analysis.raw[measured.G_NAME], e_default)
    dims = ("e_true", "record", "estimator")
    attrs = {"units": "1"}
    return xr.Dataset(
        {
            "raw": (dims, raw, {**attrs, "long_name": "raw zero-window estimate"}),
            "e_hat": (dims, e_hat, {**attrs, "long_name": "bias-corrected estimate of e"}),
            "low": (dims, low, {**attrs, "long_name": "lower end of the 95 % interval"}),
            "high": (dims, high, {**attrs, "long_name": "upper end of the 95 % interval"}),
            "g_hat": (dims[:2], g_hat, {**attrs, "long_name": "corrected g over the true g"}),
        },
        coords={
            "e_true": ("e_true", e_values, {"units": "1", "long_name": "true coefficient of restitution"}),
            "record": ("record", np.arange(n_records), {"long_name": "simulated record"}),
            "estimator": ("estimator", names, {"long_name": "estimator of e"}),
        },
        attrs={
            "n_points": int(n_points),
            "points_per_cycle": float(points_per_cycle),
            "corner": float("nan") if corner is None else float(corner),
            "load": load.describe(),
        },
    )


def summary(ds: xr.Dataset) -> pd.DataFrame:
    """Per true ``e`` and estimator: bias and spread of the corrected value, median interval
    width, coverage of the 95 % interval, failures; and the corrected ``g``'s error."""
    rows = []
    for e in ds["e_true"].values:
        sub = ds.sel(e_true=e)
        g_err = np.abs(sub["g_hat"].values - 1.0)
        for name in ds["estimator"].values:
            s = sub.sel(estimator=name)
            ok = np.isfinite(s["low"].values)
            covered = (s["low"].values <= e) & (e <= s["high"].values)
            rows.append(
                {
                    "load": ds.attrs["load"],
                    "n_points": ds.attrs["n_points"],
                    "e_true": float(e),
                    "estimator": str(name),
                    "records": int(s.sizes["record"]),
                    "raw_bias": float(np.nanmean(s["raw"].values) - e),
                    "bias": float(np.nanmean(s["e_hat"].values) - e),
                    "sd": float(np.nanstd(s["e_hat"].values, ddof=1)),
                    "median_width": float(np.nanmedian(s["high"].values - s["low"].values)),
                    "coverage": float(covered.sum() / s.sizes["record"]),
                    "failed": float(1.0 - ok.mean()),
                    "g_within_2pct": float(np.mean(g_err <= 0.02)),
                }
            )
    return pd.DataFrame(rows)


#: True ``e`` of the study, and records per ``e``.
E_VALUES = (0.6, 0.8, 0.9, 0.95, 0.98)
RECORDS_PER_E = 200

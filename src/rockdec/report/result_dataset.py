"""An estimate of ``e`` as a CF-1.10 dataset (:meth:`rockdec.RestitutionEstimate.to_dataset`)."""

from __future__ import annotations

import json
import math

import numpy as np
import xarray as xr

from rockdec._version import __version__

__all__ = ["dataset", "global_attrs"]


def _value(x) -> float:
    return math.nan if x is None else float(x)


def _bounds(pair) -> tuple[float, float]:
    return (math.nan, math.nan) if pair is None else (_value(pair[0]), _value(pair[1]))


def dataset(res) -> xr.Dataset:
    """The CF dataset of ``res`` (:class:`rockdec.RestitutionEstimate`): scalars ``e``,
    ``e_low``, ``e_high``, ``coverage``, ``g``, ``g_low``, ``g_high``; per ``estimator``
    ``e_raw``, ``e_corrected``, ``e_corrected_low``, ``e_corrected_high``,
    ``e_coverage``, ``triggers``. NaN where there is no value; the JSON document in the
    attribute ``rockdec_estimate``."""
    doc = res.to_dict()
    est = doc["estimators"]
    names = list(est)
    low, high = _bounds(doc["interval"] if doc["e"] is not None else None)
    g_low, g_high = _bounds(doc.get("g_interval"))
    per = {
        "e_raw": [_value(est[n]["raw"]) for n in names],
        "e_corrected": [_value(est[n]["e"]) for n in names],
        "e_corrected_low": [_value(est[n]["interval"][0]) if est[n]["e"] is not None else math.nan for n in names],
        "e_corrected_high": [_value(est[n]["interval"][1]) if est[n]["e"] is not None else math.nan for n in names],
        "e_coverage": [_value(est[n]["coverage"]) for n in names],
    }
    what = "coefficient of restitution"
    ds = xr.Dataset(
        {
            "e": ((), _value(doc["e"]), {"units": "1", "long_name": f"{what}, reported estimate (bias-corrected)",
                                         "ancillary_variables": "e_low e_high"}),
            "e_low": ((), low, {"units": "1", "long_name": f"{what}, lower end of the 95 % confidence interval"}),
            "e_high": ((), high, {"units": "1", "long_name": f"{what}, upper end of the 95 % confidence interval"}),
            "coverage": ((), _value(doc["coverage"]), {
                "units": "1", "long_name": "share of the calibration's simulated records whose 95 % interval held their true e"}),
            "g": ((), _value(doc["g"]), {"units": "rad s-2", "long_name": "restoring acceleration nu^2 theta_cr of the block",
                                         "ancillary_variables": "g_low g_high"}),
            "g_low": ((), g_low, {"units": "rad s-2", "long_name": "restoring acceleration, lower end of the 95 % confidence interval"}),
            "g_high": ((), g_high, {"units": "rad s-2", "long_name": "restoring acceleration, upper end of the 95 % confidence interval"}),
            "e_raw": ("estimator", per["e_raw"], {"units": "1", "long_name": f"{what}, raw estimate at zero trigger window"}),
            "e_corrected": ("estimator", per["e_corrected"], {
                "units": "1", "long_name": f"{what}, estimate corrected for its bias", "ancillary_variables": "e_corrected_low e_corrected_high"}),
            "e_corrected_low": ("estimator", per["e_corrected_low"], {"units": "1", "long_name": f"{what}, lower end of the 95 % interval"}),
            "e_corrected_high": ("estimator", per["e_corrected_high"], {"units": "1", "long_name": f"{what}, upper end of the 95 % interval"}),
            "e_coverage": ("estimator", per["e_coverage"], {
                "units": "1", "long_name": "share of the calibration's simulated records whose interval held their true e"}),
            "triggers": ("estimator", np.array([est[n]["triggers"] for n in names], dtype=np.int64), {
                "units": "1", "long_name": "triggers in the largest trigger window"}),
        },
        coords={"estimator": ("estimator", names, {"long_name": "estimator of e (paper eqs. 25-27, e_v from D_v)"})},
    )
    ds.attrs = global_attrs(doc, "by the Random Decrement technique", "estimate")
    return ds


def global_attrs(doc: dict, how: str, what: str) -> dict:
    """The global attributes of an estimate's dataset: CF conventions, a title naming
    ``how`` ``e`` was found, provenance (``what`` the history line says was done), the
    reason for a missing ``e``, the warnings, the records and the whole JSON document."""
    return {
        "Conventions": "CF-1.10",
        "title": f"coefficient of restitution of a rocking block, {how}",
        "source": f"rockdec {doc['rockdec_version'] or __version__}",
        "history": f"rockdec {__version__}: {what} of {', '.join(doc['records'])}",
        "estimator": doc["estimator"] or "",
        "reason": doc["reason"] or "",
        "warnings": json.dumps(doc["warnings"]),
        "records": json.dumps(doc["records"]),
        "rockdec_estimate": json.dumps(doc),
    }

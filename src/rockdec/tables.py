"""Replicate statistics, bias tests, and the paper's numbers side by side (paper eq. 28; docs/method.md §9).

Paper values: ``e_g`` and ``e_0`` at zero window from §5 / fig. 3 (no spread printed);
``e1..e4`` mean and standard deviation over 20 repetitions, eq. 28. The paper's ``e4`` is
its printed ``t1/(t2 - t1)`` evaluated on its estimates; we compute the corrected
``(t2 - t1)/t1`` (see :mod:`rockdec.estimators`), the quantity the paper meant.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import xarray as xr
from scipy import stats

PAPER = {
    "e_g": (0.8083, np.nan),
    "e_0": (0.9626, np.nan),
    "e1": (0.9628, 0.0048),
    "e2": (0.9948, 0.0055),
    "e3": (0.9717, 0.0039),
    "e4": (0.9539, 0.0065),
}
"""Paper's (mean, std) at zero window for ``e_target = 0.95`` (§5, fig. 3, eq. 28)."""

PAPER_E_TARGET = 0.95


def bias_row(values: np.ndarray, e_target: float) -> dict:
    """Mean, std, bias and a one-sample t-test of the bias for one estimator's replicates."""
    values = np.asarray(values, dtype=float)
    values = values[np.isfinite(values)]
    n = values.size
    mean = values.mean() if n else np.nan
    std = values.std(ddof=1) if n > 1 else np.nan
    if n > 1 and std > 0:
        test = stats.ttest_1samp(values, e_target)
        t, p = float(test.statistic), float(test.pvalue)
    else:
        t, p = np.nan, np.nan
    return {"n": n, "mean": mean, "std": std, "bias": mean - e_target, "t": t, "p_value": p}


def summary_table(e_hat0: xr.DataArray, e_target: float) -> pd.DataFrame:
    """One row per estimator: our replicate statistics, the paper's value and the difference.

    ``e_hat0(estimator, replicate)``. The paper columns are filled only when the scene's
    ``e_target`` is the paper's 0.95.
    """
    rows = []
    for name in e_hat0["estimator"].values:
        row = {"estimator": str(name), **bias_row(e_hat0.sel(estimator=name).values, e_target), "e_target": e_target}
        paper_mean, paper_std = PAPER.get(str(name), (np.nan, np.nan)) if e_target == PAPER_E_TARGET else (np.nan, np.nan)
        row.update({"paper_mean": paper_mean, "paper_std": paper_std, "mean_minus_paper": row["mean"] - paper_mean})
        rows.append(row)
    return pd.DataFrame(rows)


def to_markdown(table: pd.DataFrame) -> str:
    """The table as Markdown with 4 decimals (p-values in scientific notation)."""
    formatted = table.copy()
    for col in formatted.columns:
        if col == "p_value":
            formatted[col] = formatted[col].map(lambda v: f"{v:.2e}")
        elif formatted[col].dtype.kind == "f":
            formatted[col] = formatted[col].map(lambda v: f"{v:.4f}")
    return formatted.to_markdown(index=False) + "\n"


def with_alternative(table: pd.DataFrame, e_hat0: xr.DataArray, label: str, e_target: float) -> pd.DataFrame:
    """``table`` with the mean and std of another variant of the estimates beside ours.

    Used for the extrapolation weights (paper §5 weights by window size; the alternative
    weights by trigger count): columns ``mean_<label>``, ``std_<label>``.
    """
    rows = [bias_row(e_hat0.sel(estimator=name).values, e_target) for name in table["estimator"]]
    return table.assign(**{f"mean_{label}": [r["mean"] for r in rows], f"std_{label}": [r["std"] for r in rows]})


def write_table(table: pd.DataFrame, csv_path, md_path) -> None:
    """Write ``table`` as CSV (every digit) and as Markdown (:func:`to_markdown`)."""
    table.to_csv(csv_path, index=False)
    with open(md_path, "w") as f:
        f.write(to_markdown(table))


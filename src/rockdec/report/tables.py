"""Replicate statistics, bias tests, and the paper's numbers side by side (paper eq. 28; docs/method.md §9).

Paper values: ``e_g`` and ``e_0`` at zero window from §5 / fig. 3 (no spread printed);
``e1..e4`` mean and standard deviation over 20 repetitions, eq. 28. The paper's ``e4`` is
its printed ``t1/(t2 - t1)`` evaluated on its estimates; we compute the corrected
``(t2 - t1)/t1`` (see :mod:`rockdec.rdd.estimators`), the quantity the paper meant.

:func:`bias_row` is the one place replicate statistics are computed (the paper table, the
amplitude sweep, the speed/accuracy study); this module also formats every table as
Markdown (:func:`to_markdown`, the richer :func:`tradeoff_markdown`) and writes it with its
CSV (:func:`write_table`).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import xarray as xr

from rockdec.calibrate.belt import Z95
from rockdec.rdd.registry import BY_RANK

__all__ = [
    "MISSING", "PAPER", "PAPER_E_TARGET", "STATISTICS", "bias_row", "summary_table", "to_markdown",
    "tradeoff_markdown", "with_alternative", "write_table",
]

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

STATISTICS = ("n", "mean", "std", "bias", "rmse", "ci95", "t", "p_value")
"""What :func:`bias_row` returns, in this order."""

PAPER_COLUMNS = ["n", "mean", "std", "bias", "t", "p_value"]
"""The statistics :func:`summary_table` prints for each estimator."""


def bias_row(values, e_target: float) -> dict:
    """The replicate statistics of one estimator against the true ``e_target``.

    NaN estimates (an estimator that failed on a replicate) are left out; ``n`` counts the
    rest. ``std`` has ``ddof = 1``; ``bias = mean - e_target``; ``rmse = sqrt(mean((x -
    e_target)^2))``, hence ``rmse^2 = bias^2 + std^2 (n - 1)/n``; ``ci95 = |bias| + Z95 std``
    (:data:`rockdec.calibrate.belt.Z95`, 1.96): one replicate's estimate lies within ``+-ci95`` of
    ``e_target`` in about 95 % of cases (normal errors). ``t = bias / (std / sqrt(n))`` and
    its two-sided ``p_value`` (Student, ``n - 1`` degrees of freedom) test the bias. What
    needs two values (``std``, ``ci95``, ``t``, ``p_value``) is NaN for ``n = 1``, the test
    also for ``std = 0``; everything but ``n`` is NaN for ``n = 0``.
    """
    x = np.asarray(values, dtype=float).ravel()
    x = x[np.isfinite(x)]
    n = x.size
    out = dict.fromkeys(STATISTICS, np.nan)
    out["n"] = n
    if n == 0:
        return out
    mean = float(x.mean())
    bias = mean - e_target
    out.update(mean=mean, bias=bias, rmse=float(np.sqrt(np.mean((x - e_target) ** 2))))
    if n > 1:
        std = float(x.std(ddof=1))
        out.update(std=std, ci95=abs(bias) + Z95 * std)
        if std > 0:
            t = bias * np.sqrt(n) / std
            from scipy import stats  # imported when a table needs a p-value: scipy.stats is slow to load

            out.update(t=float(t), p_value=float(2.0 * stats.t.sf(abs(t), n - 1)))
    return out


def summary_table(e_hat0: xr.DataArray, e_target: float) -> pd.DataFrame:
    """One row per estimator: our replicate statistics, the paper's value and the difference.

    ``e_hat0(estimator, replicate)``. The paper columns are filled only when the scene's
    ``e_target`` is the paper's 0.95.
    """
    rows = []
    for name in e_hat0["estimator"].values:
        every = bias_row(e_hat0.sel(estimator=name).values, e_target)
        row = {"estimator": str(name), **{k: every[k] for k in PAPER_COLUMNS}, "e_target": e_target}
        paper_mean, paper_std = PAPER.get(str(name), (np.nan, np.nan)) if e_target == PAPER_E_TARGET else (np.nan, np.nan)
        row.update({"paper_mean": paper_mean, "paper_std": paper_std, "mean_minus_paper": row["mean"] - paper_mean})
        rows.append(row)
    return pd.DataFrame(rows)


COLUMN_WORDS = {
    "reading": "reading of the sizes",
    "estimator": "estimator",
    "n": "replicates",
    "mean": "mean over replicates",
    "std": "std over replicates",
    "bias": "bias (mean − true e)",
    "t": "t of the bias",
    "p_value": "p of the bias",
    "e_target": "true e",
    "paper_mean": "paper: mean",
    "paper_std": "paper: std",
    "mean_minus_paper": "ours − paper (mean)",
    "rmse": "RMSE",
    "ci95": "|bias| + 1.96 std",
}
"""The heading of each column in a table's Markdown (the CSV keeps the short names); each
is explained in docs/reference/tables.md."""

MARKDOWN_ONLY_IN_CSV = ("mean_count_weights", "std_count_weights", "mean_window_weights", "std_window_weights")
"""Columns the Markdown leaves out: the other extrapolation weighting (:func:`with_alternative`),
in the CSV for a reader who compares them."""

MISSING = "—"
"""What a table's Markdown shows where there is no value (the paper gives none, or too few replicates)."""


def _cell(column: str, value) -> str:
    """One value of ``column`` in the Markdown: one precision per column, :data:`MISSING` for NaN."""
    if isinstance(value, str):
        return f"`{value}`" if column == "estimator" else value
    if value is None or (isinstance(value, float) and not np.isfinite(value)):
        return MISSING
    if isinstance(value, (int, np.integer)) or (column == "n" and float(value).is_integer()):
        return str(int(value))
    if column == "p_value":
        return f"{value:.2g}"
    if column == "e_target":
        return f"{value:g}"
    if column == "t":
        return f"{value:.1f}"
    if column in ("bias", "mean_minus_paper"):
        return f"{value:+.4f}"
    return f"{value:.4f}"


def to_markdown(table: pd.DataFrame) -> str:
    """The table as Markdown a reader can read: columns headed in words (:data:`COLUMN_WORDS`),
    one precision per column (4 decimals for values of ``e``, ``t`` to 0.1, ``p`` to two
    significant digits), :data:`MISSING` where there is no value; a column with no value in
    any row is left out, and one that holds the same value in every row is said once above
    the table instead of in every row."""
    table = table.drop(columns=[c for c in MARKDOWN_ONLY_IN_CSV if c in table.columns])
    table = table.drop(columns=[c for c in table.columns if table[c].isna().all()])
    constant = [c for c in table.columns[1:] if len(table) > 1 and table[c].nunique(dropna=False) == 1]
    lines = []
    if constant:
        lines.append("; ".join(f"{COLUMN_WORDS.get(c, c)}: {_cell(c, table[c].iloc[0])}" for c in constant) + ".\n")
    shown = table.drop(columns=constant)
    body = pd.DataFrame({COLUMN_WORDS.get(c, c): [_cell(c, v) for v in shown[c]] for c in shown.columns})
    align = ["left" if shown[c].dtype.kind == "O" else "right" for c in shown.columns]
    lines.append(body.to_markdown(index=False, disable_numparse=True, colalign=align))
    return "\n".join(lines) + "\n"


def with_alternative(table: pd.DataFrame, e_hat0: xr.DataArray, label: str, e_target: float) -> pd.DataFrame:
    """``table`` with the mean and std of another variant of the estimates beside ours.

    Used for the extrapolation weights (paper §5 weights by window size; the alternative
    weights by trigger count): columns ``mean_<label>``, ``std_<label>``.
    """
    rows = [bias_row(e_hat0.sel(estimator=name).values, e_target) for name in table["estimator"]]
    return table.assign(**{f"mean_{label}": [r["mean"] for r in rows], f"std_{label}": [r["std"] for r in rows]})


def tradeoff_markdown(table: pd.DataFrame, recommendations: dict[str, pd.DataFrame],
                      estimators_shown=BY_RANK) -> str:
    """The speed/accuracy study as Markdown: cost per configuration, accuracy per estimator,
    and the cheapest configurations.

    ``table``: :func:`rockdec.studies.tradeoff.study_table`; ``recommendations``: criterion ->
    :func:`rockdec.studies.tradeoff.recommend` by that criterion (``"ci95"``, ``"rmse"``).
    """
    configs = table.drop_duplicates(["knob", "value"])
    cost = configs[["knob", "value", "kind", "points_per_cycle", "n_points", "series_per_replicate", "n_windows",
                    "level", "n_periods", "dt", "cpu_s", "cpu_s_per_replicate", "calibration_cpu_s"]]
    e_target = table.attrs.get("e_target")
    parts = ["# Speed against accuracy (rule tradeoff)\n",
             "One knob at a time moved from the scene `tradeoff`. Cost: CPU seconds of one configuration "
             "(simulation + signatures + estimates, all replicates; per replicate in `cpu_s_per_replicate`); "
             "the step calibration is a one-off (`calibration_cpu_s`). Accuracy over the replicates: "
             "`bias = mean - e`, `std` (ddof 1), `rmse` (so `rmse^2 = bias^2 + std^2 (n-1)/n`), "
             "`ci95 = |bias| + 1.96 std`."
             + (f" Target e = {e_target:g}." if e_target is not None else "") + "\n",
             "## Cost\n", to_markdown(cost)]
    for name in estimators_shown:
        part = table[table["estimator"] == name]
        if part.empty:
            continue
        parts += [f"## {name}\n", to_markdown(
            part[["knob", "value", "kind", "cpu_s_per_replicate", "n", "mean", "bias", "std", "rmse", "ci95"]])]
    criteria = {"ci95": "|bias| + 1.96 std <= tolerance (e within +-tolerance, 95 %)", "rmse": "rmse <= tolerance"}
    for criterion, rec in recommendations.items():
        parts += [f"## Cheapest configuration: {criteria[criterion]}\n", to_markdown(rec.drop(columns="criterion"))]
    return "\n".join(parts)


def write_table(table: pd.DataFrame, csv_path, md_path, markdown: str | None = None) -> None:
    """Write ``table`` as CSV (every digit) and as Markdown: ``markdown`` when given (a
    richer text made from the table), else :func:`to_markdown` of the table."""
    table.to_csv(csv_path, index=False)
    with open(md_path, "w") as f:
        f.write(to_markdown(table) if markdown is None else markdown)

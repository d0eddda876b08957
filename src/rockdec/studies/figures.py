"""Figures of the studies: the speed/accuracy trade-off's Pareto front and the coverage study.

Drawn from the tables the studies write (:func:`rockdec.studies.tradeoff.study_table`,
:func:`rockdec.studies.coverage.table`), with the styles of :mod:`rockdec.report.figures`.
"""

from __future__ import annotations

import math

import matplotlib
import numpy as np
from matplotlib.figure import Figure

from rockdec.pipeline.layout import COVERAGE_CONDITIONS, COVERAGE_E
from rockdec.rdd import registry
from rockdec.report.figures import TARGET_STYLE, _new_figure
from rockdec.studies import tradeoff
from rockdec.studies.coverage import BAND_MIN_ANSWERED, BIAS_RATIO, COVERAGE_BAND, band_chance

__all__ = ["fig_coverage", "pareto_figure"]

PARETO_ESTIMATORS = registry.BY_RANK[:4]
"""Estimators drawn by :func:`pareto_figure` by default: the first four of the studies' order."""

KNOB_LABELS = {
    "points_per_cycle": "ppc",
    "n_points": "points",
    "series_per_replicate": "series",
    "n_windows": "windows",
    "level": "level",
    "n_periods": "lag periods",
    "simulator": "",
    "fixed_step_points_per_cycle": "fixed-step ppc",
}
"""Short knob names (:data:`rockdec.studies.tradeoff.KNOBS`) for the labels of the Pareto front."""



def pareto_figure(table, estimators_shown=PARETO_ESTIMATORS) -> Figure:
    """The speed/accuracy study: CPU seconds per replicate (log) against RMSE (log), one
    panel per estimator.

    ``table``: :func:`rockdec.studies.tradeoff.study_table`. One marker per configuration, coloured
    by the knob moved (the base scene a black star); the Pareto front
    (:func:`rockdec.studies.tradeoff.pareto_front`) as a step line with its points labelled; grey
    lines at the RMSE of the accuracy classes.
    """
    shown = [name for name in estimators_shown if name in set(table["estimator"])]
    n_col = 2 if len(shown) > 1 else 1
    n_row = math.ceil(len(shown) / n_col)
    fig = _new_figure(6.0 * n_col, 4.6 * n_row)
    axes = np.atleast_1d(fig.subplots(n_row, n_col, sharex=True, sharey=True)).ravel()
    knobs = list(table.loc[~table["base"], "knob"].unique())
    colors = {k: matplotlib.colormaps["tab10"](i % 10) for i, k in enumerate(knobs)}
    handles = {}
    for ax, name in zip(axes, shown):
        # one marker per distinct configuration (the base and the fixed-step run at the
        # base density are listed under two knobs each)
        points = table[table["estimator"] == name].drop_duplicates(tradeoff.SETTING_COLUMNS)
        for knob in knobs:
            sel = points[(points["knob"] == knob) & ~points["base"]]
            handles[knob] = ax.scatter(sel["cpu_s_per_replicate"], sel["rmse"], s=28, color=colors[knob],
                                       label=knob.replace("_", " "), zorder=3)
        base = points[points["base"]]
        if not base.empty:
            handles["base"] = ax.scatter(base["cpu_s_per_replicate"], base["rmse"], s=110, marker="*", color="k",
                                         label="base scene", zorder=4)
        front = points.iloc[tradeoff.pareto_front(points["cpu_s_per_replicate"], points["rmse"])]
        ax.step(front["cpu_s_per_replicate"], front["rmse"], where="post", color="0.3", lw=1.2, zorder=2)
        for k, (_, row) in enumerate(front.iterrows()):
            text = "base" if row["base"] else f"{KNOB_LABELS.get(row['knob'], row['knob'])} {row['value']}".strip()
            ax.annotate(text, (row["cpu_s_per_replicate"], row["rmse"]), textcoords="offset points",
                        xytext=(4, 4) if k % 2 == 0 else (-4, -11), ha="left" if k % 2 == 0 else "right",
                        fontsize=6.5, color="0.25")
        for tol in tradeoff.ACCURACY_CLASSES:
            ax.axhline(tol, color="0.75", lw=0.7, ls=":", zorder=1)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title(f"{name}: Pareto front of cost and RMSE", fontsize="medium")
        ax.grid(True, which="major", lw=0.3, alpha=0.5)
    for ax in axes[len(shown):]:
        ax.set_visible(False)
    for ax in axes[-n_col:]:
        ax.set_xlabel("CPU seconds per replicate")
    for ax in axes[::n_col]:
        ax.set_ylabel("RMSE of the estimate of e")
    fig.legend(handles=list(handles.values()), loc="outside lower center", ncol=min(5, len(handles)), fontsize="small")
    return fig



def fig_coverage(table) -> Figure:
    """Coverage of the reported 95 % interval and corrected bias, per condition and true ``e``.

    ``table``: :func:`rockdec.studies.coverage.table` (one row per cell). x axis: the conditions,
    the true ``e`` side by side within each; filled circles the kernel's records, crosses
    the reference simulator's. Left: coverage on the records the tool answered (the band
    :data:`rockdec.studies.coverage.COVERAGE_BAND` shaded, 95 % dashed) with its binomial
    standard error, the share of records declined written beside it (a cell declined
    whole is a triangle on the axis's floor), and open circles for the paper model's
    interval on every record; below it, how many cells lie outside the band against what a
    calibrated interval leaves (:func:`rockdec.studies.coverage.band_chance`). Right:
    corrected bias over its sd (the band ``+-`` :data:`rockdec.studies.coverage.BIAS_RATIO` shaded).
    """

    conditions = [c for c in COVERAGE_CONDITIONS if c in set(table["condition"])]
    es = sorted(set(COVERAGE_E) | set(table["e_true"]))
    colours = matplotlib.colormaps["viridis"](np.linspace(0.0, 0.9, len(es)))
    fig = _new_figure(13.0, 4.5)
    cov_ax, bias_ax = fig.subplots(1, 2)
    width = 0.8 / len(es)
    shown = np.concatenate([table["answered_coverage"].to_numpy(float), table["paper_coverage"].to_numpy(float)])
    floor = min(0.5, float(np.nanmin(shown)) - 0.05) if np.isfinite(shown).any() else 0.5
    for row in table.itertuples():
        x = conditions.index(row.condition) + (es.index(row.e_true) - (len(es) - 1) / 2) * width
        colour = colours[es.index(row.e_true)]
        kernel = row.simulator == "kernel"
        x += 0.0 if kernel else width / 3
        marker = "o" if kernel else "x"
        if row.answered:
            cov_ax.errorbar(x, row.answered_coverage, yerr=row.answered_coverage_se, color=colour, marker=marker, ms=5, lw=0.8, ls="none")
        else:
            cov_ax.plot(x, floor + 0.01, marker="v", color=colour, ms=6, ls="none")
        if row.declined > 0:
            y = row.answered_coverage if row.answered else floor + 0.01
            cov_ax.annotate(f"{row.declined:.0%}", (x, y), xytext=(0, 7), textcoords="offset points", ha="center", fontsize=6, color=colour)
        if kernel:
            cov_ax.plot(x, row.paper_coverage, marker="o", mfc="none", color=colour, ms=5, ls="none")
        bias_ax.plot(x, row.bias_over_sd, color=colour, marker=marker, ms=5, ls="none")
    cov_ax.axhspan(*COVERAGE_BAND, color="tab:green", alpha=0.15, label=f"{COVERAGE_BAND[0]:.0%}-{COVERAGE_BAND[1]:.0%}")
    cov_ax.axhline(0.95, **TARGET_STYLE)
    bias_ax.axhspan(-BIAS_RATIO, BIAS_RATIO, color="tab:green", alpha=0.15, label=f"|bias| <= {BIAS_RATIO:g} sd")
    bias_ax.axhline(0.0, **TARGET_STYLE)
    for e, colour in zip(es, colours):
        cov_ax.plot([], [], marker="o", color=colour, ls="none", label=f"e = {e:g}")
    cov_ax.plot([], [], marker="o", mfc="none", color="0.4", ls="none", label="paper model's interval")
    cov_ax.plot([], [], marker="x", color="0.4", ls="none", label="reference simulator")
    cov_ax.plot([], [], marker="v", color="0.4", ls="none", label="every record declined (% beside: share declined)")
    for ax, what in ((cov_ax, "coverage of the reported 95 % interval (answered records)"), (bias_ax, "corrected bias / sd")):
        ax.set_xticks(range(len(conditions)), [c.replace("_", "\n") for c in conditions], fontsize=8)
        ax.set(xlabel="condition", ylabel=what)
    chance = band_chance(table)
    cov_ax.set_xlabel(f"condition\n{chance['outside']} of {chance['cells']} cells answered on {BAND_MIN_ANSWERED} or more records "
                      f"outside the band\n(a calibrated interval leaves {chance['expected_outside']:.1f}); dispersion "
                      f"{chance['chi2_ratio']:.2f} x binomial", fontsize=8)
    cov_ax.set_ylim(floor, 1.02)
    cov_ax.legend(fontsize=7, loc="lower left", bbox_to_anchor=(0.0, 1.02), ncol=4)  # above: the floor holds the declined cells
    bias_ax.legend(fontsize=7)
    return fig

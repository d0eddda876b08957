"""The figure of a free-rocking analysis (:func:`rockdec.free.analysis.analyse_free_rocking`).

Matplotlib is imported inside :func:`plot_free_rocking` only, so importing this module
costs nothing to a caller that never draws.
"""

from __future__ import annotations

import numpy as np

__all__ = ["plot_free_rocking"]


def plot_free_rocking(fit, theta, dt, ax=None):
    """Draw a free-rocking record with its fitted arcs (eqs. 2, 4) and ``e`` per impact (eq. 6).

    Left: the record (each of several records on its own time axis), the fitted flights
    from each release to its last fitted impact, the impacts (circles) and the releases
    (triangles). Right: ``e`` of each impact against the apex of the arc before it, with
    its 95 % error bar, and the pooled ``e`` with its 95 % interval as a band (the
    simplified and linearised Housner models both predict a constant ``e``; a trend is the
    block's own).

    Parameters
    ----------
    fit : rockdec.free.analysis.FreeRockingFit
        The analysis of ``theta``.
    theta : array_like or list of array_like
        The record(s) analysed (rad).
    dt : float, array_like or list
        As given to the analysis: the step (s), the time stamps, or one per record.
    ax : sequence of two matplotlib.axes.Axes, optional
        The panels to draw into; by default a new figure with two.

    Returns
    -------
    matplotlib.figure.Figure
        The figure holding the panels.

    Examples
    --------
    >>> from rockdec.free.analysis import analyse_free_rocking
    >>> from rockdec.studies.free_coverage import free_record
    >>> theta, dt, _ = free_record(0.9, noise=0.01, samples_per_cycle=40)
    >>> fig = plot_free_rocking(analyse_free_rocking(theta, dt), theta, dt)
    >>> len(fig.axes)
    2
    """
    from matplotlib.figure import Figure

    from scipy import stats

    if ax is None:
        fig = Figure(figsize=(11.0, 4.0), layout="constrained")
        record_ax, e_ax = fig.subplots(1, 2, gridspec_kw={"width_ratios": [2, 1]})
    else:
        record_ax, e_ax = ax
        fig = record_ax.figure
    records = list(theta) if isinstance(theta, (list, tuple)) and all(np.ndim(r) >= 1 for r in theta) else [theta]
    steps = list(dt) if isinstance(dt, (list, tuple)) and len(records) > 1 else [dt] * len(records)
    for r, (y, step) in enumerate(zip(records, steps)):
        y = np.asarray(y, dtype=float)
        t = np.asarray(step, dtype=float) if np.ndim(step) else step * np.arange(y.size)
        record_ax.plot(t, y, color="0.55", lw=0.8, label="record" if r == 0 else None)
        for s in np.flatnonzero(fit.release_record == r):
            times = fit.fitted_times[s]
            fine = np.linspace(max(t[0], times[0] - 0.1 * (times[1] - times[0])), times[-1], 40 * (times.size + 2))
            record_ax.plot(fine, fit.curve(int(s), fine), color="tab:blue", lw=1.2,
                           label=f"fitted flights ({fit.model})" if s == 0 else None)
            record_ax.plot(times[0], fit.release_angle[s], "v", color="tab:green", label="release" if s == 0 else None)
    record_ax.plot(fit.impact_time, np.zeros(fit.n_impacts), "o", ms=4, mfc="none", color="tab:red",
                   label="impacts with e" if fit.n_impacts else None)
    record_ax.axhline(0.0, color="0.8", lw=0.6)
    record_ax.set(xlabel="time (s)", ylabel="angle (rad)", title="free-rocking record")
    record_ax.legend(fontsize=8, loc="upper right")

    z = stats.norm.ppf(0.5 + fit.confidence_level / 2)
    if fit.n_impacts:
        e_ax.errorbar(fit.amplitude_before, fit.e_impact, yerr=z * fit.e_impact_se, fmt="o", ms=4, color="tab:red",
                      ecolor="0.6", elinewidth=0.8, label="e per impact (95 %)")
    if np.isfinite(fit.e):
        e_ax.axhspan(*fit.e_interval, color="tab:blue", alpha=0.2, label="pooled 95 % interval")
        e_ax.axhline(fit.e, color="tab:blue", lw=1.0, label=f"pooled e = {fit.e:.4f}")
    else:
        e_ax.text(0.5, 0.5, fit.reason or "", transform=e_ax.transAxes, ha="center", va="center", wrap=True, fontsize=8)
    e_ax.set(xlabel="apex of the arc before the impact (rad)", ylabel="e", title="e against amplitude")
    if e_ax.get_legend_handles_labels()[0]:
        e_ax.legend(fontsize=8, loc="lower right")
    return fig

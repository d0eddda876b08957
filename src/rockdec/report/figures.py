"""The paper's figures (1b, 2, 3, 4), the figure of its §6 proposal, ``e_v``, and those of
the studies beyond the paper (amplitude sweep, speed/accuracy Pareto plot, coverage) and of
a measured record.

One function per figure: labelled datasets in, a :class:`matplotlib.figure.Figure` out.
Figures are made without :mod:`matplotlib.pyplot`, so no global figure state is created
or leaked; :func:`save` writes them (PNG at 150 dpi, PDF without a creation date, so
the same data give the same file).

Inputs are the workflow's products (:mod:`rockdec.io`):

- ``sim``: a simulation Dataset, ``theta(seed, time)`` in rad, attributes ``dt``, ``g``,
  ``e``, ``sigma_y``;
- ``sig``: a signature cube (:func:`rockdec.rdd.signatures.signature_cube`), possibly with a
  ``group`` dimension, which is pooled exactly (:func:`rockdec.rdd.signatures.pool`);
- ``est``: estimates, ``e_hat(estimator, replicate, window)``, ``e_hat0`` and ``slope``
  ``(estimator, replicate)`` (:func:`rockdec.pipeline.replicates.replicate_estimates`).

The target ``e`` is passed in (the estimates do not store it; the studies' datasets do);
the paper's values are drawn only when it is the paper's ``e = 0.95`` (as in
:func:`rockdec.report.tables.summary_table`).
Window sizes are relative, ``da/da_max`` (``dv/dv_max`` for ``e_v``).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from rockdec.physics import models
from rockdec.rdd import registry  # noqa: E402
from rockdec.physics.models import period_from_g  # noqa: E402

# rockdec.rdd.signatures (numba, dask), rockdec.report.tables (scipy.stats), rockdec.studies.tradeoff (numba,
# dask) and scipy.optimize are imported where they are used: a study's plot rule and
# a record's plot are fresh processes, and these imports would double their
# start-up time for the figures that do not need them.

__all__ = [
    "TARGET_STYLE", "fig1b", "fig2", "fig3", "fig4", "fig_amplitude", "fig_ev", "fig_record",
    "free_rocking", "save",
]

WINDOW_LABEL = r"relative window size $\Delta a/\Delta a_{max}$"
TARGET_STYLE = {"color": "k", "ls": "--", "lw": 1.0}
PAPER_STYLE = {"color": "tab:red", "marker": "D", "ms": 10, "mfc": "none", "mew": 1.5, "ls": "none", "zorder": 5}
"""The paper's value: a large open diamond, so that our zero-window marker (:data:`OURS_STYLE`,
smaller and drawn above it) stays visible when the two coincide."""
OURS_STYLE = {"marker": "o", "ms": 5, "ls": "none", "zorder": 6}
SPREAD_ALPHA = 0.18
"""Shading of the spread across replicates (mean +- 1 std), told apart from the error bars
of the mean (+- 1 standard error)."""

# --------------------------------------------------------------------------- helpers


def free_rocking(t, theta0: float, omega0: float, g: float, e: float) -> np.ndarray:
    """Closed-form free rocking of the simplified model (eqs. 4, 6) from ``(theta0, omega0)``.

    Between impacts the angle is a parabola of curvature ``-g sign(theta)``; at every zero
    crossing the speed is multiplied by ``e``. From ``(a, 0)`` (the free response
    ``G(a, 0, t)`` of paper §2) the first crossing is at ``t1 = sqrt(2a/g)`` with speed
    ``g t1``, the first minimum ``-e^2 a`` at ``(1 + e) t1``; bounce ``k >= 1`` starts
    with speed ``e^k V`` (``V`` the first impact speed) and lasts ``2 e^k V/g``. With
    ``e < 1`` the bounces add up to a finite time after which the block rests at 0.

    ``t`` in s (``t >= 0``), angles in rad, ``omega0`` in rad/s, ``g = nu^2 theta_cr`` in
    rad/s^2. ``theta0 = 0, omega0 > 0`` starts *after* an impact, leaving zero upwards.
    """
    t = np.asarray(t, dtype=float)
    if theta0 == 0.0 and omega0 == 0.0:
        return np.zeros_like(t)
    side = math.copysign(1.0, theta0 if theta0 != 0.0 else omega0)
    h, u = abs(theta0), side * omega0  # height above zero and speed away from it
    speed = math.sqrt(u * u + 2.0 * g * h)  # speed at the first impact
    t_cross = (u + speed) / g
    out = np.where(t <= t_cross, side * (h + u * t - 0.5 * g * t**2), 0.0)
    start, w, t_end = t_cross, e * speed, float(np.max(t, initial=0.0))
    while start < t_end and w > 0.0:
        side = -side
        length = 2.0 * w / g
        if length <= 1e-12 * max(t_end, 1.0):  # the remaining bounces are shorter than rounding
            break
        s = t - start
        inside = (s > 0.0) & (s <= length)
        out[inside] = side * (w * s[inside] - 0.5 * g * s[inside] ** 2)
        start, w = start + length, e * w
    return out


def save(fig: Figure, paths: str | Path | Iterable[str | Path]) -> list[Path]:
    """Write ``fig`` to each path, in the format its suffix names (PNG at 150 dpi, PDF).

    Metadata that would change from run to run (creation date, software version) is left
    out, so the same figure gives the same bytes. The figure is laid out once, as the first
    path is drawn (its layout engine, constrained for the figures here); the other formats
    keep those positions, and the engine is set back after the last.
    """
    if isinstance(paths, (str, Path)):
        paths = [paths]
    engine = fig.get_layout_engine()
    written = []
    try:
        for path in map(Path, paths):
            fmt = path.suffix.lstrip(".").lower()
            metadata = {"CreationDate": None, "Producer": None} if fmt == "pdf" else {"Software": None}
            fig.savefig(path, format=fmt, dpi=150, metadata=metadata)
            fig.set_layout_engine("none")
            written.append(path)
    finally:
        fig.set_layout_engine(engine)
    return written


def _new_figure(width: float, height: float) -> Figure:
    return Figure(figsize=(width, height), layout="constrained")


def _paper_values(name: str, e_target: float | None) -> tuple[float, float]:
    """Paper's (mean, std) of an estimator at zero window, NaN unless the target is the paper's."""
    from rockdec.report import tables

    if e_target is None or e_target != tables.PAPER_E_TARGET:
        return np.nan, np.nan
    return tables.PAPER.get(name, (np.nan, np.nan))


def _replicate_stats(values: xr.DataArray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mean, std (ddof 1) and standard error over ``replicate``, NaN-aware."""
    n = values.notnull().sum("replicate")
    mean = values.mean("replicate", skipna=True)
    std = values.std("replicate", ddof=1, skipna=True).where(n > 1)
    return mean.values, std.values, (std / np.sqrt(n.where(n > 0))).values


def _extrapolated_line(est: xr.DataArray | xr.Dataset, name: str, w: np.ndarray) -> np.ndarray:
    """Mean over replicates of the fitted line ``e_hat0 + slope * w`` (paper §5)."""
    line = est["e_hat0"].sel(estimator=name) + est["slope"].sel(estimator=name) * xr.DataArray(w, dims="w")
    return line.mean("replicate", skipna=True).values


def _pooled(sig: xr.Dataset) -> xr.Dataset:
    """A cube without groups: pooled exactly over ``group`` when it has that dimension."""
    from rockdec.rdd import signatures

    return signatures.pool(sig, "group") if "group" in sig.dims else sig


def _draw_target(ax, e_target: float | None) -> None:
    if e_target is not None:
        ax.axhline(e_target, label=f"target e = {e_target:g}", **TARGET_STYLE)


# --------------------------------------------------------------------------- figures


def fig1b(max_ratio: float = 0.9, tolerance: float = 0.05) -> Figure:
    """Paper fig. 1b: free-rocking period against relative amplitude, eqs. 3 and 5.

    Top: ``nu T`` (the period in units of ``1/nu``) against ``theta0/theta_cr`` for the
    linearized Housner model (eq. 3) and the simplified model (eq. 5). Bottom: their
    relative difference; the amplitude where it reaches ``tolerance`` is marked (0.111
    for 5 %, in line with the paper's remark that the two agree below about 0.1).
    Needs no simulation.
    """
    ratio = np.linspace(0.0, max_ratio, 400)
    housner = models.period_housner(ratio, 1.0, 1.0)  # nu = theta_cr = 1: nu T against theta0/theta_cr
    simple = models.period_simplified(ratio, 1.0, 1.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        rel = housner / simple - 1.0
    x_tol = models.amplitude_limit(tolerance)

    fig = _new_figure(6.0, 5.5)
    top, bottom = fig.subplots(2, 1, sharex=True, height_ratios=[2.0, 1.0])
    top.plot(ratio, housner, label="linearized Housner model, eq. 3")
    top.plot(ratio, simple, ls="--", label="simplified model, eq. 5")
    top.axvline(x_tol, color="0.5", lw=0.8, ls=":")
    top.set_ylabel(r"period $\nu T$ (T in units of $1/\nu$)")
    top.set_ylim(0.0, None)
    top.legend(loc="upper left")
    bottom.plot(ratio[1:], 100.0 * rel[1:], color="tab:purple")
    bottom.axhline(100.0 * tolerance, color="0.5", lw=0.8, ls=":")
    bottom.axvline(x_tol, color="0.5", lw=0.8, ls=":")
    bottom.annotate(
        f"{100 * tolerance:g} % at $\\theta_0/\\theta_{{cr}}$ = {x_tol:.3f}",
        xy=(x_tol, 100.0 * tolerance),
        xytext=(x_tol + 0.08, 100.0 * tolerance + 25.0),
        arrowprops={"arrowstyle": "->", "color": "0.3"},
    )
    bottom.set_xlabel(r"relative amplitude $\theta_0/\theta_{cr}$")
    bottom.set_ylabel("eq. 3 / eq. 5 − 1 (%)")
    bottom.set_xlim(0.0, max_ratio)
    bottom.set_ylim(0.0, None)
    return fig


def fig2(sim: xr.Dataset, stored_sig: xr.Dataset, *, n_samples: int = 750, window: float | None = None) -> Figure:
    """Paper fig. 2: two simulated responses (a, b) and a free-response estimate (c).

    (a), (b): the first ``n_samples`` samples of the first two stored series, in units of
    ``sigma_Y``, with the trigger levels ``+-a``. (c): the even part of ``D_a`` (eq. 20)
    pooled over the series of ``stored_sig`` (the paper pools 10 series of 6000 points),
    divided by the trigger level ``a``, against the free response ``G(a, 0, tau)/a`` of
    eqs. 4 and 6 (:func:`free_rocking`) at the simulated ``e``. ``window`` (relative)
    defaults to the middle one of the windows that caught triggers.
    """
    attrs = sim.attrs
    sigma_y, e, g, dt = (float(attrs[k]) for k in ("sigma_y", "e", "g", "dt"))
    sig = _pooled(stored_sig)
    a = float(sig.attrs["a"])
    count = sig["count"].sel(trigger="a")
    if window is None:
        filled = sig["window"].values[count.values > 0]
        window = float(filled[(filled.size - 1) // 2]) if filled.size else float(sig["window"].values[-1])
    r = sig["free_response"].sel(window=window)
    n_trig = int(count.sel(window=window))
    tau = sig["lag_pos"].values

    fig = _new_figure(7.5, 7.5)
    axes = fig.subplots(3, 1)
    n_series = sim.sizes["seed"]
    n = min(n_samples, sim.sizes["time"])
    t = np.arange(n) * dt
    for k, (ax, letter) in enumerate(zip(axes[:2], "ab")):
        if k < n_series:
            y = sim["theta"].isel(seed=k, time=slice(0, n)).values.astype(float) / sigma_y
            ax.plot(t, y, lw=0.8, color="tab:blue", label=f"seed {int(sim['seed'][k])}")
            for level in (a / sigma_y, -a / sigma_y):
                ax.axhline(level, color="tab:orange", lw=0.8, ls=":")
            ax.legend(loc="upper right", fontsize="small")
        else:
            ax.text(0.5, 0.5, "only one stored series", ha="center", va="center", transform=ax.transAxes)
        ax.axhline(0.0, color="0.6", lw=0.5)
        ax.set_xlim(0.0, t[-1] if n > 1 else 1.0)
        ax.set_xlabel("time t (s)")
        ax.set_ylabel(r"$\theta/\sigma_Y$")
        ax.set_title(
            f"({letter}) simulated response, e = {e:g} "
            f"($\\sigma_Y$ = {sigma_y:.3g} rad; dotted: trigger levels $\\pm a$)",
            fontsize="medium",
        )
    ax = axes[2]
    tau_fine = np.linspace(0.0, tau[-1], 2000)
    ax.plot(tau_fine, free_rocking(tau_fine, a, 0.0, g, e) / a, color="k", lw=1.0, ls="--",
            label=f"free response G(a, 0, τ)/a, e = {e:g}")
    ax.plot(tau, r.values / a, color="tab:blue", lw=1.3,
            label=f"RDD estimate, {n_trig} triggers, Δa/Δa$_{{max}}$ = {window:g}")
    ax.axhline(0.0, color="0.6", lw=0.5)
    ax.set_xlim(0.0, tau[-1])
    ax.set_xlabel("time lag τ (s)")
    ax.set_ylabel(r"free response $r(\tau)/a$")
    ax.set_title(
        f"(c) free-response estimate from {n_series} series × {sim.sizes['time']} points "
        f"(a = {float(sig.attrs.get('level', a / sigma_y)):g} $\\sigma_Y$)",
        fontsize="medium",
    )
    ax.legend(loc="upper right", fontsize="small")
    return fig


def _zero_window_ylim(ax, values) -> None:
    """Y limits that hold ``values`` (the target among them) with a margin, so no line sits on
    the frame."""
    values = np.concatenate([np.ravel(np.asarray(v, dtype=float)) for v in values])
    values = values[np.isfinite(values)]
    lo, hi = (min(values.min(), ax.get_ylim()[0]), max(values.max(), ax.get_ylim()[1])) if values.size else ax.get_ylim()
    pad = 0.08 * (hi - lo if hi > lo else 1e-3)
    ax.set_ylim(lo - pad, hi + pad)


def _legend_below(fig: Figure, handles, ncols: int = 3) -> None:
    """One legend for the whole figure, under the axes, each entry once."""
    seen, unique = set(), []
    for h in handles:
        if h.get_label() not in seen and not h.get_label().startswith("_"):
            seen.add(h.get_label())
            unique.append(h)
    fig.legend(handles=unique, loc="outside lower center", ncols=ncols, fontsize="small", frameon=False)


def fig3(est: xr.Dataset, e_target: float | None = None) -> Figure:
    """Paper fig. 3: ``e_g`` (eqs. 25, 7) and ``e_0`` (eq. 26) against the window size.

    One panel each, on its own scale. Points: the mean over replicates at each window, error
    bars one standard error (``std/sqrt(n)``). Lines: the mean over replicates of the
    least-squares lines ``e_hat0 + slope * w`` weighted by the window size (§5), drawn from
    ``w = 0``; the filled circle at ``w = 0`` is our mean extrapolated value, the open
    diamond the paper's, both written in the panel. The line follows the large windows,
    which weigh most: where an estimator bends at small windows (``e_g``), it passes beside
    their points.
    """
    w = est["window"].values
    w_line = np.linspace(0.0, w.max(), 50)
    fig = _new_figure(9.0, 4.6)
    axes = fig.subplots(1, 2)
    handles = []
    for ax, name, letter in zip(axes, ("e_g", "e_0"), "ab"):
        spec = registry.spec(name)
        title = f"({letter}) {spec.symbol}: {spec.label}, {spec.equation}"
        mean, _, sem = _replicate_stats(est["e_hat"].sel(estimator=name))
        handles.append(ax.errorbar(w, mean, yerr=sem, color="tab:blue", marker="o", ms=4, ls="none", capsize=4,
                                   elinewidth=1.2, label="mean over replicates ± 1 standard error"))
        handles += ax.plot(w_line, _extrapolated_line(est, name, w_line), color="tab:blue", lw=1.0,
                           label="least-squares line weighted by window size (§5)")
        e0 = float(est["e_hat0"].sel(estimator=name).mean(skipna=True))
        paper, _ = _paper_values(name, e_target)
        if np.isfinite(paper):
            handles += ax.plot(0.0, paper, **PAPER_STYLE, label="paper at zero window")
        handles += ax.plot(0.0, e0, color="tab:blue", **OURS_STYLE, label="ours at zero window (mean)")
        note = f"zero window: ours {e0:.4f}" + (f", paper {paper:.4f}" if np.isfinite(paper) else "")
        ax.text(0.98, 0.97, note, transform=ax.transAxes, ha="right", va="top", fontsize="small")
        if e_target is not None:
            handles.append(ax.axhline(e_target, label=f"target e = {e_target:g}", **TARGET_STYLE))
        ax.set_xlim(-0.05 * w.max(), 1.03 * w.max())
        _zero_window_ylim(ax, [mean + sem, mean - sem, e0, paper, e_target if e_target is not None else np.nan])
        ax.set_xlabel(WINDOW_LABEL)
        ax.set_ylabel(r"estimate of $e$")
        ax.set_title(title, fontsize="medium")
    _legend_below(fig, handles, ncols=3)
    return fig


def fig4(est: xr.Dataset, e_target: float | None = None) -> Figure:
    """Paper fig. 4: the local estimates ``e1..e4`` (eq. 27, ``e4`` corrected) per replicate.

    Each panel: every replicate's estimate against the window size (thin grey), their mean
    (thick), the mean extrapolated line, our mean and standard deviation at zero window
    (filled circle with bar) beside the paper's (open diamond with bar, eq. 28) and the
    target, kept clear of the frame. Values at zero window are written in the panel; one
    legend for all panels, below them.
    """
    w = est["window"].values
    w_line = np.linspace(0.0, w.max(), 50)
    fig = _new_figure(9.0, 7.8)
    axes = fig.subplots(2, 2)
    handles = []
    for ax, name in zip(axes.flat, ("e1", "e2", "e3", "e4")):
        curves = est["e_hat"].sel(estimator=name)
        for k, rep in enumerate(curves["replicate"].values):
            handles += ax.plot(w, curves.sel(replicate=rep).values, color="0.65", lw=0.6,
                               label="one replicate" if k == 0 else None)
        mean, _, _ = _replicate_stats(curves)
        handles += ax.plot(w, mean, color="tab:blue", lw=2.0, marker="o", ms=3, label="mean over replicates")
        handles += ax.plot(w_line, _extrapolated_line(est, name, w_line), color="tab:blue", lw=1.0, ls="-.",
                           label="mean extrapolation to zero window (§5)")
        e0_mean, e0_std, _ = _replicate_stats(est["e_hat0"].sel(estimator=name))
        e0_mean, e0_std = float(e0_mean), float(e0_std)
        paper, paper_std = _paper_values(name, e_target)
        if np.isfinite(paper):
            handles.append(ax.errorbar(0.0, paper, yerr=paper_std, capsize=4, **PAPER_STYLE,
                                       label="paper at zero window ± 1 std (eq. 28)"))
        handles.append(ax.errorbar(0.0, e0_mean, yerr=e0_std if np.isfinite(e0_std) else None, color="tab:blue",
                                   capsize=3, **OURS_STYLE, label="ours at zero window ± 1 std"))
        _draw_target(ax, e_target)
        handles += [line for line in ax.lines if line.get_label().startswith("target")]
        note = f"zero window: ours {e0_mean:.4f} ± {e0_std:.4f}"
        if np.isfinite(paper):
            note += f"\npaper {paper:.4f} ± {paper_std:.4f}"
        ax.text(0.98, 0.97, note, transform=ax.transAxes, ha="right", va="top", fontsize="x-small",
                bbox={"facecolor": "white", "edgecolor": "none", "alpha": 0.8, "pad": 1.5})
        ax.set_title(registry.spec(name).symbol, fontsize="medium")
        ax.set_ylabel(r"estimate of $e$")
        ax.set_xlim(-0.05 * w.max(), 1.03 * w.max())
        _zero_window_ylim(ax, [e0_mean - e0_std, e0_mean + e0_std, paper - paper_std, paper + paper_std,
                               e_target if e_target is not None else np.nan])
        lo, hi = ax.get_ylim()
        ax.set_ylim(lo, hi + 0.18 * (hi - lo))  # room for the note above the curves
        ax.set_xlabel(WINDOW_LABEL)
    _legend_below(fig, handles, ncols=3)
    return fig


def fig_ev(sig: xr.Dataset, est: xr.Dataset, e_target: float | None = None) -> Figure:
    """The paper's §6 proposal: ``e`` from the zero-crossing signature ``D_v`` (eq. 19).

    (a) ``D_v`` pooled over every group, at the smallest and largest window, in units of
    ``sigma_Y`` against the lag in rocking periods ``T(a)`` (eq. 5). (b) The same near lag 0
    with the free flight through an impact at ``(0, v)``: slope ``v`` before, ``e v`` after
    (eqs. 4, 6); the kink is the estimator ``e_v`` (slope ratio,
    docs/method.md §5.4). (c) ``e_v`` of every replicate against
    ``dv/dv_max``, the mean extrapolated line and the target.
    """
    pooled = _pooled(sig)
    sigma_y, a, v, dt = (float(pooled.attrs[k]) for k in ("sigma_y", "a", "v", "dt"))
    g = float(pooled.attrs["g"]) if "g" in pooled.attrs else None
    e_ideal = e_target
    lag = pooled["lag"].values
    period = float(period_from_g(a, g)) if g else None
    x = lag / period if period else lag
    x_label = r"time lag $\tau/T(a)$ (T from eq. 5)" if period else "time lag τ (s)"
    windows = pooled["window"].values
    count = pooled["count"].sel(trigger="v")
    shown = sorted({float(windows[0]), float(windows[-1])})

    fig = _new_figure(12.0, 4.8)
    ax_full, ax_zoom, ax_e = fig.subplots(1, 3, width_ratios=[1.2, 1.0, 1.1])
    colors = {shown[0]: "tab:blue", shown[-1]: "tab:orange"}
    for w in shown:
        d = pooled["signature"].sel(trigger="v", window=w).values / sigma_y
        label = f"Δv/Δv$_{{max}}$ = {w:g} ({int(count.sel(window=w))} triggers)"
        ax_full.plot(x, d, color=colors[w], lw=1.0, label=label)
        ax_zoom.plot(lag * 1e3, d, color=colors[w], lw=1.0, marker=".", ms=3, label=label)
    ax_full.axhline(0.0, color="0.6", lw=0.5)
    ax_full.axvline(0.0, color="0.6", lw=0.5)
    ax_full.set_xlabel(x_label)
    ax_full.set_ylabel(r"$D_v(\tau)/\sigma_Y$")
    ax_full.set_title(f"(a) zero-crossing signature, v = {pooled.attrs.get('v_level', 1.0):g} "
                      r"$\sigma_{\dot Y}$", fontsize="medium")

    # zoom: a few free flights of the post-impact arc, 2 e v / g long
    half = 1.5 * 2.0 * v / g if g else 10 * dt
    half = max(half, 8 * dt)
    if g and e_ideal is not None:
        # before: the incoming arc back to the previous crossing; after: the free response
        before = np.linspace(-min(half, 2.0 * v / g), 0.0, 200)
        after = np.linspace(0.0, half, 400)
        ax_zoom.plot(before * 1e3, (v * before + 0.5 * g * before**2) / sigma_y, color="k", ls="--", lw=1.0,
                     label=f"free flight through an impact at (0, v): slope v, then {e_ideal:g} v")
        ax_zoom.plot(after * 1e3, free_rocking(after, 0.0, e_ideal * v, g, e_ideal) / sigma_y,
                     color="k", ls="--", lw=1.0)
    ax_zoom.axhline(0.0, color="0.6", lw=0.5)
    ax_zoom.axvline(0.0, color="0.6", lw=0.5)
    ax_zoom.set_xlim(-half * 1e3, half * 1e3)
    in_view = np.abs(lag) <= half
    sel = pooled["signature"].sel(trigger="v", window=shown).values[..., in_view] / sigma_y
    if np.isfinite(sel).any():
        lo, hi = np.nanmin(sel), np.nanmax(sel)
        pad = 0.1 * (hi - lo if hi > lo else 1.0)
        ax_zoom.set_ylim(lo - pad, hi + pad)
    ax_zoom.set_xlabel("time lag τ (ms)")
    ax_zoom.set_ylabel(r"$D_v(\tau)/\sigma_Y$")
    ax_zoom.set_title("(b) the slope jump at the impact, lag 0", fontsize="medium")

    curves = est["e_hat"].sel(estimator="e_v")
    w = est["window"].values
    mean, std, sem = _replicate_stats(curves)
    spread = ax_e.fill_between(w, mean - std, mean + std, color="tab:blue", alpha=SPREAD_ALPHA, lw=0,
                               label="spread across replicates (mean ± 1 std)")
    means = ax_e.errorbar(w, mean, yerr=sem, color="tab:blue", marker="o", ms=4, capsize=4, elinewidth=1.2,
                          label="mean over replicates ± 1 standard error")
    w_line = np.linspace(0.0, w.max(), 50)
    line = ax_e.plot(w_line, _extrapolated_line(est, "e_v", w_line), color="tab:blue", lw=1.0, ls="-.",
                     label="mean extrapolation to zero window (§5)")
    e0_mean, e0_std, e0_sem = (float(x) for x in _replicate_stats(est["e_hat0"].sel(estimator="e_v")))
    if np.isfinite(e0_std):
        ax_e.bar(0.0, 2 * e0_std, bottom=e0_mean - e0_std, width=0.04 * w.max(), color="tab:blue", alpha=SPREAD_ALPHA)
    ax_e.errorbar(0.0, e0_mean, yerr=e0_sem if np.isfinite(e0_sem) else None, color="tab:blue", capsize=4,
                  **OURS_STYLE)
    ax_e.text(0.98, 0.97, f"zero window: {e0_mean:.4f}, std {e0_std:.4f}", transform=ax_e.transAxes,
              ha="right", va="top", fontsize="small")
    _draw_target(ax_e, e_target)
    ax_e.set_xlim(-0.05 * w.max(), 1.03 * w.max())
    _zero_window_ylim(ax_e, [mean - std, mean + std, e0_mean - e0_std, e0_mean + e0_std,
                             e_target if e_target is not None else np.nan])
    lo, hi = ax_e.get_ylim()
    ax_e.set_ylim(lo, hi + 0.12 * (hi - lo))
    ax_e.set_xlabel(r"relative window size $\Delta v/\Delta v_{max}$")
    ax_e.set_ylabel(r"$\hat e_v$ (slope ratio at lag 0)")
    ax_e.set_title(r"(c) $\hat e_v$ over the replicates", fontsize="medium")
    targets = [ln for ln in ax_e.lines if ln.get_label().startswith("target")]
    _legend_below(fig, [*ax_zoom.get_legend_handles_labels()[0], spread, means, *line, *targets], ncols=3)
    return fig


def fig_amplitude(ds: xr.Dataset, estimators=registry.CANDIDATES) -> Figure:
    """Simplified (eq. 4) vs linearized Housner (eq. 2) estimates against ``sigma_Y/theta_cr``.

    ``ds`` from :func:`rockdec.studies.amplitude.sweep` (the target ``e`` is its attribute
    ``e_target``). Points: mean over replicates, error bars one standard error. The dotted
    line marks where ``auto`` switches model: ``3 sigma_Y`` at the amplitude where eqs. 3
    and 5 differ by 2 % (:func:`rockdec.physics.models.amplitude_limit`).
    """
    e_target = float(ds.attrs["e_target"])
    fig = _new_figure(4.0 * len(estimators), 4.0)
    axes = np.atleast_1d(fig.subplots(1, len(estimators), sharey=False))
    switch = models.auto_switch_ratio()
    for ax, name in zip(axes, estimators):
        for model, color, marker in (("simplified", "tab:blue", "o"), ("housner", "tab:red", "s")):
            values = ds["e_hat0"].sel(model=model, estimator=name)
            mean, _, sem = _replicate_stats(values.transpose("replicate", "ratio"))
            ax.errorbar(ds["ratio"].values, mean, yerr=sem, color=color, marker=marker, capsize=3, label=f"{model} model")
        ax.axvline(switch, color="0.4", ls=":", label="auto switches model")
        _draw_target(ax, e_target)
        ax.set_xscale("log")
        ax.set_xticks(ds["ratio"].values, [f"{r:g}" for r in ds["ratio"].values], rotation=45)
        ax.minorticks_off()
        ax.set_xlabel(r"$\sigma_Y/\theta_{cr}$")
        ax.set_ylabel(f"{name} at zero window")
        ax.set_title(name, fontsize="medium")
    axes[0].legend(fontsize="small")
    return fig


def fig_record(res, axes=None) -> Figure:
    """A measured record's estimate (:meth:`rockdec.RestitutionEstimate.plot`): the
    reported estimator's signature beside its calibration.

    Left: for ``e_v``, the zero-crossing signature ``D_v`` (largest window) through the
    impact at lag 0, with the straight slopes before and after it whose ratio is ``e``
    (eq. 6); for the other estimators, the free-response estimate (even part of ``D_a``)
    beside the free rocking of eqs. 4 and 6 from ``(c1, 0)`` at the corrected ``e`` and
    ``g``: the two part after the first half cycle because a trigger window mixes
    amplitudes, and so periods (eq. 5), which damps the average beyond what ``e`` does
    (paper §5); that bias is what the calibration corrects. Right: the calibration belt
    of the reported estimator (mean raw estimate against the true ``e``, and its 95 %
    band) with the observed raw value and the corrected ``e`` and interval read off it;
    a note instead when the records were declined before calibrating.

    ``res``: a :class:`rockdec.RestitutionEstimate` made from a record (it carries the
    analysis and belts); ``axes``: two axes to draw in, or ``None`` for a new figure.
    """
    doc = res.document
    name = doc["estimator"] or registry.DEFAULT_ESTIMATOR  # none trusted: the default's belt, without a value
    analysis, belt = res.analysis, (res.belts or {}).get(name)
    if axes is None:
        fig = _new_figure(10.0, 4.0)
        left, right = fig.subplots(1, 2)
    else:
        left, right = axes
        fig = left.figure
    e, g = doc["e"], doc["g"]
    if registry.trigger(name) == "v":
        d = analysis.velocity_signature
        tau = (np.arange(d.size) - d.size // 2) * analysis.dt
        left.plot(tau, d, color="tab:blue", lw=1.2, label="$D_v$: average motion through an impact")
        raw = doc["estimators"][name]["raw"]
        if raw is not None and np.isfinite(d).any():
            k = max(2, d.size // 16)
            before = np.polyfit(tau[d.size // 2 - k:d.size // 2 + 1], d[d.size // 2 - k:d.size // 2 + 1], 1)[0]
            span = tau[d.size // 2 - k:d.size // 2 + k + 1]
            left.plot(span[span <= 0], before * span[span <= 0], "k--", lw=1.0, label="slope before the impact")
            left.plot(span[span >= 0], raw * before * span[span >= 0], "r--", lw=1.0, label=f"slope after = {raw:.3f} x before (raw e_v)")
        left.axvline(0.0, color="0.6", lw=0.6)
        title = "zero-crossing signature of the record"
    else:
        r = analysis.free_response
        tau = np.arange(r.size) * analysis.dt
        left.plot(tau, r, color="tab:blue", lw=1.2, label="free-response estimate (even part of $D_a$)")
        if e is not None and g is not None:
            left.plot(tau, free_rocking(tau, float(r[0]), 0.0, g, e), "k--", lw=1.0,
                      label=f"free rocking, e = {e:.3f}, g = {g:.3g} rad/s$^2$ (eqs. 4, 6)")
            left.text(0.98, 0.04, "after the first half cycle the two part: the triggers mix\namplitudes, and so periods "
                      "(the bias the calibration corrects)", transform=left.transAxes, ha="right", va="bottom", fontsize=7)
        title = "signature of the record"
    left.axhline(0.0, color="0.6", lw=0.6)
    left.set(xlabel=r"lag $\tau$ (s)", ylabel="angle (rad)", title=title)
    left.legend(fontsize=8, loc="upper right")
    if belt is None:
        right.text(0.5, 0.5, "no calibration: the records were declined\n(see the reason in the report)", ha="center", va="center",
                   transform=right.transAxes)
        right.set(title="calibration (simulated records)", xticks=[], yticks=[])
        return fig
    from rockdec.calibrate.belt import Z95

    right.fill_between(belt.e, belt.mean - Z95 * belt.spread, belt.mean + Z95 * belt.spread, color="tab:blue", alpha=0.25, label="95 % of simulated estimates")
    right.plot(belt.e, belt.mean, color="tab:blue", label="mean raw estimate")
    right.plot(belt.e, belt.e, **TARGET_STYLE, label="no bias")
    raw = doc["estimators"][name]["raw"]
    if raw is not None:
        right.axhline(raw, color="tab:red", lw=1.0, label=f"observed {name} = {raw:.4f}")
    if e is not None:
        low, high = doc["interval"]
        right.axvspan(low, high, color="tab:red", alpha=0.15, label=f"e = {e:.4f}, 95 %: [{low:.4f}, {high:.4f}]")
        right.axvline(e, color="tab:red", lw=1.0)
    right.set(xlabel="true e", ylabel=f"raw {name} at zero window", title="calibration (simulated records)")
    right.legend(fontsize=8, loc="upper left")
    return fig

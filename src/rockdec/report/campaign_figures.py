"""The figures of a test campaign, drawn from its summary dataset (``results/<campaign>/estimates.nc``,
:func:`rockdec.pipeline.campaign.summary_dataset`): ``e`` of each record and block with its
95 % interval (a forest plot, the blocks side by side), the record model measured off each
record, and each record's diagnostics against their thresholds.

The dataset runs along ``record`` (records, then blocks' pooled estimates, ``kind``), with
``block`` and ``true_e`` (NaN when not known) as coordinates; a figure function takes it and
returns a :class:`matplotlib.figure.Figure` (written by :func:`rockdec.report.figures.save`).
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure

from rockdec.report.figures import _new_figure

__all__ = ["FIGURES", "diagnostics", "forest", "record_model"]


def _positions(ds: xr.Dataset) -> tuple[np.ndarray, list[str]]:
    """The row of each record and block estimate of ``ds`` (in its order), grouped by block (its
    records, then its pooled estimate) with a gap between blocks; and the labels of the rows
    from the top (at ``sorted(rows)``)."""
    rows, labels, y = [], [], 0
    for block in dict.fromkeys(str(b) for b in ds["block"].values):
        members = [i for i in range(ds.sizes["record"]) if str(ds["block"].values[i]) == block]
        members.sort(key=lambda i: str(ds["kind"].values[i]) == "block")
        for i in members:
            rows.append((i, y))
            labels.append(str(ds["record"].values[i]))
            y += 1
        y += 0.6
    order = np.full(ds.sizes["record"], np.nan)
    for i, pos in rows:
        order[i] = pos
    return order, labels


def forest(ds: xr.Dataset) -> Figure:
    """``e`` and its 95 % interval per record (circles) and per block's records pooled
    (diamonds), grouped by block; the true ``e`` (a cross) where it is known; a record with
    no ``e`` is named with its reason's first words at the left.

    Examples
    --------
    >>> ds = xr.Dataset({"e": ("record", [0.9, np.nan]), "interval_low": ("record", [0.85, np.nan]),
    ...                  "interval_high": ("record", [0.93, np.nan]), "reason": ("record", ["", "declined"])},
    ...                 coords={"record": ["a", "b"], "block": ("record", ["A", "B"]), "kind": ("record", ["record", "record"]),
    ...                         "true_e": ("record", [0.9, 0.8])})
    >>> fig = forest(ds)
    >>> [t.get_text() for t in fig.axes[0].get_yticklabels()]
    ['a', 'b']
    """
    y, labels = _positions(ds)
    fig = _new_figure(6.0, 1.2 + 0.32 * len(labels))
    ax = fig.add_subplot()
    pooled = ds["kind"].values == "block"
    free = ds["test"].values == "free" if "test" in ds.coords else np.zeros(pooled.size, dtype=bool)
    e, low, high = (ds[v].values.astype(float) for v in ("e", "interval_low", "interval_high"))
    for mask, marker, label in ((~pooled & ~free, "o", "record"), (pooled & ~free, "D", "block (records pooled)"),
                                (free, "s", "free-rocking test")):
        shown = mask & np.isfinite(e)
        ax.errorbar(e[shown], y[shown], xerr=[e[shown] - low[shown], high[shown] - e[shown]], fmt=marker, capsize=3, label=label)
    true = ds["true_e"].values.astype(float)
    if np.isfinite(true).any():
        ax.plot(true, y, "x", color="k", ms=7, label="true e")
    for i in np.flatnonzero(~np.isfinite(e)):
        reason = str(ds["reason"].values[i]) or "no estimate"
        ax.annotate(f"no e: {reason[:40]}", (0.01, y[i]), xycoords=("axes fraction", "data"), va="center", fontsize=7, color="tab:red")
    ax.set_yticks(np.sort(y), labels)
    ax.invert_yaxis()
    ax.set_xlabel("coefficient of restitution e (95 % interval)")
    ax.grid(axis="x", alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    return fig


def _value(ds: xr.Dataset, name: str) -> np.ndarray:
    return ds[name].values.astype(float) if name in ds else np.full(ds.sizes["record"], np.nan)


def record_model(ds: xr.Dataset) -> Figure:
    """Per record: the sensor noise measured off it (in ``sigma_Y``), the corner of its load
    (rocking frequencies ``1/T(sigma_Y)``, eq. 5; "none" where no colour was detected) and its
    samples per cycle at ``sigma_Y``, each with the standard error the measurement gives."""
    records = ds.where(ds["kind"] == "record", drop=True) if (ds["kind"] == "record").any() else ds
    names = [str(r) for r in records["record"].values]
    panels = (
        ("record_model_measured_sensor_noise_sigma_y", "sensor noise / sigma_Y"),
        ("record_model_measured_load_corner_rocking", "load corner (rocking frequencies)"),
        ("points_per_cycle", "samples per cycle at sigma_Y"),
    )
    fig = _new_figure(9.0, 1.4 + 0.3 * len(names))
    axes = fig.subplots(1, len(panels), sharey=True)
    y = np.arange(len(names))
    coloured = _value(records, "record_model_measured_detected_colour") > 0.5
    for ax, (name, label) in zip(axes, panels):
        value = _value(records, f"{name}_value" if f"{name}_value" in records else name)
        se = _value(records, f"{name}_se")
        if name.endswith("load_corner_rocking"):  # a corner only where colour was detected: else white
            value, se = np.where(coloured, value, np.nan), np.where(coloured, se, np.nan)
        ax.errorbar(value, y, xerr=np.where(np.isfinite(se), se, 0.0), fmt="o", capsize=3)
        for i in np.flatnonzero(~np.isfinite(value)):
            ax.annotate("none", (0.02, y[i]), xycoords=("axes fraction", "data"), va="center", fontsize=7, color="0.4")
        ax.set_xlabel(label)
        ax.grid(axis="x", alpha=0.3)
    axes[0].set_yticks(y, names)
    axes[0].invert_yaxis()
    return fig


def diagnostics(ds: xr.Dataset) -> Figure:
    """Per record and check (:mod:`rockdec.record.diagnostics`): whether the check fired (red)
    or not, with its statistic and its threshold written in the cell (a check fires above or
    below its threshold, as the check reads it; the warnings say which in the table)."""
    records = ds.where(ds["kind"] == "record", drop=True) if (ds["kind"] == "record").any() else ds
    names = [str(r) for r in records["record"].values]
    fig = _new_figure(8.0, 1.6 + 0.35 * len(names))
    ax = fig.add_subplot()
    if "check" not in records.dims:
        ax.text(0.5, 0.5, "no record was checked", ha="center", va="center", transform=ax.transAxes)
        return fig
    checks = [str(c) for c in records["check"].values]
    fired = records["check_fired"].transpose("record", "check").values.astype(float)
    statistic = records["check_statistic"].transpose("record", "check").values.astype(float)
    threshold = records["check_threshold"].transpose("record", "check").values.astype(float)
    ax.imshow(np.where(np.isfinite(fired), fired, 0.0), aspect="auto", cmap=ListedColormap(["#e8f0e8", "#f2a0a0"]), vmin=0, vmax=1)
    for i in range(len(names)):
        for j in range(len(checks)):
            ax.text(j, i, f"{statistic[i, j]:.3g} / {threshold[i, j]:.3g}", ha="center", va="center", fontsize=7)
    ax.set_xticks(np.arange(len(checks)), checks, rotation=30, ha="right")
    ax.set_yticks(np.arange(len(names)), names)
    ax.set_title("statistic / threshold of each check (red: fired)", fontsize=9)
    return fig


#: The campaign's figures by name: what rule ``campaign_figures`` draws.
FIGURES = {"forest": forest, "record_model": record_model, "diagnostics": diagnostics}

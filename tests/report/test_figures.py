"""Figures (paper figs. 1b, 2-4, the e_v figure and the studies' figures), drawn from small
synthetic products; the workflow that draws them is tested in :mod:`test_workflow`."""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.image  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
import pytest  # noqa: E402
import xarray as xr  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from rockdec.report import figures
from rockdec.pipeline import layout
from rockdec.studies import figures as study_figures
from rockdec.physics import models, simulate
from rockdec.pipeline import replicates
from rockdec.rdd import signatures  # noqa: E402

REPO = Path(__file__).resolve().parents[2]

# --- the closed-form free response ---------------------------------------------------


@pytest.mark.parametrize("e", [0.0, 0.5, 0.95, 1.0])
def test_free_rocking_from_rest_hits_the_closed_form_points(e):
    a, g = 0.3, 2.0
    t1 = math.sqrt(2 * a / g)
    t = np.array([0.0, 0.5 * t1, t1, (1 + e) * t1, (1 + 2 * e) * t1])
    r = figures.free_rocking(t, a, 0.0, g, e)
    assert r[0] == pytest.approx(a)
    assert r[1] == pytest.approx(a - g * (0.5 * t1) ** 2 / 2)  # the parabola a - g t^2/2
    assert r[2] == pytest.approx(0.0, abs=1e-12)  # first crossing at sqrt(2a/g)
    assert r[3] == pytest.approx(-(e**2) * a, abs=1e-12)  # first minimum -e^2 a at (1+e) t1
    assert r[4] == pytest.approx(0.0, abs=1e-12)  # second crossing


def test_free_rocking_minimum_is_the_lowest_point_of_the_first_bounce():
    a, g, e = 1.0, 1.0, 0.8
    t1 = math.sqrt(2 * a / g)
    t = np.linspace(0.0, 2 * t1, 20001)
    r = figures.free_rocking(t, a, 0.0, g, e)
    k = np.argmin(r)
    assert r[k] == pytest.approx(-(e**2) * a, rel=1e-6)
    assert t[k] == pytest.approx((1 + e) * t1, abs=2 * (t[1] - t[0]))


def test_free_rocking_comes_to_rest_after_the_geometric_series_of_bounces():
    a, g, e = 1.0, 1.0, 0.6
    t1 = math.sqrt(2 * a / g)
    rest = t1 * (1 + e) / (1 - e)  # t1 + 2 e t1 (1 + e + e^2 + ...)
    t = np.linspace(1.001 * rest, 3 * rest, 50)
    assert np.all(figures.free_rocking(t, a, 0.0, g, e) == 0.0)
    assert np.any(figures.free_rocking(np.linspace(0.9 * rest, 0.999 * rest, 50), a, 0.0, g, e) != 0.0)


def test_free_rocking_after_an_impact_leaves_zero_with_the_given_speed():
    w, g, e = 0.5, 1.0, 0.9
    t = np.array([1e-7, w / g, 2 * w / g, 2 * w / g + e * w / g])
    r = figures.free_rocking(t, 0.0, w, g, e)
    assert r[0] / t[0] == pytest.approx(w, rel=1e-6)
    assert r[1] == pytest.approx(w**2 / (2 * g))  # apex of the first flight
    assert r[2] == pytest.approx(0.0, abs=1e-12)
    assert r[3] == pytest.approx(-((e * w) ** 2) / (2 * g))  # next flight, other side


def test_free_rocking_matches_the_exact_simulator():
    a, g, e, dt = 0.01, 1.0, 0.9, 1e-3
    theta, _ = simulate.simulate_block([0], 2000, dt=dt, g=g, e=e, sigma_p=0.0, theta0=a)
    r = figures.free_rocking(np.arange(2000) * dt, a, 0.0, g, e)
    np.testing.assert_allclose(r, theta[0], atol=1e-12)


def test_periods_differ_by_five_percent_near_a_tenth_of_the_critical_angle():
    x = models.amplitude_limit(0.05)
    assert x == pytest.approx(0.1113, abs=5e-4)  # the paper: negligible below about 0.1
    ratio = models.period_housner(x, 1.0, 1.0) / models.period_simplified(x, 1.0, 1.0)
    assert ratio == pytest.approx(1.05)
    assert models.amplitude_limit(0.10) > x


# --- figures from synthetic products -------------------------------------------------

G, E, DT, SIGMA_P = 1.0, 0.95, 0.00343, 0.003


@pytest.fixture(scope="module")
def products():
    """Small products shaped like the workflow's: 4 series, 2 replicates of 2 series."""
    seeds = np.arange(4)
    theta, _ = simulate.simulate_block(seeds, 6000, dt=DT, g=G, e=E, sigma_p=SIGMA_P, burn_in=4000)
    sigma_y = float(theta.std())
    sigma_ydot = float(np.diff(theta, axis=1).std() / DT)
    sim = xr.Dataset(
        {"theta": (("seed", "time"), theta.astype(np.float32), {"units": "rad"})},
        coords={"seed": seeds, "time": np.arange(theta.shape[1]) * DT},
        attrs={"dt": DT, "g": G, "e": E, "sigma_y": sigma_y, "sigma_ydot": sigma_ydot},
    )
    kw = {"sigma_y": sigma_y, "sigma_ydot": sigma_ydot, "windows": [0.25, 0.5, 1.0], "g": G}
    th = sim["theta"].astype(np.float64).assign_attrs(dt=DT)
    stored = signatures.signature_cube(th, group=xr.DataArray(np.zeros(4, int), dims="seed"), **kw)
    sig = signatures.signature_cube(th, group=xr.DataArray([0, 0, 1, 1], dims="seed"), **kw)
    sig = sig.assign_coords(replicate=("group", [0, 1]))
    est = replicates.replicate_estimates(sig, fit_points=5)
    return {"sim": sim, "stored": stored, "sig": sig, "est": est}


def draw(name, products, e_target=E):
    p = products
    return {
        "fig1b": lambda: figures.fig1b(),
        "fig2": lambda: figures.fig2(p["sim"], p["stored"]),
        "fig3": lambda: figures.fig3(p["est"], e_target),
        "fig4": lambda: figures.fig4(p["est"], e_target),
        "fig_ev": lambda: figures.fig_ev(p["sig"], p["est"], e_target),
    }[name]()


def assert_labelled(fig):
    """Every axes has a y label and an x label, its own or one of an axes sharing its x axis."""
    axes = [ax for ax in fig.axes if ax.get_label() != "<colorbar>"]
    assert axes
    for ax in axes:
        assert ax.get_ylabel().strip(), f"axes '{ax.get_title()}' has no y label"
        siblings = ax.get_shared_x_axes().get_siblings(ax)
        assert any(s.get_xlabel().strip() for s in siblings), f"axes '{ax.get_title()}' has no x label"


@pytest.mark.parametrize("name", layout.FIGURES)
def test_every_figure_has_labelled_axes_and_a_legend(name, products):
    fig = draw(name, products)
    assert isinstance(fig, Figure)
    assert_labelled(fig)
    assert fig.legends or any(ax.get_legend() is not None for ax in fig.axes)


def test_figures_leave_no_pyplot_state(products):
    plt.close("all")
    for name in layout.FIGURES:
        draw(name, products)
    assert plt.get_fignums() == []


def legend_texts(fig):
    texts = [t.get_text() for ax in fig.axes if ax.get_legend() for t in ax.get_legend().get_texts()]
    return texts + [t.get_text() for leg in fig.legends for t in leg.get_texts()]


@pytest.mark.parametrize("name", ["fig3", "fig4"])
def test_paper_values_are_shown_only_for_the_papers_target(name, products):
    assert any("paper" in t for t in legend_texts(draw(name, products, e_target=0.95)))
    assert not any("paper" in t for t in legend_texts(draw(name, products, e_target=0.8)))


def test_extrapolated_lines_start_at_the_mean_zero_window_value(products):
    est = products["est"]
    fig = figures.fig3(est, E)
    starts = {round(float(line.get_ydata()[0]), 12) for ax in fig.axes for line in ax.lines if len(line.get_xdata()) > 2}
    for name in ("e_g", "e_0"):
        assert round(float(est["e_hat0"].sel(estimator=name).mean()), 12) in starts


def test_figures_cope_with_one_replicate_and_missing_estimates(products):
    est = products["est"].isel(replicate=[0]).copy(deep=True)
    est["e_hat"][dict(window=0)] = np.nan
    for fig in (figures.fig3(est, E), figures.fig4(est, E), figures.fig_ev(products["sig"], est, E)):
        assert_labelled(fig)


def drawn(fig: Figure) -> Figure:
    """``fig`` laid out and rendered (extents known)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig).draw()
    return fig


@pytest.fixture(scope="module")
def rendered(products) -> dict[str, Figure]:
    """fig3, fig4 and fig_ev of :func:`products` rendered once (:func:`drawn`), for the
    tests that only read their layout."""
    return {name: drawn(draw(name, products)) for name in ("fig3", "fig4", "fig_ev")}


@pytest.mark.parametrize("name", layout.FIGURES)
def test_no_figure_carries_a_title_naming_the_papers_figure(name, products):
    fig = draw(name, products)
    titles = [ax.get_title() for ax in fig.axes] + [fig._suptitle.get_text() if fig._suptitle else ""]
    assert not any("paper fig" in title.lower() for title in titles), titles


@pytest.mark.parametrize("name", ["fig3", "fig4", "fig_ev"])
def test_legends_sit_below_the_axes_off_the_data_each_entry_once(name, rendered):
    fig = rendered[name]
    assert not any(ax.get_legend() for ax in fig.axes) and len(fig.legends) == 1
    box = fig.legends[0].get_window_extent()
    assert all(box.y1 <= ax.get_window_extent().y0 + 1 for ax in fig.axes)
    texts = legend_texts(fig)
    assert len(texts) == len(set(texts)) and sum("paper" in text for text in texts) <= 1
    assert all(text.get_fontsize() >= 8 for text in fig.legends[0].get_texts())


@pytest.mark.parametrize("name", ["fig3", "fig4", "fig_ev"])
def test_the_target_line_stays_clear_of_the_frame(name, rendered):
    fig = rendered[name]
    for ax in fig.axes:
        for line in ax.lines:
            if line.get_label().startswith("target"):
                lo, hi = ax.get_ylim()
                assert lo + 0.03 * (hi - lo) < E < hi - 0.03 * (hi - lo)


def test_fig3_draws_our_zero_window_value_inside_the_papers_open_diamond(products):
    fig = figures.fig3(products["est"], E)
    for ax in fig.axes:
        paper = next(line for line in ax.lines if line.get_label() == "paper at zero window")
        ours = next(line for line in ax.lines if line.get_label().startswith("ours at zero window"))
        assert paper.get_markerfacecolor() == "none" and ours.get_markersize() < paper.get_markersize()
        assert ours.get_zorder() > paper.get_zorder()


def test_fig3_error_bars_are_a_visible_part_of_each_panel(products):
    fig = drawn(figures.fig3(products["est"], E))
    for ax in fig.axes:
        bars = [c for c in ax.collections if type(c).__name__ == "LineCollection"]
        spans = [abs(seg[1][1] - seg[0][1]) for c in bars for seg in c.get_segments()]
        lo, hi = ax.get_ylim()
        assert spans and max(spans) > 0.01 * (hi - lo)


def test_fig_ev_draws_the_spread_as_a_band_and_the_standard_errors_as_bars(products):
    fig = figures.fig_ev(products["sig"], products["est"], E)
    texts = legend_texts(fig)
    from matplotlib.collections import PolyCollection

    band = next(c for c in fig.axes[2].collections if c.get_label().startswith("spread across replicates"))
    assert isinstance(band, PolyCollection) and band.get_label() in texts  # a shaded band, in the legend
    assert any(text.startswith("mean over replicates ± 1 standard error") for text in texts)


def test_fig2_overlays_the_free_response_from_the_trigger_level(products):
    fig = figures.fig2(products["sim"], products["stored"])
    ax = fig.axes[2]
    ideal = next(line for line in ax.lines if line.get_linestyle() == "--")
    tau, r = ideal.get_xdata(), ideal.get_ydata()
    t1 = math.sqrt(2 * float(products["stored"].attrs["a"]) / G)
    assert r[0] == pytest.approx(1.0)  # normalized by the trigger level a
    assert np.interp(t1, tau, r) == pytest.approx(0.0, abs=1e-3)
    assert r.min() == pytest.approx(-(E**2), abs=1e-3)


def test_save_writes_png_at_150_dpi_and_pdf_reproducibly(tmp_path):
    fig = figures.fig1b()
    png, pdf = tmp_path / "f.png", tmp_path / "f.pdf"
    figures.save(fig, [png, pdf])
    image = matplotlib.image.imread(png)
    width, height = fig.get_size_inches()
    assert image.shape[:2] == (round(height * 150), round(width * 150))
    assert pdf.read_bytes().startswith(b"%PDF")
    first = png.read_bytes(), pdf.read_bytes()
    figures.save(fig, [png, pdf])
    assert (png.read_bytes(), pdf.read_bytes()) == first


def test_save_lays_the_figure_out_once_for_both_formats_and_keeps_its_layout_engine(tmp_path, monkeypatch):
    fig = figures.fig1b()
    engine = fig.get_layout_engine()
    laid_out = []
    execute = type(engine).execute
    monkeypatch.setattr(type(engine), "execute", lambda self, f: (laid_out.append(f), execute(self, f))[1])
    figures.save(fig, [tmp_path / "f.png", tmp_path / "f.pdf"])
    assert laid_out == [fig] and fig.get_layout_engine() is engine
    figures.save(fig, [tmp_path / "f.pdf"])
    assert laid_out == [fig, fig]


# --- the studies' figures --------------------------------------------------------------


def test_fig_amplitude_draws_the_target_stored_in_the_sweep():
    shape = {"ratio": [0.002, 0.01], "model": ["simplified", "housner"], "estimator": ["e_0", "e4", "e_v"], "replicate": [0, 1]}
    values = np.random.default_rng(0).normal(0.8, 0.01, [len(v) for v in shape.values()])
    ds = xr.Dataset({"e_hat0": (tuple(shape), values)}, coords=shape, attrs={"e_target": 0.8})
    fig = figures.fig_amplitude(ds)
    assert_labelled(fig)
    for ax in fig.axes:
        targets = [line for line in ax.lines if line.get_label() == "target e = 0.8"]
        assert len(targets) == 1 and list(targets[0].get_ydata()) == [0.8, 0.8]


def test_pareto_figure_labels_the_front_and_marks_the_base():
    # two estimators, three configurations each; the base costs most and is the most accurate
    rows = [(knob, value, cost, name, rmse, knob == "level" and value == "2")
            for name in ("e4", "e_v")
            for knob, value, cost, rmse in (("n_points", "1500", 1.0, 0.03), ("n_points", "3000", 2.0, 0.04),
                                            ("level", "2", 4.0, 0.01))]
    table = pd.DataFrame(rows, columns=["knob", "value", "cpu_s_per_replicate", "estimator", "rmse", "base"])
    # the settings that tell configurations apart (one marker each)
    table = table.assign(kind="exact", points_per_cycle=75.0, n_points=table["value"], series_per_replicate=200,
                         n_windows=10, level=2.0, n_periods=2.5)
    fig = study_figures.pareto_figure(table)
    shown = [ax for ax in fig.axes if ax.get_visible()]
    assert [ax.get_title().split(":")[0] for ax in shown] == ["e4", "e_v"]
    for ax in shown:
        assert sorted(text.get_text() for text in ax.texts) == ["base", "points 1500"]  # 3000 is dominated
    assert "base scene" in legend_texts(fig)

"""The workflow's light steps, one function each: files in, files out.

The workflow's rules of the same names (``stored_series``, ``series``, ``stored_signature``,
``estimates``, ``table_readings``: ``run:`` through :func:`rockdec.pipeline.in_snakemake.step`,
inside the Snakemake process; ``fig1b``, ``fig2``, ``fig3``, ``fig4``, ``fig_ev``: through
:func:`rockdec.pipeline.in_snakemake.draw`, in a worker process of
:mod:`rockdec.pipeline.figure_workers`) and ``rockdec verify --rebuild``
(:func:`rockdec.pipeline.archive.rebuild`) call these functions, so a product rebuilt from an
archive is made by the code that made it in the workflow. Figures import matplotlib, and
the estimates the estimators' kernels, only when they run.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from rockdec import io

__all__ = [
    "estimates", "fig1b", "fig2", "fig3", "fig4", "fig_ev", "series", "stored_series", "stored_signature",
    "table_readings",
]

Paths = Sequence[str | Path]


def stored_series(run: str | Path, nc: str | Path, records: dict) -> None:
    """Rule ``stored_series``: the series scene ``records`` keeps (fig. 2,
    :func:`rockdec.pipeline.layout.simulation_seeds`), simulated under the run contract ``run``
    (``run.json``) and written as float32. A handful of series: on one thread of Dask's
    ``threads`` engine whatever ``ROCKDEC_DASK_SCHEDULER`` names (every engine gives the same
    numbers, :mod:`rockdec.engine`), so no worker process starts inside Snakemake's."""
    from rockdec import engine
    from rockdec.pipeline import layout
    from rockdec.physics.run import Run

    ds = Run.read(run).dataset(layout.simulation_seeds(records), records["n_points"], records["chunk_seeds"])
    ds.attrs.update(io.provenance("stored_series", records, inputs=[run]))
    with engine.session(1, scheduler="threads"):
        io.write_netcdf(ds, nc, float32=("theta", "theta_dot"))


def series(run: str | Path, nc: str | Path, records: dict, replicate: int, threads: int) -> None:
    """Rule ``series`` (scenes with ``store_series: all``): every series of replicate
    ``replicate``, simulated under the run contract ``run`` and written as float32, chunked
    by seed (:func:`rockdec.pipeline.series.write_replicate`), on ``threads`` threads of
    Dask's ``threads`` engine whatever ``ROCKDEC_DASK_SCHEDULER`` names (every engine gives
    the same numbers, :mod:`rockdec.engine`), so no worker process starts inside
    Snakemake's."""
    from rockdec import engine
    from rockdec.pipeline import series as series_files
    from rockdec.physics.run import Run

    with engine.session(threads, scheduler="threads"):
        series_files.write_replicate(Run.read(run), records, replicate, nc)


def stored_signature(series: str | Path, nc: str | Path, settings: dict) -> None:
    """Rule ``stored_signature``: the signatures of the stored series ``series`` pooled into one
    group (fig. 2c), under a scene's ``signatures`` settings, with the run's attributes."""
    import numpy as np

    from rockdec.pipeline import replicates
    from rockdec.physics.run import Run

    with io.open_dataset(series) as sim:
        run = Run.from_attrs(sim.attrs)
        theta = sim["theta"].astype(np.float64).load().assign_attrs(dt=run.dt)
    n = theta.sizes["seed"]
    cube = replicates.scene_signatures(
        theta, settings, sigma_y=run.sigma_y, sigma_ydot=run.sigma_ydot, g=run.g,
        group=np.zeros(n, dtype=np.int64), replicate_of_group=[0],
    )
    cube.attrs.update({**run.to_attrs(), **io.provenance("stored_signature", settings, inputs=[series])})
    io.write_netcdf(cube, nc)


def estimates(signatures: str | Path, nc: str | Path, csv: str | Path, md: str | Path, options: dict) -> None:
    """Rule ``estimates``: the estimators of eqs. 25-27 and e_v per replicate, their
    zero-window extrapolation (:func:`rockdec.pipeline.replicates.scene_estimates`, the analysis core
    of :mod:`rockdec.rdd.estimators` over the replicates) and the table beside the paper's,
    from the signature file ``signatures``."""
    from rockdec.pipeline import replicates
    from rockdec.report import tables  # the estimators' kernels: not loaded by the figure steps

    with io.open_dataset(signatures) as cube:
        cube = cube.load()
    est, table = replicates.scene_estimates(cube, options)
    est.attrs.update(io.provenance("estimates", options, inputs=[signatures]))
    io.write_netcdf(est, nc)
    tables.write_table(table, csv, md)


def table_readings(readings: str | Path, nc: str | Path, csv: str | Path, md: str | Path, weights: str) -> None:
    """Rule ``table_readings``: every reading of the paper's sizes in one dataset and one
    table (:func:`rockdec.pipeline.replicates.readings_estimates`), from ``readings``."""
    from rockdec.pipeline import replicates
    from rockdec.report import tables

    with io.open_dataset(readings) as curves:
        combined, table = replicates.readings_estimates(curves.load(), weights)
    combined.attrs.update(io.provenance("table_readings", {"weights": weights}, inputs=[readings]))
    io.write_netcdf(combined, nc)
    tables.write_table(table, csv, md)


def fig1b(outputs: Paths) -> None:
    """Rule ``fig1b``: paper fig. 1b, the free-rocking periods of eqs. 3 and 5."""
    from rockdec.report import figures

    figures.save(figures.fig1b(), outputs)


def fig2(series: str | Path, signature: str | Path, outputs: Paths) -> None:
    """Rule ``fig2``: paper fig. 2, stored series and their pooled free-response estimate."""
    from rockdec.report import figures

    with io.open_dataset(series) as sim, io.open_dataset(signature) as sig:
        fig = figures.fig2(sim.load(), sig.load())
    figures.save(fig, outputs)


def fig3(estimates: str | Path, outputs: Paths) -> None:
    """Rule ``fig3``: paper fig. 3, e_g and e_0 against the window size."""
    from rockdec.report import figures

    with io.open_dataset(estimates) as est:
        fig = figures.fig3(est.load(), e_target=est.attrs["e_target"])
    figures.save(fig, outputs)


def fig4(estimates: str | Path, outputs: Paths) -> None:
    """Rule ``fig4``: paper fig. 4, e1..e4 of every replicate against the window size."""
    from rockdec.report import figures

    with io.open_dataset(estimates) as est:
        fig = figures.fig4(est.load(), e_target=est.attrs["e_target"])
    figures.save(fig, outputs)


def fig_ev(signatures: str | Path, estimates: str | Path, outputs: Paths) -> None:
    """Rule ``fig_ev``: the D_v signature and the estimator e_v (the paper's section 6)."""
    from rockdec.report import figures

    with io.open_dataset(signatures) as sig, io.open_dataset(estimates) as est:
        fig = figures.fig_ev(sig.load(), est.load(), e_target=est.attrs["e_target"])
    figures.save(fig, outputs)

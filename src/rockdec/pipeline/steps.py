"""The workflow's steps after the signatures, one function each: files in, files out.

The workflow's rules of the same names (``estimates``, ``table_readings``, ``fig1b``,
``fig2``, ``fig3``, ``fig4``, ``fig_ev``: ``run:`` through :func:`rockdec.pipeline.in_snakemake.step`,
inside the Snakemake process) and ``rockdec verify --rebuild``
(:func:`rockdec.pipeline.archive.rebuild`) call these functions, so a product rebuilt from an
archive is made by the code that made it in the workflow. Figures import matplotlib, and
the estimates the estimators' kernels, only when they run.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from rockdec import io

Paths = Sequence[str | Path]


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

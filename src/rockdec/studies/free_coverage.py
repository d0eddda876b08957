"""Does the free-rocking interval hold? Coverage and per-impact bias on simulated releases.

A cell is a true ``e``, a model (simplified, eq. 4, or linearised Housner, eq. 2 at a release
angle of :data:`HOUSNER_RATIO` of ``theta_cr``), a sensor noise in units of the release angle
and the samples per cycle at the release angle (eq. 5, or eq. 3 under Housner). Each record
is one release from rest (:func:`free_record`: the project simulator with no load,
:func:`rockdec.physics.simulate.simulate_model` with ``sigma_p = 0``), held for
:data:`HOLD_SAMPLES` samples first, recorded until the block is at rest, plus white sensor
noise. :func:`run_cell` analyses each with :func:`rockdec.free.analysis.analyse_free_rocking`
and tallies how often the 95 % interval covers the true ``e``, and the bias of the
per-impact ``e`` in units of its standard error. benchmarks/free_coverage.py runs the grid of
cells and prints the table.

Seeds: record ``i`` of a cell draws its noise from ``numpy.random.default_rng(seed + i)``
with ``seed`` the cell's first seed, so a record is regenerable from its seed alone.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from rockdec.free.analysis import analyse_free_rocking
from rockdec.physics.models import period_from_g, period_housner
from rockdec.physics.simulate import simulate_model
from rockdec.timeaxis import RecordError

__all__ = [
    "GRID_DENSITY", "GRID_E", "GRID_MODELS", "GRID_NOISE", "GRID_RECORDS", "HOLD_SAMPLES", "free_record",
    "markdown", "record_density", "run_cell", "run_grid",
]

#: Release angle over ``theta_cr`` of the Housner cells: where eqs. 3 and 5 differ by about
#: 13 %, so the parabola would not do.
HOUSNER_RATIO = 0.3

#: The grid of cells of the study (issue 37): true ``e``, sensor noise in units of the release
#: angle, models, records per cell, and the range of samples per cycle the records draw from.
GRID_E = (0.6, 0.8, 0.9, 0.95, 0.98)
GRID_NOISE = (0.0, 0.01, 0.03, 0.05)
GRID_MODELS = ("simplified", "housner")
GRID_RECORDS = 50
GRID_DENSITY = (20.0, 500.0)

#: Samples the block is held at its release angle before it is let go.
HOLD_SAMPLES = 20

#: Rest recorded after the block comes to rest, as a fraction of the time it rocks.
REST_SHARE = 0.1

#: The release angle (rad) and ``g`` (rad/s^2) of the simulated blocks: any values do (the
#: analysis is invariant to both scales, tests/free/test_analysis.py), these are a slender
#: laboratory block's.
RELEASE_ANGLE, G = 0.02, 1.0


def free_record(e: float, *, model: str = "simplified", noise: float = 0.0, samples_per_cycle: float = 75.0, seed: int = 0,
                theta0: float = RELEASE_ANGLE, g: float = G, hold: int = HOLD_SAMPLES, ratio: float = HOUSNER_RATIO):
    """One simulated free-rocking record: held at ``theta0``, released, rocking to rest.

    Parameters
    ----------
    e : float
        Coefficient of restitution (eq. 6).
    model : {"simplified", "housner"}
        The simulated flight (eq. 4 or eq. 2 with ``theta_cr = theta0/ratio``).
    noise : float
        White sensor noise, standard deviation in units of ``theta0``.
    samples_per_cycle : float
        Samples per rocking cycle at the release angle (eq. 5, or eq. 3).
    seed : int
        Seed of the noise.
    theta0 : float
        Release angle (rad).
    g : float
        ``nu^2 theta_cr`` (rad/s^2).
    hold : int
        Samples held at ``theta0`` before the release.
    ratio : float
        ``theta0/theta_cr`` of the Housner model.

    Returns
    -------
    tuple
        ``(theta, dt, theta_cr)``: the record (rad), its step (s) and the critical angle
        (rad; ``None`` under the simplified model).

    Examples
    --------
    >>> theta, dt, theta_cr = free_record(0.9, samples_per_cycle=40)
    >>> theta[:HOLD_SAMPLES + 1].tolist() == [RELEASE_ANGLE] * (HOLD_SAMPLES + 1), theta_cr is None
    (True, True)
    """
    theta_cr = theta0 / ratio if model == "housner" else None
    period = float(period_from_g(theta0, g)) if model == "simplified" else float(period_housner(theta0, math.sqrt(g / theta_cr), theta_cr))
    dt = period / samples_per_cycle
    rocking = period / 4.0 + period / 2.0 * e / (1.0 - e)  # the fall, then flights shrinking by e (eq. 6)
    n_points = int(math.ceil((1.0 + REST_SHARE) * rocking / dt)) + 1
    flight = simulate_model(model, [0], n_points, dt=dt, g=g, e=e, sigma_p=0.0, theta_cr=theta_cr, theta0=theta0)[0][0]
    theta = np.concatenate([np.full(hold, theta0), flight])
    if noise > 0.0:
        theta = theta + np.random.default_rng(seed).normal(0.0, noise * theta0, theta.size)
    return theta, dt, theta_cr


@dataclass(frozen=True)
class Cell:
    """Tally of one cell: records, answered, covered; per-impact ``(e_i - e)/se_i`` mean and
    count; the mean impacts per answered record; declines and refusals (reasons counted)."""

    e: float
    model: str
    noise: float
    samples_per_cycle: float | tuple
    records: int
    answered: int
    covered: int
    impacts: int
    z_mean: float
    z_std: float
    width: float
    failures: dict

    @property
    def coverage(self) -> float:
        """Share of the answered records whose interval covers ``e``."""
        return self.covered / self.answered if self.answered else math.nan


def record_density(samples_per_cycle, seed: int) -> float:
    """Samples per cycle of record ``seed``: ``samples_per_cycle`` itself, or for a range
    ``(low, high)`` a draw log-uniform in it from ``numpy.random.default_rng([seed, 1])``
    (apart from the record's noise stream).

    Parameters
    ----------
    samples_per_cycle : float or tuple of float
        A density, or a range ``(low, high)``.
    seed : int
        The record's seed.

    Returns
    -------
    float
        The record's samples per cycle at its release angle.

    Examples
    --------
    >>> record_density(75.0, 3)
    75.0
    >>> 20.0 <= record_density((20.0, 500.0), 3) <= 500.0
    True
    """
    if np.ndim(samples_per_cycle) == 0:
        return float(samples_per_cycle)
    low, high = samples_per_cycle
    return float(math.exp(np.random.default_rng([seed, 1]).uniform(math.log(low), math.log(high))))


def run_cell(e: float, *, model: str = "simplified", noise: float = 0.0, samples_per_cycle=75.0, n_records: int = 50,
             seed: int = 0, **analysis) -> Cell:
    """Simulate ``n_records`` records of a cell (:func:`free_record`, seeds ``seed + i``),
    analyse each and tally coverage and per-impact bias.

    Parameters
    ----------
    e, model, noise : float, str, float
        The cell (:func:`free_record`).
    samples_per_cycle : float or tuple of float
        Samples per cycle at the release angle, or a range ``(low, high)`` each record draws
        from (:func:`record_density`).
    n_records : int
        Records in the cell.
    seed : int
        Seed of the first record's noise.
    **analysis
        Passed on to :func:`rockdec.free.analysis.analyse_free_rocking`.

    Returns
    -------
    Cell
        The tally.

    Examples
    --------
    >>> cell = run_cell(0.9, noise=0.01, n_records=3)
    >>> cell.answered, cell.impacts > 10
    (3, True)
    """
    answered = covered = 0
    z, widths, impacts, failures = [], [], 0, {}
    for i in range(n_records):
        theta, dt, theta_cr = free_record(e, model=model, noise=noise, samples_per_cycle=record_density(samples_per_cycle, seed + i),
                                          seed=seed + i)
        try:
            fit = analyse_free_rocking(theta, dt, model=model, theta_cr=theta_cr, **analysis)
        except RecordError as err:
            key = _kind(str(err))
            failures[key] = failures.get(key, 0) + 1
            continue
        if fit.reason is not None:
            failures[_kind(fit.reason)] = failures.get(_kind(fit.reason), 0) + 1
            continue
        answered += 1
        covered += fit.e_interval[0] <= e <= fit.e_interval[1]
        widths.append(fit.e_interval[1] - fit.e_interval[0])
        ok = fit.e_impact_se > 0
        z.extend(((fit.e_impact[ok] - e) / fit.e_impact_se[ok]).tolist())
        impacts += fit.n_impacts
    z = np.asarray(z)
    return Cell(e, model, noise, samples_per_cycle, n_records, answered, covered, impacts,
                float(z.mean()) if z.size else math.nan, float(z.std()) if z.size else math.nan,
                float(np.median(widths)) if widths else math.nan, failures)


def run_grid(e=GRID_E, noise=GRID_NOISE, models=GRID_MODELS, n_records: int = GRID_RECORDS, samples_per_cycle=GRID_DENSITY,
             seed: int = 0) -> list[Cell]:
    """Every cell of the grid (:func:`run_cell`), models outermost; cell ``c`` seeds its
    records from ``seed + 1000 c``.

    Parameters
    ----------
    e, noise, models : sequence
        True ``e``, sensor noise (in units of the release angle) and models of the cells.
    n_records : int
        Records per cell.
    samples_per_cycle : float or tuple of float
        Density, or the range each record draws its own from (:func:`record_density`).
    seed : int
        Seed of the first cell's first record.

    Returns
    -------
    list of Cell
        One tally per cell.

    Examples
    --------
    >>> [c.answered for c in run_grid(e=(0.9,), noise=(0.01,), models=("simplified",), n_records=2)]
    [2]
    """
    cells = []
    for model in models:
        for e_true in e:
            for sigma in noise:
                cells.append(run_cell(e_true, model=model, noise=sigma, samples_per_cycle=samples_per_cycle, n_records=n_records,
                                      seed=seed + 1000 * len(cells)))
    return cells


def _kind(sentence: str) -> str:
    """A refusal or decline without its numbers: its first clause, numbers as ``#``."""
    return re.sub(r"\d+(\.\d+)?", "#", sentence.split(",")[0])


def markdown(cells: list[Cell]) -> str:
    """A Markdown table of cells, then the pooled coverage over all answered records.

    Parameters
    ----------
    cells : list of Cell
        Tallies of :func:`run_cell`.

    Returns
    -------
    str
        The table (one row per cell: answered records, coverage of the 95 % interval, impacts
        per record, median width, mean and standard deviation of ``(e_i - e)/se_i``, declines
        and refusals by kind) and a line with the pooled coverage, the lowest cell and the
        largest per-impact bias.

    Examples
    --------
    >>> c = Cell(0.9, "simplified", 0.01, 75.0, 50, 50, 48, 400, 0.02, 1.0, 0.004, {})
    >>> print(markdown([c]).splitlines()[2])
    | 0.9 | simplified | 1 % | 75 | 50 | 50 | 96.0 % | 8.0 | 0.004 | +0.02 | 1.00 |  |
    """
    lines = ["| e | model | noise | samples/cycle | records | answered | coverage | impacts/record | median width | "
             "bias/se per impact | sd of z |  declined or refused |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for c in cells:
        why = "; ".join(f"{k} ({v})" for k, v in sorted(c.failures.items()))
        density = "-".join(f"{v:g}" for v in np.atleast_1d(c.samples_per_cycle))
        lines.append(f"| {c.e:g} | {c.model} | {c.noise * 100:g} % | {density} | {c.records} | {c.answered} | "
                     f"{c.coverage * 100:.1f} % | {c.impacts / max(c.answered, 1):.1f} | {c.width:.3g} | {c.z_mean:+.2f} | "
                     f"{c.z_std:.2f} | {why} |")
    answered = sum(c.answered for c in cells)
    covered = sum(c.covered for c in cells)
    lines.append("")
    lines.append(f"Pooled: {covered} of {answered} answered intervals cover e ({100 * covered / max(answered, 1):.1f} %); "
                 f"lowest cell {min((c.coverage for c in cells if c.answered), default=math.nan) * 100:.1f} %; "
                 f"largest |bias/se| per impact {max((abs(c.z_mean) for c in cells if c.impacts), default=math.nan):.2f}.")
    return "\n".join(lines)

"""Calibration by simulation: how each estimator of ``e`` scatters about the truth, for a measured record.

Every estimator of eqs. 25-27 is biased by an amount that depends on ``e`` and the
sampling, and the zero-window line's standard error understates the spread, so both are
measured on records simulated like the measured one. Under eq. 4 the statistics depend only
on ``e``, the samples per cycle at ``sigma_Y`` (eq. 5) and the record model
(:func:`binned_model`): :func:`build` simulates, at each ``e`` of :data:`E_GRID`,
:data:`SETS_PER_E` record sets (:func:`sets_per_e`) of the records' lengths (beyond
:data:`LENGTH_CAP`: :data:`E_GRID_LONG`, :func:`simulated_lengths`, :func:`spread_scale`),
``g = sigma_p = 1``, at the step (:func:`step_for`) where the analysis reads the record's
samples per cycle; it stores every estimator's zero-window value, ``g`` and every check's
statistic per set. The belt is :mod:`rockdec.calibrate.belt`.

:func:`load_or_build` stores it as NetCDF under a name hashed from its settings and the
pipeline's source (:func:`settings_hash`, :func:`pipeline_fingerprint`), trusts a file only
when its values match the SHA-256 it carries (else rebuilds it with a note), and builds one
at a time: the builder holds ``calibration-<hash>.building`` and touches it every
:data:`HEARTBEAT_S` seconds; a lock untouched for :data:`STALE_S` seconds is taken over.

Explanation: docs/explanation/method/measured-record.md (calibration by simulation, long
records); the cache: docs/how-to/own-record.md.
"""

from __future__ import annotations

import contextlib
import dataclasses
import errno
import functools
import hashlib
import json
import logging
import math
import os
import signal
import socket
import sys
import threading
import time
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from rockdec import io, locks
from rockdec._version import __version__
from rockdec.record import diagnostics, repair
from rockdec import engine
from rockdec.rdd import measured, registry
from rockdec.calibrate import ncread
from rockdec.physics.models import SCALE_CONSTANT_GUESS, step_for_density
from rockdec.physics.record_model import PAPER, Load, RecordModel, SensorNoise
from rockdec.sources import package_sources
from rockdec.validate import InputError

if TYPE_CHECKING:  # annotations only: xarray loads where a function needs it
    import xarray as xr

__all__ = [
    "CALIBRATION_SEED_OFFSET", "E_GRID", "E_GRID_LONG", "FILTER_BIN", "LENGTH_CAP", "NAMES", "NOISE_BIN",
    "PAPER", "PILOT_SETS", "POLE_BIN", "PPC_BIN", "PPC_BIN_LONG", "RATIO_BIN", "SEED_STRIDE",
    "LENGTHS_PER_DECADE", "LENGTH_GRID_MIN", "SETS_PER_E", "SETS_PER_E_CAPPED", "SET_PPC_TOLERANCE", "SET_STEP_TRIES", "STALE_S", "binned_model",
    "build", "calibration_settings", "grid_tasks", "length_bin", "load_or_build", "pipeline_fingerprint", "ppc_key",
    "seed_base", "sets_per_e", "settings_hash", "simulated_lengths", "spread_scale", "step_for",
]

log = logging.getLogger(__name__)

#: True ``e`` of the calibration grid: about evenly spaced in ``log(1 - e)``, in which the
#: spread of the estimators is smooth (:mod:`rockdec.calibrate.belt`); evidence for its size:
#: docs/explanation/constants.md.
E_GRID = (0.4, 0.55, 0.7, 0.8, 0.865, 0.92, 0.95, 0.972, 0.985, 0.995)

#: Simulated record sets per grid point: ``SETS_PER_E`` for records of at most
#: :data:`LENGTH_CAP` samples in all, whatever their record model; ``SETS_PER_E_CAPPED`` for a
#: calibration on shortened records (:func:`simulated_lengths`), whose sets are each as long
#: as the cap. The belt's spread and mean curve come from these sets, and their error is
#: shared by every record a calibration serves: the interval's coverage and width scatter
#: from one calibration to the next by about ``1/sqrt(sets)`` (evidence:
#: ``benchmarks/calibration_replicates.py``; cold time: ``benchmarks/bench_estimate.py``;
#: docs/explanation/constants.md).
SETS_PER_E, SETS_PER_E_CAPPED = 120, 30

#: Records longer than this (samples in all) are calibrated on simulated records of this
#: many samples in all (:func:`simulated_lengths`), their belt's spread scaled to the
#: records' length (:func:`spread_scale`).
LENGTH_CAP = 1_000_000

#: With ``length_grid`` (:func:`calibration_settings`), records of ``LENGTH_GRID_MIN`` to
#: :data:`LENGTH_CAP` samples in all are calibrated on simulated records of the grid length
#: at or below theirs, ``LENGTHS_PER_DECADE`` lengths a decade (:func:`length_bin`), their
#: belt's spread scaled as the cap's (:func:`spread_scale`): records of nearby lengths share
#: one calibration, never longer than theirs. Shorter records keep their own lengths.
LENGTHS_PER_DECADE, LENGTH_GRID_MIN = 2, 1_000


def _with_midpoints(grid) -> tuple[float, ...]:
    """``grid`` and the midpoint in ``log(1 - e)`` of each pair of neighbours (4 significant digits)."""
    u = np.log1p(-np.asarray(grid, dtype=float))
    return tuple(sorted({*grid, *(float(f"{1.0 - math.exp(0.5 * (a + b)):.4g}") for a, b in zip(u[:-1], u[1:]))}))


#: True ``e`` of the calibration of records longer than :data:`LENGTH_CAP`: :data:`E_GRID`
#: and the midpoints between its points, so that the mean curve follows the bias to a
#: fraction of such a record's narrow spread.
E_GRID_LONG = _with_midpoints(E_GRID)

#: Pilot sets of each iteration of the step search, and the most samples of a pilot record
#: (:func:`step_for`); under a coloured load a pilot record is as long as the record, up to
#: ``PILOT_SAMPLES_COLOURED``.
PILOT_SETS, PILOT_SAMPLES, PILOT_SAMPLES_COLOURED = 8, 50_000, 200_000

#: Calibrations are shared by records whose samples per cycle agree within this relative
#: step; records longer than :data:`LENGTH_CAP`, within the finer ``PPC_BIN_LONG``: the bias
#: of ``e_v`` moves from one bin of ``PPC_BIN`` to the next by more than a 20-million-sample
#: record's spread (``benchmarks/long_coverage.py``).
PPC_BIN, PPC_BIN_LONG = 0.1, 0.02

#: Under a coloured load, the sets of a grid point are re-simulated (same seeds) at a
#: corrected step until the median samples per cycle read off them lies within this
#: relative distance of the calibration's (a quarter of :data:`PPC_BIN`), at most
#: ``SET_STEP_TRIES`` times (:func:`_grid_point`).
SET_PPC_TOLERANCE, SET_STEP_TRIES = PPC_BIN / 4, 3

#: Calibrations are shared by records whose sensor noise (in ``sigma_Y``) and load pole
#: (``-ln`` of the pole per sample) agree within these relative steps (:func:`binned_model`).
NOISE_BIN, POLE_BIN = 0.1, 0.1

#: Calibrations are shared by records whose sensor filter's corner per sample agrees within
#: this relative step (:func:`binned_model`): a filter's effect on ``e`` changes steeply with
#: its corner (``benchmarks/filter_study.py``), so its bins are half the load's.
FILTER_BIN = 0.05

#: Housner's model (eq. 2) is not scale-free in ``sigma_Y / theta_cr``: calibrations are
#: shared by records whose ratio agrees within this relative step.
RATIO_BIN = 0.1

#: Fewest iterations of the step search under Housner's model, which also sets ``theta_cr``.
HOUSNER_ITERATIONS = 5

#: Names calibrated: every estimator of e, and g.
NAMES = (*registry.ESTIMATORS, measured.G_NAME)

#: Seeds of calibration records start here (apart from scene seeds and pilot seeds); each
#: calibration draws from its own base, ``CALIBRATION_SEED_OFFSET + h * SEED_STRIDE`` with
#: ``h < SEED_BASES`` (:func:`seed_base`), all below ``CALIBRATION_SEED_OFFSET + 2**50``.
CALIBRATION_SEED_OFFSET = 2**61
SEED_STRIDE, SEED_BASES = 10**9, 2**20

#: Seconds between touches of a build lock, and age of its mtime after which it is stale.
HEARTBEAT_S, STALE_S = 10.0, 120.0

#: Seconds between looks at a lock held by another run.
POLL_S = 1.0



def log_bin(x: float, width: float) -> float:
    """``x > 0`` rounded to the nearest of the bins ``exp(width k)`` (``k`` integer), to 4
    significant digits: values within a relative step ``width`` share a bin."""
    return float(f"{math.exp(width * round(math.log(x) / width)):.4g}")


def ppc_key(points_per_cycle: float, width: float = PPC_BIN) -> float:
    """Samples per cycle rounded to the calibration's bins (:data:`PPC_BIN`, relative, or ``width``)."""
    return log_bin(points_per_cycle, width)


def binned_model(model: RecordModel, points_per_cycle: float, ppc_bin: float = PPC_BIN) -> RecordModel:
    """The record model a calibration simulates for records of ``model`` read at
    ``points_per_cycle`` samples per cycle: the sensor noise (in ``sigma_Y``) on the bins
    of :data:`NOISE_BIN`, and a low-pass load's pole per sample on the bins of
    :data:`POLE_BIN`, so that records of nearly the same model share a calibration.

    The load is matched by its pole per sample, ``alpha = exp(-2 pi corner / N)`` at the
    records' own ``N = points_per_cycle`` (what :func:`rockdec.record.record_measure.measure`
    reads directly): ``-ln alpha`` is binned and the corner stated at the binned samples
    per cycle (:func:`ppc_key` on bins of ``ppc_bin``), at which the calibration simulates, so that the
    calibration's records carry the binned pole per sample and are read at the binned
    samples per cycle. A spectrum load is simulated as stated (its table in rocking
    frequencies, placed at the binned samples per cycle). A sensor filter is matched like the
    load, by its corner per sample (``corner / N``, binned on :data:`FILTER_BIN`), stated in
    rocking frequencies at the binned samples per cycle.
    """
    if model.sensor.units != "sigma_y":
        raise ValueError("a calibration takes its sensor noise in units of sigma_Y")
    sensor = model.sensor
    if sensor.std > 0.0:
        sensor = SensorNoise(log_bin(sensor.std, NOISE_BIN), "sigma_y")
    load = model.load
    if load.kind == "lowpass":
        rate = log_bin(-math.log(load.pole(points_per_cycle)), POLE_BIN)
        load = Load("lowpass", float(f"{rate * ppc_key(points_per_cycle, ppc_bin) / (2.0 * math.pi):.6g}"))
    found = model.filter
    if found is not None:
        rate = log_bin(found.cycles_per_sample(points_per_cycle), FILTER_BIN)
        found = dataclasses.replace(found, corner=float(f"{rate * ppc_key(points_per_cycle, ppc_bin):.6g}"))
    return dataclasses.replace(model, load=load, sensor=sensor, filter=found)


def sets_per_e(capped: bool = False) -> int:
    """Sets per grid point of a calibration: :data:`SETS_PER_E`, or :data:`SETS_PER_E_CAPPED`
    for a calibration on shortened records (``capped``, :func:`simulated_lengths`).

    Examples
    --------
    >>> sets_per_e() > sets_per_e(capped=True)
    True
    """
    return SETS_PER_E_CAPPED if capped else SETS_PER_E


def calibration_settings(
    lengths, points_per_cycle: float, settings: dict | None = None, model: RecordModel = PAPER, theta_cr_ratio: float | None = None,
    repaired: dict | None = None, length_grid: bool = False,
) -> dict:
    """Everything a calibration depends on, as a JSON-able dict (hashed for the cache name).

    ``model``: the record model of the records (:mod:`rockdec.physics.record_model`): its load (a
    corner in rocking frequencies at ``points_per_cycle``) and sensor noise (in units of
    ``sigma_Y``: the calibration is scale-free); the calibration simulates it binned
    (:func:`binned_model`). Under the simplified model (eq. 4) nothing else sets the
    statistics; Housner's (eq. 2) adds ``nu^2 theta = g theta / theta_cr``, so the records'
    ``theta_cr_ratio = sigma_Y / theta_cr`` (binned by :data:`RATIO_BIN`) enters the key.
    ``repaired``: the repair of the records (:func:`rockdec.record.repair.settings`), which
    every simulated set then gets too (:func:`_repaired`); it enters the key only when it
    repairs something, so an unrepaired record keeps its calibration. ``length_grid``:
    simulate records of :func:`length_bin`'s length (the key's ``length_grid`` entry says so;
    :func:`simulated_lengths`), so that records of nearby lengths share the calibration.

    Examples
    --------
    >>> a, b = (calibration_settings([n], 75.0, length_grid=True) for n in (12_000, 30_000))
    >>> a["lengths"] == b["lengths"] == [10_000], settings_hash(a) == settings_hash(b)
    (True, True)
    """
    if model.sensor.units != "sigma_y":
        raise ValueError("a calibration takes its sensor noise in units of sigma_Y")
    housner = model.rocking == "housner"
    if housner != (theta_cr_ratio is not None):
        raise ValueError("a calibration of Housner's model (eq. 2) needs sigma_Y / theta_cr, which the simplified model (eq. 4) does not take")
    total = sum(int(n) for n in lengths)
    capped = total > LENGTH_CAP
    simulated = simulated_lengths(lengths, length_grid)
    gridded = length_grid and _on_grid(total)
    ppc_bin = PPC_BIN_LONG if capped else PPC_BIN
    out = {
        "lengths": simulated,
        "points_per_cycle": ppc_key(points_per_cycle, ppc_bin),
        "record_model": binned_model(model, points_per_cycle, ppc_bin).key(),
        "analysis": {k: (list(v) if isinstance(v, tuple) else v) for k, v in {**measured.DEFAULT_SETTINGS, **(settings or {})}.items()},
        "e_grid": list(E_GRID_LONG if capped else E_GRID),
        "sets_per_e": sets_per_e(capped),
        "rockdec_version": __version__,
        "pipeline": pipeline_fingerprint(),
    }
    if capped:
        out["length_cap"] = {"samples": LENGTH_CAP, "spread": "scaled by sqrt(simulated samples / record samples)"}
    if gridded:
        out["length_grid"] = {
            "per_decade": LENGTHS_PER_DECADE, "samples": sum(simulated), "spread": "scaled by sqrt(simulated samples / record samples)",
        }
    if housner:
        out["sigma_y_over_theta_cr"] = log_bin(theta_cr_ratio, RATIO_BIN)
    if repaired and any(repaired.get(k) is not None for k in ("spikes", "highpass")):
        out["repair"] = dict(repaired)
    return out


def _repaired(records: list, repaired: dict | None, points_per_cycle: float) -> tuple[list, tuple | None]:
    """A simulated set as the measured records were repaired (:func:`rockdec.record.repair.apply`,
    the high-pass placed at the calibration's ``points_per_cycle``), and the samples the
    repair replaced per record (``None`` without a repair)."""
    if not repaired:
        return records, None
    records, done = repair.apply(records, repaired, points_per_cycle)
    return records, done.spikes


def length_bin(samples: int) -> int:
    """The grid length (:data:`LENGTHS_PER_DECADE` a decade, 3 significant digits) at or
    below ``samples``; refused below :data:`LENGTH_GRID_MIN` or above :data:`LENGTH_CAP`.

    Examples
    --------
    >>> [length_bin(n) for n in (1_000, 3_159, 3_160, 99_999, 200_000)]
    [1000, 1000, 3160, 31600, 100000]
    """
    if not LENGTH_GRID_MIN <= samples <= LENGTH_CAP:
        raise ValueError(f"{samples} samples lie outside the length grid ({LENGTH_GRID_MIN} to {LENGTH_CAP}); calibrate them at their own length")
    k = math.floor(math.log10(samples) * LENGTHS_PER_DECADE) + 1
    while (n := int(float(f"{10.0 ** (k / LENGTHS_PER_DECADE):.3g}"))) > samples:
        k -= 1
    return n


def _on_grid(total: int) -> bool:
    """Whether records of ``total`` samples in all fall on the length grid (:func:`length_bin`)."""
    return LENGTH_GRID_MIN <= total <= LENGTH_CAP


def simulated_lengths(lengths, length_grid: bool = False) -> list[int]:
    """The lengths of the records a calibration simulates for records of ``lengths``: the
    same when they hold at most :data:`LENGTH_CAP` samples in all, else each shrunk in
    proportion to :data:`LENGTH_CAP` in all (at least one sample each). With
    ``length_grid``, records of :data:`LENGTH_GRID_MIN` to :data:`LENGTH_CAP` samples in all
    are shrunk in proportion to :func:`length_bin` of their total.

    Why that holds. The bias of every estimator depends on ``e`` and the sampling (samples
    per cycle, eq. 5), and its spread falls as ``1/sqrt(length)`` (a record's triggers are
    independent beyond a few cycles); so the belt of the shorter records, its spread scaled
    by :func:`spread_scale`, is the belt of the records. Measured, not assumed:
    ``benchmarks/long_coverage.py`` (docs/explanation/estimate.md, "Long records").
    """
    lengths = [int(n) for n in lengths]
    total = sum(lengths)
    if length_grid and _on_grid(total):
        target = length_bin(total)
    elif total <= LENGTH_CAP:
        return lengths
    else:
        target = LENGTH_CAP
    return [max(1, round(n * target / total)) for n in lengths]


def spread_scale(cal_settings: dict, samples: int) -> float:
    """Factor on the spread of the belt of the calibration ``cal_settings`` for records of
    ``samples`` in all: ``sqrt(simulated / samples)`` for a calibration on shortened records
    (:func:`simulated_lengths`: beyond the cap or on the length grid), else 1."""
    if "length_cap" not in cal_settings and "length_grid" not in cal_settings:
        return 1.0
    return math.sqrt(sum(cal_settings["lengths"]) / samples)


@functools.lru_cache(maxsize=1)
def pipeline_fingerprint() -> str:
    """SHA-256 (16 hex digits) of the source of every module this one reaches by import
    (:func:`rockdec.sources.package_sources`, the list the workflow's rules declare too): a
    change to the simulator, the models, the signatures, the estimators, the analysis or this
    module makes every stored calibration stale, whatever the version number says.

    Read once per process: every calibration a process builds or reads is named by the
    source it runs, not by files edited while it runs (a study of hours keeps its names)."""
    digest = hashlib.sha256()
    for path in package_sources(__name__):
        digest.update(Path(path).read_bytes())
    return digest.hexdigest()[:16]


def settings_hash(cal_settings: dict) -> str:
    """SHA-256 (first 16 hex digits) of the canonical JSON of the settings."""
    return hashlib.sha256(json.dumps(cal_settings, sort_keys=True).encode()).hexdigest()[:16]


def seed_base(cal_settings: dict) -> int:
    """First seed of the calibration for ``cal_settings``: :data:`CALIBRATION_SEED_OFFSET`
    plus a multiple of :data:`SEED_STRIDE` taken from :func:`settings_hash` of the settings
    without the code's fingerprint and version.

    Calibrations of different records (lengths, samples per cycle, record model) draw
    independent record sets, so that the sampling error of one calibration's spread (some
    tens of sets per ``e``) is not repeated by every calibration of a study or of a user's
    records; one record's calibration draws the same sets whatever the code's version.
    """
    description = {k: v for k, v in cal_settings.items() if k not in ("pipeline", "rockdec_version")}
    h = int(settings_hash(description), 16) % SEED_BASES
    return CALIBRATION_SEED_OFFSET + h * SEED_STRIDE


def _simulate_set(
    seed0: int, lengths, dt: float, e: float, burn_in: int, model: RecordModel, pole: float = 0.0, theta_cr: float | None = None,
    spectrum=None, points_per_cycle: float | None = None,
) -> list[np.ndarray]:
    """One set of records (one per length), seeds ``seed0, seed0 + 1, ...``; ``g = sigma_p = 1``,
    the rocking model of ``model`` (``theta_cr`` for Housner's, eq. 2, with ``nu^2 = 1/theta_cr``;
    :func:`rockdec.physics.simulate.simulate_model`), the load's filter ``pole`` or its ``spectrum``
    (:meth:`rockdec.physics.record_model.Load.draw_options`), the sensor filter of ``model``
    placed at ``points_per_cycle`` (:meth:`rockdec.physics.record_model.SensorFilter.apply`: the
    block's angle is filtered), then the sensor noise of ``model`` relative to each record's rms."""
    from rockdec.physics.loading import add_sensor_noise  # the simulators load only when a calibration is built
    from rockdec.physics.simulate import simulate_model

    out = []
    for k, n in enumerate(lengths):
        theta = simulate_model(
            model.rocking, [seed0 + k], n, dt=dt, g=1.0, e=e, sigma_p=1.0, theta_cr=theta_cr, burn_in=burn_in, pole=pole, spectrum=spectrum,
        )[0]
        if model.filter is not None:
            theta = model.filter.apply(theta, points_per_cycle)
        if model.sensor.std > 0.0:
            add_sensor_noise(theta, [seed0 + k], model.sensor.std_rad(float(np.sqrt(np.nanmean(theta**2)))))
        out.append(theta[0])
    return out


def step_for(
    e: float, points_per_cycle: float, lengths, settings: dict, seed0: int, model: RecordModel = PAPER, theta_cr_ratio: float | None = None,
    pilot_samples: int = PILOT_SAMPLES, repaired: dict | None = None,
) -> tuple[float, int, float | None]:
    """Step ``dt`` (for ``g = sigma_p = 1``) at which :func:`rockdec.rdd.measured.analyse` reads
    ``points_per_cycle`` off simulated records at ``e``, the burn-in, and (Housner's model,
    eq. 2) the critical angle at which the records' ``sigma_Y / theta_cr`` is ``theta_cr_ratio``.

    Fixed point on the scale law: ``points_per_cycle`` goes as ``1/dt^2`` (``sigma_Y`` as
    ``S^2/g^3`` with ``S = sigma_p^2/dt``, and eq. 5), so ``dt <- dt sqrt(N_read / N)``, on
    :data:`PILOT_SETS` sets of at most ``pilot_samples`` (:data:`PILOT_SAMPLES`) samples a
    record (a calibration of records beyond :data:`LENGTH_CAP`: as long as its records, for
    their interval is narrow enough to see the bias move with a few per cent of samples per
    cycle). Under a
    coloured load the samples per cycle read off a record grow with its length (rare large
    excursions) and fall steeply with ``dt``, so the pilot records are as long as the
    records (up to :data:`PILOT_SAMPLES_COLOURED`, as many sets as make
    :data:`PILOT_SETS` x :data:`PILOT_SAMPLES` samples, at least half :data:`PILOT_SETS`)
    and the step is bracketed (:func:`rockdec.physics.simulate.secant_step`); the step returned is
    then the pilot's whose samples per cycle came nearest the target.
    :data:`rockdec.physics.simulate.STEP_ITERATIONS` iterations. Under Housner's model each pilot
    also sets the next ``theta_cr = sigma_Y / theta_cr_ratio`` from its median ``sigma_Y``
    (the first from eq. 5 at the target: ``sigma_Y = (N dt / 4)^2 / 2``), and the search
    runs at least :data:`HOUSNER_ITERATIONS` iterations. ``repaired``: the records' repair,
    applied to each pilot set before it is read (:func:`_repaired`).
    """
    from rockdec.physics.simulate import STEP_ITERATIONS, default_burn_in, secant_step

    burn_in = default_burn_in(e, points_per_cycle)
    dt = step_for_density(SCALE_CONSTANT_GUESS, 1.0, 1.0, points_per_cycle)
    draw = model.load.draw_options(points_per_cycle)
    white = model.load.kind == "white"
    housner = model.rocking == "housner"
    theta_cr = (points_per_cycle * dt / 4.0) ** 2 / 2.0 / theta_cr_ratio if housner else None
    pilot = [min(int(n), pilot_samples if white else PILOT_SAMPLES_COLOURED) for n in lengths]
    sets = PILOT_SETS if white else max(PILOT_SETS // 2, PILOT_SETS * PILOT_SAMPLES // sum(pilot))
    iterations = max(STEP_ITERATIONS[model.load.kind], HOUSNER_ITERATIONS if housner else 0)
    history: list = []
    closest = (math.inf, dt, theta_cr)
    for i in range(iterations):
        read, rms = [], []
        for k in range(sets):
            try:
                records = _simulate_set(seed0 + k * len(pilot), pilot, dt, e, burn_in, model, theta_cr=theta_cr, points_per_cycle=points_per_cycle, **draw)
                records, _ = _repaired(records, repaired, points_per_cycle)
                read.append(measured.analyse(records, dt, settings).points_per_cycle)
                rms.append(float(np.sqrt(np.nanmean(np.concatenate(records) ** 2))))
            except ValueError:
                continue
        if not read:
            raise ValueError(f"no pilot record at e = {e} could be analysed; the records are too short for this sampling")
        miss = abs(math.log(float(np.median(read)) / points_per_cycle))
        if miss < closest[0]:
            closest = (miss, dt, theta_cr)
        if housner:
            theta_cr = float(np.median(rms)) / theta_cr_ratio
        if white:
            dt *= math.sqrt(float(np.median(read)) / points_per_cycle)
        else:
            dt = secant_step(history, dt, float(np.median(read)), points_per_cycle)
    return (dt, burn_in, theta_cr) if white else (closest[1], burn_in, closest[2])


def _sets(e: float, cal_settings: dict, seed0: int, dt: float, burn_in: int, theta_cr: float | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every set of one grid point at step ``dt``, repaired as the records were
    (:func:`_repaired`): raw zero-window values ``(set, name)``, the
    checks' statistics ``(set, check)`` and the samples per cycle read off each set (NaN for
    a set that cannot be analysed)."""
    lengths, ppc, settings = cal_settings["lengths"], cal_settings["points_per_cycle"], cal_settings["analysis"]
    model = RecordModel.from_key(cal_settings["record_model"])
    n_sets = cal_settings["sets_per_e"]
    out = np.full((n_sets, len(NAMES)), np.nan)
    diag = np.full((n_sets, len(diagnostics.CHECKS)), np.nan)
    read = np.full(n_sets, np.nan)
    for k in range(n_sets):
        try:
            records = _simulate_set(seed0 + k * len(lengths), lengths, dt, e, burn_in, model, theta_cr=theta_cr, points_per_cycle=ppc, **model.load.draw_options(ppc))
            records, replaced = _repaired(records, cal_settings.get("repair"), ppc)
            analysis = measured.analyse(records, dt, settings)
        except ValueError:
            continue
        out[k] = [analysis.raw[name] for name in NAMES]
        diag[k] = diagnostics.statistics(records, analysis, replaced)
        read[k] = analysis.points_per_cycle
    return out, diag, read


def _grid_point(j: int, e: float, cal_settings: dict, seed_base: int) -> tuple[np.ndarray, np.ndarray]:
    """Raw zero-window values ``(set, name)`` of one grid point and the checks' statistics
    ``(set, check)`` (:func:`rockdec.record.diagnostics.statistics`); NaN for sets (or the whole
    point) that cannot be analysed, e.g. records too short for the lag range at this ``e``.

    The step is :func:`step_for`'s. Under a coloured load the pilot's median samples per
    cycle misses the median of the point's own sets by several per cent (the pilot's records
    are few, and such a load's sampling varies widely from record to record), so the sets of one calibration would sit at
    different samplings from ``e`` to ``e``; the sets are then simulated again with the same
    seeds at a corrected step until their own median is within :data:`SET_PPC_TOLERANCE` of
    the calibration's samples per cycle (at most :data:`SET_STEP_TRIES` times; the try that
    came nearest is kept). The correction is a secant step in ``ln dt``
    (:func:`rockdec.physics.simulate.secant_step`) on the sets' medians, which vary smoothly
    with the step since the seeds are the same.
    """
    from rockdec.physics.simulate import secant_step

    lengths, ppc, settings = cal_settings["lengths"], cal_settings["points_per_cycle"], cal_settings["analysis"]
    model = RecordModel.from_key(cal_settings["record_model"])
    ratio = cal_settings.get("sigma_y_over_theta_cr")
    seed0 = seed_base + j * 10**7
    try:
        dt, burn_in, theta_cr = step_for(e, ppc, lengths, settings, seed0 + 9 * 10**6, model, ratio, LENGTH_CAP if "length_cap" in cal_settings else PILOT_SAMPLES,
                                         cal_settings.get("repair"))
    except ValueError:  # no record at this e can be analysed: the belt leaves this e out
        n_sets = cal_settings["sets_per_e"]
        return np.full((n_sets, len(NAMES)), np.nan), np.full((n_sets, len(diagnostics.CHECKS)), np.nan)
    out, diag, read = _sets(e, cal_settings, seed0, dt, burn_in, theta_cr)
    if model.load.kind == "white" or not np.isfinite(read).any():
        return out, diag
    history: list = []
    best = (abs(math.log(float(np.nanmedian(read)) / ppc)), out, diag)
    for _ in range(SET_STEP_TRIES):
        if best[0] <= SET_PPC_TOLERANCE:
            break
        dt = secant_step(history, dt, float(np.nanmedian(read)), ppc)
        out, diag, read = _sets(e, cal_settings, seed0, dt, burn_in, theta_cr)
        if not np.isfinite(read).any():
            break
        miss = abs(math.log(float(np.nanmedian(read)) / ppc))
        if miss < best[0]:
            best = (miss, out, diag)
    return best[1], best[2]


#: Fewest seconds between two messages of the calibration's progress (:class:`_Countdown`).
PROGRESS_EVERY_S = 10.0


class _Countdown:
    """Logs, as the grid points of a calibration finish, how many are done and the time
    left (the mean time per finished point so far times the points left), at most every
    :data:`PROGRESS_EVERY_S` seconds: a message a log file keeps, where a progress bar is
    drawn only on a terminal (:func:`rockdec.console.progress`). Counts the Dask ``tasks``
    (one per grid point) as they finish on the local schedulers (threads, the default engine)."""

    def __init__(self, tasks):
        from dask.callbacks import Callback

        keys = {task.key for task in tasks}
        self.points, self.done, self.start, self.last = len(keys), 0, time.perf_counter(), time.perf_counter()
        countdown = self

        class _Finished(Callback):
            def _posttask(self, key, result, dsk, state, worker_id):
                if key in keys:
                    countdown.finished()

        self.callback = _Finished()

    def finished(self) -> None:
        self.done += 1
        now = time.perf_counter()
        if self.done == self.points or now - self.last < PROGRESS_EVERY_S:
            return
        self.last = now
        left = (now - self.start) / self.done * (self.points - self.done)
        log.info(f"calibrating: {self.done} of {self.points} values of e done, about {left:.0f} s left")

    def __enter__(self):
        self.callback.__enter__()
        return self

    def __exit__(self, *exc):
        self.callback.__exit__(*exc)
        log.info(f"calibrating: {self.points} values of e done in {time.perf_counter() - self.start:.0f} s")


def grid_tasks(cal_settings: dict, base: int) -> list:
    """One Dask task per ``e`` of the settings' grid, :func:`_grid_point` from seed ``base``."""
    import dask

    return [dask.delayed(_grid_point)(j, e, cal_settings, base) for j, e in enumerate(cal_settings["e_grid"])]


def build(cal_settings: dict) -> xr.Dataset:
    """Simulate and analyse the calibration records; ``raw(e_true, set, name)`` and
    ``diagnostic(e_true, set, check)``.

    Grid points run as Dask tasks on the engine of :mod:`rockdec.engine` (threads by
    default); the simulation and signature kernels release the GIL.
    """
    import xarray as xr

    log.info(
        f"calibrating: simulating {cal_settings['sets_per_e']} record sets of {sum(cal_settings['lengths'])} samples at each of "
        f"{len(cal_settings['e_grid'])} values of e like the measured records (once; stored for every record with the same settings)"
    )
    tasks = grid_tasks(cal_settings, seed_base(cal_settings))
    with _Countdown(tasks):
        points = engine.compute(*tasks)
    values = np.stack([raw for raw, _ in points])
    ds = xr.Dataset(
        {
            "raw": (("e_true", "set", "name"), values, {"units": "1", "long_name": "zero-window estimate on a simulated record set (g in units of the true g)"}),
            "diagnostic": (("e_true", "set", "check"), np.stack([diag for _, diag in points]), {"units": "1", "long_name": "statistic of a check of rockdec.record.diagnostics on a simulated record set"}),
        },
        coords={
            "e_true": ("e_true", np.asarray(cal_settings["e_grid"]), {"units": "1", "long_name": "true coefficient of restitution"}),
            "set": ("set", np.arange(values.shape[1]), {"long_name": "simulated record set"}),
            "name": ("name", list(NAMES), {"long_name": "estimator of e, or g"}),
            "check": ("check", list(diagnostics.CHECKS), {"long_name": "check of the records (rockdec.record.diagnostics)"}),
        },
    )
    ds.attrs.update(io.provenance("calibration", cal_settings))
    return ds


def content_checksum(ds: xr.Dataset) -> str:
    """SHA-256 of the calibration's values, the checks' statistics and the true ``e`` grid
    (stored as an attribute)."""
    digest = hashlib.sha256()
    for name in ("raw", "diagnostic"):
        if name in ds:
            digest.update(np.ascontiguousarray(ds[name].values, dtype=np.float64).tobytes())
    digest.update(np.ascontiguousarray(ds["e_true"].values, dtype=np.float64).tobytes())
    return digest.hexdigest()


def _read_checked(path: Path, expected_hash: str) -> tuple[ncread.Stored | None, str | None]:
    """The calibration stored at ``path`` and ``None``, or ``None`` and why it cannot be trusted
    (read by :func:`rockdec.calibrate.ncread.read`: no xarray to import for a cached calibration)."""
    try:
        with locks.HDF5:  # the HDF5 library is not safe from two threads at once (a study's Dask threads)
            ds = ncread.read(path)
    except (OSError, ValueError, RuntimeError, AttributeError) as exc:  # netCDF4 raises AttributeError on a bad attribute
        return None, f"it is not readable ({type(exc).__name__})"
    try:
        stored_hash = settings_hash(json.loads(ds.attrs["settings"]))
        checksum = content_checksum(ds)
    except (KeyError, TypeError, ValueError):
        return None, "it lacks its settings or values"
    if stored_hash != expected_hash:
        return None, "its settings do not hash to its name"
    if ds.attrs.get("content_sha256") != checksum:
        return None, "its values do not match their checksum"
    return ds, None


@contextlib.contextmanager
def _heartbeat(lock: Path):
    """Touch ``lock`` every :data:`HEARTBEAT_S` seconds while the block runs."""
    stop = threading.Event()

    def beat():
        while not stop.wait(HEARTBEAT_S):
            with contextlib.suppress(OSError):
                os.utime(lock)

    thread = threading.Thread(target=beat, daemon=True)
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join()


def _pid_alive(pid: int) -> bool:
    """Whether process ``pid`` runs on this host (``os.kill(pid, 0)``: a process of another
    user counts as running)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError, ValueError):
        return pid > 0
    return True


def _ended_here(holder: str) -> bool:
    """Whether the lock text ``holder`` (``host H pid P started ...``) names a process of this
    host that has ended: its lock is stale at once, whatever its time stamp."""
    words = holder.split()
    try:
        host, pid = words[words.index("host") + 1], int(words[words.index("pid") + 1])
    except (ValueError, IndexError):
        return False
    return host == socket.gethostname() and not _pid_alive(pid)


def _cache_error(folder: Path, exc: OSError) -> InputError:
    """One sentence for a cache folder the calibration cannot be written to, naming ``cache``."""
    why = {
        errno.EROFS: "lies on a read-only file system",
        errno.EACCES: "is not writable by this user",
        errno.EPERM: "is not writable by this user",
        errno.ENOTDIR: "lies under a file, not a folder",
        errno.EEXIST: "lies under a file, not a folder",
        errno.ENOSPC: "lies on a full disk",
        errno.ENAMETOOLONG: "has a name too long for the file system",
    }.get(exc.errno, f"cannot be written ({exc.strerror})")
    return InputError(f"`cache` '{folder}' {why}; give a writable folder for the stored calibrations.")


def _take_lock(lock: Path, notes: list, watch: dict | None = None) -> bool:
    """Create ``lock`` exclusively; ``False`` while a live run holds it.

    A lock is stale, removed (with a note) and then taken on the next call, when its mtime is
    older than :data:`STALE_S` seconds, when it names a process of this host that has ended
    (a run killed before it could remove it), or, with ``watch`` (a dict kept by the caller
    between calls), when its mtime has not changed for :data:`STALE_S` seconds of waiting: a
    live holder touches it every :data:`HEARTBEAT_S` seconds, so a lock stamped in the future
    (a clock set wrong) does not hold a run forever. An empty folder in its place (no run
    makes one) is removed; a folder with content is refused (:class:`InputError`).
    """
    try:
        fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
    except FileExistsError:
        try:
            stamp = lock.stat().st_mtime
        except FileNotFoundError:  # released meanwhile
            return False
        if lock.is_dir():
            try:
                lock.rmdir()
            except OSError:
                raise InputError(
                    f"`cache` '{lock.parent}' holds a folder {lock.name} where a calibration's lock file goes; "
                    "remove it, or give another folder."
                ) from None
            notes.append(f"removed the empty folder {lock.name} that stood where the calibration's lock goes")
            return False
        now = time.time()
        holder = lock.read_text(errors="replace").strip() if lock.is_file() else ""
        age = now - stamp
        if watch is not None and watch.get("stamp") != stamp:
            watch.update(stamp=stamp, since=now)
        unchanged = now - watch["since"] if watch is not None else 0.0
        if _ended_here(holder):
            why = "whose process has ended"
        elif age >= STALE_S:
            why = f"that stopped {age:.0f} s ago"
        elif unchanged >= STALE_S:
            why = f"untouched for {unchanged:.0f} s though stamped {-age:.0f} s in the future"
        else:
            return False
        notes.append(f"took over the calibration lock {lock.name} of a run {why} ({holder})")
        lock.unlink(missing_ok=True)
        return False
    except OSError as exc:
        raise _cache_error(lock.parent, exc) from None
    with os.fdopen(fd, "w") as f:
        f.write(f"host {socket.gethostname()} pid {os.getpid()} started {time.strftime('%Y-%m-%dT%H:%M:%SZ', time.gmtime())}\n")
    return True


@contextlib.contextmanager
def _removed_on_sigterm(lock: Path):
    """While the block runs in the main thread, a SIGTERM first removes ``lock`` (and then
    does what it did before: the previous handler, or ends the process as by default), so a
    killed build leaves no lock for the next run to wait on. Ctrl-C (KeyboardInterrupt)
    unwinds through the caller's ``finally``, which removes it."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.getsignal(signal.SIGTERM)

    def terminated(signum, frame):
        lock.unlink(missing_ok=True)
        if callable(previous):
            previous(signum, frame)
        elif previous != signal.SIG_IGN:
            signal.signal(signal.SIGTERM, signal.SIG_DFL)
            os.kill(os.getpid(), signal.SIGTERM)

    signal.signal(signal.SIGTERM, terminated)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def cache_folder(cache_dir: str | Path) -> Path:
    """``cache_dir`` as a folder of stored calibrations, refused in one sentence naming
    ``cache`` when it is a file."""
    folder = Path(cache_dir)
    if folder.exists() and not folder.is_dir():
        raise InputError(f"`cache` '{folder}' is a file, not a folder; give a folder for the stored calibrations.")
    return folder


def load_or_build(cal_settings: dict, cache_dir: str | Path, notes: list | None = None) -> tuple[ncread.Stored, bool]:
    """The calibration for ``cal_settings`` from ``cache_dir``, built and stored when absent
    or damaged (module docstring; ``notes`` receives a sentence on each rebuild, wait or
    takeover).

    Returns ``(calibration, from_cache)``, the calibration as read back from its file
    (:func:`rockdec.calibrate.ncread.read`) whether it was stored or built.
    """
    notes = [] if notes is None else notes
    folder = cache_folder(cache_dir)
    expected = settings_hash(cal_settings)
    path = folder / f"calibration-{expected}.nc"
    lock = path.with_suffix(".building")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise _cache_error(folder, exc) from None
    waited, watch = False, {}
    while True:
        if path.is_file():
            ds, problem = _read_checked(path, expected)
            if ds is not None:
                return ds, True
            if not waited:
                notes.append(f"the stored calibration {path.name} was rebuilt: {problem}")
        if _take_lock(lock, notes, watch):
            break
        if not waited:
            print(f"waiting for another run that builds {path.name} (lock {lock})", file=sys.stderr)
            waited = True
        time.sleep(POLL_S)
    try:
        with _removed_on_sigterm(lock), _heartbeat(lock):
            if path.is_file() and _read_checked(path, expected)[0] is not None:  # stored while we took the lock
                return _read_checked(path, expected)[0], True
            ds = build(cal_settings)
            ds.attrs["content_sha256"] = content_checksum(ds)
            with locks.HDF5:
                io.write_netcdf(ds, path, overwrite=True)
    finally:
        lock.unlink(missing_ok=True)
    with locks.HDF5:
        return ncread.read(path), False

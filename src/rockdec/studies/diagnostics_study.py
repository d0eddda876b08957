"""Are the warnings of ``rockdec estimate`` right? False alarms and detections of each check.

Records of known ``e`` are simulated apart from any calibration (``g = sigma_p = 1``, the
step calibrated to :data:`POINTS_PER_CYCLE` samples per cycle at ``sigma_Y``, eq. 5; seeds
from :data:`STUDY_SEED_OFFSET`), with or without one defect of a given size
(:data:`DEFECTS`), and each goes through what ``rockdec estimate`` does with a record: the
analysis (:func:`rockdec.rdd.measured.analyse`), the calibration for its own length and
sampling (:mod:`rockdec.calibrate.calibration`, shared by records in one samples-per-cycle bin), the
corrected ``e`` and interval of the default estimator (no ``e`` when the raw value lies
beyond the calibration, :func:`rockdec.calibrate.inference.beyond`), and every check of
:mod:`rockdec.record.diagnostics` against the calibration's thresholds.

The defects, each on the same seeds as the clean records (so the shift of ``e`` is read
record by record):

* ``nonstationary``: the impulses' standard deviation ramps linearly from ``1 - m`` to
  ``1 + m`` along the record (``m`` the size);
* ``drift``: a linear trend from ``-D/2`` to ``+D/2`` added (``D`` in ``sigma_Y``);
* ``spikes``: one sample in :data:`SPIKE_EVERY` replaced by ``+-k sigma_Y`` (``k`` the size);
* ``asymmetry``: impulses with mean ``b g dt`` per step, a constant push that leaves the
  block ``g (1 - b)`` on one side and ``g (1 + b)`` on the other (a leaning block);
* ``few_triggers``: a share of the record lost in gaps (NaN) of :data:`GAP` samples;
* ``coarse_sampling``: the records sampled at fewer samples per cycle (their own
  calibration; no pairing, the shift is read against the clean records' mean).

A defect *matters* at a size when it moves the corrected ``e`` by more than half the
median 95 % interval (median over records of the paired shift). :func:`summary` gives per
check and ``e`` the false-alarm rate on the clean records and, per size, the shift, half
the interval, and the detection rate (the share of defective records on which the
check fires).
"""

from __future__ import annotations

import sys
import time
import warnings

import dask
import numpy as np
import pandas as pd

from rockdec.calibrate import belt, calibration, inference
from rockdec.record import diagnostics
from rockdec.pipeline import engine
from rockdec.rdd import measured
from rockdec.physics.loading import draw_impulses, series_rng
from rockdec.rdd.registry import DEFAULT_ESTIMATOR
from rockdec.physics.simulate import calibrate_dt, integrate

#: Seeds of the study's records start here (apart from scenes, pilots, calibrations and
#: the other studies).
STUDY_SEED_OFFSET = 5 * 2**60

#: Samples per cycle at ``sigma_Y`` of the clean records (the paper's sampling).
POINTS_PER_CYCLE = 75.0

#: True ``e`` of the study.
E_VALUES = (0.6, 0.8, 0.95, 0.98)

#: Records per cell and their length (``coarse_sampling`` uses :data:`COARSE_POINTS`).
RECORDS, N_POINTS, COARSE_POINTS = 40, 100_000, 50_000

#: One sample in this many is a spike; gaps are this long.
SPIKE_EVERY, GAP = 1000, 2000

#: Sizes of each defect (units in the module docstring).
DEFECTS = {
    "nonstationary": (0.05, 0.15, 0.4),
    "drift": (0.3, 1.0, 3.0),
    "spikes": (1.0, 5.0, 20.0),
    "asymmetry": (0.03, 0.1, 0.3),
    "few_triggers": (0.05, 0.1, 0.3),
    "coarse_sampling": (30.0, 15.0),
}


def simulate(e: float, seed: int, n: int, dt: float, burn_in: int, defect: str | None = None, size: float = 0.0) -> np.ndarray:
    """One record of ``n`` samples at ``e`` (``g = sigma_p = 1``) from ``seed``, with the
    simulated ``defect`` (``nonstationary`` or ``asymmetry``) of ``size``; any other defect
    is added afterwards (:func:`add_defect`). Clean, it equals
    :func:`rockdec.physics.simulate.simulate_block` of the same seed."""
    impulses = np.empty(burn_in + n - 1)
    draw_impulses(series_rng(seed), impulses, 1.0)
    if defect == "nonstationary":
        impulses[burn_in:] *= 1.0 + size * np.linspace(-1.0, 1.0, n - 1)
        impulses[:burn_in] *= 1.0 - size
    elif defect == "asymmetry":
        impulses += size * dt  # b g dt with g = 1
    theta, omega = np.empty(n), np.empty(n)
    integrate(impulses, dt, 1.0, e, 0.0, 0.0, burn_in, theta, omega)
    return theta


def add_defect(theta: np.ndarray, defect: str | None, size: float, seed: int) -> np.ndarray:
    """``theta`` with an added ``drift``, ``spikes`` or ``few_triggers`` (gaps) of ``size``
    (module docstring); other defects return it unchanged."""
    y = theta.copy()
    sigma = float(np.std(theta))
    if defect == "drift":
        y += size * sigma * np.linspace(-0.5, 0.5, y.size)
    elif defect == "spikes":
        rng = np.random.default_rng(seed)
        where = rng.choice(y.size, y.size // SPIKE_EVERY, replace=False)
        y[where] = rng.choice([-1.0, 1.0], where.size) * size * sigma
    elif defect == "few_triggers":
        gaps = int(round(size * y.size / GAP))
        starts = np.linspace(0, y.size - GAP, gaps + 2)[1:-1].astype(int)
        for s in starts:
            y[s : s + GAP] = np.nan
    return y


def _cell(e: float, defect: str | None, size: float, seeds, n: int, dt: float, burn_in: int) -> list:
    """``(analysis, statistics, seconds to simulate and analyse, seconds for the
    statistics)`` per seed of one cell; ``analysis`` and ``statistics`` ``None`` when the
    record cannot be analysed."""
    out = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for seed in seeds:
            tick = time.perf_counter()
            y = add_defect(simulate(e, int(seed), n, dt, burn_in, defect, size), defect, size, int(seed))
            try:
                analysis = measured.analyse([y], dt)
            except ValueError:
                out.append((None, None, 0.0, 0.0))
                continue
            tock = time.perf_counter()
            values = diagnostics.statistics([y], analysis)
            out.append((analysis, values, tock - tick, time.perf_counter() - tock))
    return out


def run(e_values=E_VALUES, defects=DEFECTS, n_records: int = RECORDS, n_points: int = N_POINTS, cache_dir=None) -> pd.DataFrame:
    """One row per record and cell (``e``, ``defect``, ``size``; ``defect`` ``"clean"`` for the
    clean records): the corrected ``e`` and interval of the default estimator, and per
    check its statistic, threshold and whether it fired. Calibrations are stored in
    ``cache_dir``. The result's attributes ``statistics_s`` and ``simulate_analyse_s`` hold
    the seconds spent on the checks' statistics and on simulating and analysing the records
    (their ratio is the checks' share of a calibration's work), ``calibrations`` how many
    calibrations the records used."""
    cells = []
    for i, e in enumerate(e_values):
        seeds = STUDY_SEED_OFFSET + i * 10**6 + np.arange(n_records)
        cells.append((e, "clean", 0.0, seeds, n_points, POINTS_PER_CYCLE))
        for defect, sizes in defects.items():
            for size in sizes:
                if defect == "coarse_sampling":
                    cells.append((e, defect, size, seeds, COARSE_POINTS, size))
                else:
                    cells.append((e, defect, size, seeds, n_points, POINTS_PER_CYCLE))
    steps = {}
    for e, _, _, _, _, ppc in cells:
        if (e, ppc) not in steps:
            steps[e, ppc] = calibrate_dt(e=e, g=1.0, sigma_p=1.0, points_per_cycle=ppc)
    tasks = [
        dask.delayed(_cell)(e, None if d in ("clean", "coarse_sampling") else d, size, seeds, n, steps[e, ppc]["dt"], steps[e, ppc]["burn_in"])
        for e, d, size, seeds, n, ppc in cells
    ]
    results = engine.compute(*tasks)
    print(f"diagnostics study: {len(cells)} cells of {n_records} records simulated and analysed; correcting", file=sys.stderr, flush=True)
    level = measured.DEFAULT_SETTINGS["level"]
    by_hash: dict = {}
    rows = []
    cost = np.zeros(2)
    for (e, defect, size, seeds, n, _), records in zip(cells, results):
        for seed, (analysis, values, work_s, statistics_s) in zip(seeds, records):
            row = {"e_true": e, "defect": defect, "size": size, "seed": int(seed), "n_points": n}
            rows.append(row)
            if analysis is None:
                continue
            cost += (work_s, statistics_s)
            key = calibration.calibration_settings([n], analysis.points_per_cycle)
            h = calibration.settings_hash(key)
            if h not in by_hash:
                cal = calibration.load_or_build(key, cache_dir)[0]
                by_hash[h] = (cal, belt.belts(cal))
            cal, belts = by_hash[h]
            c = belt.correct(belts[DEFAULT_ESTIMATOR], analysis.raw[DEFAULT_ESTIMATOR])
            placed = None if inference.beyond(belts[DEFAULT_ESTIMATOR], analysis.raw[DEFAULT_ESTIMATOR], c) else c.value
            row.update(e_hat=placed, low=c.low, high=c.high)
            for name, o in diagnostics.judge(values, diagnostics.thresholds(cal, placed, (c.low, c.high), level)).items():
                row[f"{name}_statistic"], row[f"{name}_threshold"], row[f"{name}_fired"] = o.statistic, o.threshold, o.fired
    table = pd.DataFrame(rows)
    table.attrs.update(simulate_analyse_s=float(cost[0]), statistics_s=float(cost[1]), calibrations=len(by_hash))
    return table


def summary(table: pd.DataFrame) -> pd.DataFrame:
    """Per check, ``e`` and size: records analysed; the median shift of the corrected ``e``
    from the same seeds' clean records (``coarse_sampling``: from their mean) over the
    records that keep an ``e``; the share of records that lose the ``e`` their clean record
    had (``lost_pct``); half the median 95 % interval of the clean records; whether the
    defect matters (the shift beyond half the interval, or half the records losing their
    ``e``); and the share of records on which the check fires (on the clean records, size
    0: the false-alarm rate)."""
    rows = []
    for e, at_e in table.groupby("e_true"):
        clean = at_e[at_e["defect"] == "clean"].set_index("seed")
        half = 0.5 * float(np.nanmedian(clean["high"] - clean["low"]))
        for check in diagnostics.CHECKS:
            fired = clean[f"{check}_fired"].dropna().astype(bool)
            rows.append({"check": check, "e_true": e, "size": 0.0, "records": int(fired.size), "e_shift": 0.0, "lost_pct": 0.0,
                         "half_interval": half, "matters": False, "fired_pct": 100.0 * float(fired.mean())})
            for size, cell in at_e[at_e["defect"] == check].groupby("size"):
                cell = cell.set_index("seed")
                base = clean["e_hat"].reindex(cell.index)
                if check == "coarse_sampling":
                    shift = float(np.nanmedian(cell["e_hat"]) - np.nanmean(clean["e_hat"]))
                else:
                    shift = float(np.nanmedian(cell["e_hat"] - base)) if (cell["e_hat"] - base).notna().any() else np.nan
                lost = float(np.mean(cell["e_hat"].isna() & base.notna()))
                fired = cell[f"{check}_fired"].dropna().astype(bool)
                rows.append({"check": check, "e_true": e, "size": size, "records": int(fired.size), "e_shift": shift,
                             "lost_pct": 100.0 * lost, "half_interval": half, "matters": bool(abs(shift) > half or lost >= 0.5),
                             "fired_pct": 100.0 * float(fired.mean()) if fired.size else np.nan})
    return pd.DataFrame(rows)

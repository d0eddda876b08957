"""Are the warnings of ``rockdec estimate`` right? False alarms and detections of each check.

Records of known ``e`` are simulated apart from any calibration (``g = sigma_p = 1``,
:data:`POINTS_PER_CYCLE` samples per cycle at ``sigma_Y``, eq. 5; seeds from
:data:`STUDY_SEED_OFFSET`; :func:`simulate`, :func:`record`), clean or with one defect of
:data:`DEFECTS` (:func:`add_defect`), at every noise level and load of
:mod:`rockdec.pipeline.layout` (``DIAGNOSTICS_NOISE``, ``DIAGNOSTICS_CORNERS``,
``DIAGNOSTICS_COLOURED_NOISE``, :data:`COLOURED_DEFECTS`), and go through ``rockdec
estimate`` itself (:func:`rockdec.estimation.estimate`, :func:`run`). The defects,
on the clean records' seeds so the shift of ``e`` is read record by record:
``nonstationary`` (the impulses' standard deviation ramped from ``1 - m`` to ``1 + m``),
``drift`` (a trend from ``-D/2`` to ``+D/2`` in ``sigma_Y``), ``spikes`` (one sample in
:data:`SPIKE_EVERY` set to ``+-k sigma_Y``), ``asymmetry`` (impulses of mean ``b g dt``: the
block feels ``g (1 -+ b)`` on its sides), ``few_triggers`` (gaps of :data:`GAP` samples),
``coarse_sampling``. A defect *matters* when it moves the corrected ``e`` by more than half
the median 95 % interval; :func:`summary` and :func:`digest` give per check and cell the
false-alarm rate on the clean records and, per size, the shift and the detection rate.

Explanation: docs/explanation/studies/diagnostics.md; the checks: docs/explanation/method/warnings.md.
"""

from __future__ import annotations

import sys
import time

import dask
import numpy as np
import pandas as pd

from rockdec.calibrate import calibration

from rockdec import estimation

from rockdec.report.estimate_report import document
from rockdec.record import diagnostics
from rockdec import engine
from rockdec.rdd import measured
from rockdec.physics.loading import add_sensor_noise, draw_impulses, series_rng
from rockdec.physics.simulate import calibrate_dt, integrate
from rockdec.pipeline.layout import DIAGNOSTICS_COLOURED_NOISE, DIAGNOSTICS_CORNERS, DIAGNOSTICS_E, DIAGNOSTICS_NOISE, diagnostics_noise
from rockdec.record.records import Record
from rockdec.validate import InputError

__all__ = [
    "DEFECTS", "POINTS_PER_CYCLE", "Record", "add_defect", "digest", "digest_markdown", "record", "run",
    "simulate", "summary",
]

#: Seeds of the study's records start here (apart from scenes, pilots, calibrations and
#: the other studies); the pilots that place a coloured load's records (:func:`_step`)
#: start ``PILOT_SEEDS`` further on, beyond every cell's records.
STUDY_SEED_OFFSET, PILOT_SEEDS = 5 * 2**60, 9 * 10**8

#: Samples per cycle at ``sigma_Y`` of the clean records (the paper's sampling).
POINTS_PER_CYCLE = 75.0

#: Defects studied under a coloured load too (the loads and noise levels of the records:
#: :data:`rockdec.pipeline.layout.DIAGNOSTICS_CORNERS`, ``DIAGNOSTICS_NOISE`` and
#: ``DIAGNOSTICS_COLOURED_NOISE``).
COLOURED_DEFECTS = ("asymmetry",)

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


def simulate(e: float, seed: int, n: int, dt: float, burn_in: int, defect: str | None = None, size: float = 0.0, pole: float = 0.0) -> np.ndarray:
    """One record of ``n`` samples at ``e`` (``g = sigma_p = 1``) from ``seed``, the load
    low-pass filtered with ``pole`` per sample (0: white), with the simulated ``defect``
    (``nonstationary`` or ``asymmetry``) of ``size``; any other defect is added afterwards
    (:func:`add_defect`). Clean, it equals :func:`rockdec.physics.simulate.simulate_block`
    of the same seed and pole."""
    impulses = np.empty(burn_in + n - 1)
    draw_impulses(series_rng(seed), impulses, 1.0, pole)
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


def record(e: float, seed: int, n: int, dt: float, burn_in: int, defect: str | None, size: float, noise: float, pole: float = 0.0) -> np.ndarray:
    """The study's record: :func:`simulate` (load pole ``pole``), :func:`add_defect`, then
    white sensor noise of ``noise`` times the clean record's rms
    (:func:`rockdec.physics.loading.add_sensor_noise`, as the calibration and the coverage
    study add it)."""
    theta = simulate(e, seed, n, dt, burn_in, defect, size, pole)
    y = add_defect(theta, defect, size, seed)
    return add_sensor_noise(y[None], [seed], noise * float(np.sqrt(np.mean(theta**2))))[0]


def _cell(e: float, defect: str | None, size: float, noise: float, seeds, n: int, dt: float, burn_in: int, pole: float) -> list:
    """``(calibration settings, seconds to simulate and analyse, seconds for the
    statistics)`` per seed of one cell: the settings ``rockdec estimate`` calibrates the record
    with (its measured record model, :func:`rockdec.estimation.record_model`); ``None``
    when the record cannot be analysed or ``rockdec estimate`` declines it (its model cannot
    be measured, or its measured colour is not shown to lie above the corner's floor,
    :func:`rockdec.estimation.colour_decline`): ``rockdec estimate`` builds no
    calibration for such a record, and neither does the study (at corner 3 and 3 % noise, 21
    of the 58 calibrations of 400 records would serve declined records only)."""
    out = []
    for seed in seeds:
        tick = time.perf_counter()
        y = record(e, int(seed), n, dt, burn_in, defect, size, noise, pole)
        try:
            analysis = measured.analyse([y], dt)
        except ValueError:
            out.append((None, 0.0, 0.0))
            continue
        tock = time.perf_counter()
        diagnostics.statistics([y], analysis)
        spent = time.perf_counter() - tock
        measurement, _ = estimation.measure_model([Record(y, dt, "study")], dt)
        model, sources = estimation.record_model(measurement, analysis)
        declined = measurement is None or estimation.colour_decline(model, sources, measurement, analysis.points_per_cycle)
        out.append((None if declined else calibration.calibration_settings([n], analysis.points_per_cycle, None, model), tock - tick, spent))
    return out


def _estimates(e: float, defect: str | None, size: float, noise: float, seeds, n: int, dt: float, burn_in: int, pole: float, cache_dir) -> list:
    """Per seed of one cell, what :func:`rockdec.estimation.estimate` gives the record
    (its calibration stored in ``cache_dir``): ``e`` (``None`` when it gives none), the
    interval, the calibration's file name, and per check its statistic, threshold and whether it fired; ``None`` for a
    record it refuses."""
    out = []
    for seed in seeds:
        y = record(e, int(seed), n, dt, burn_in, defect, size, noise, pole)
        try:
            got = document(estimation.estimate([Record(y, dt, f"record {seed}")], cache_dir=cache_dir, repair_records=False))  # the checks themselves, on the records as given
        except InputError:
            out.append(None)
            continue
        row = {"e_hat": got["e"], "low": got["interval"][0] if got["e"] is not None else np.nan,
               "high": got["interval"][1] if got["e"] is not None else np.nan, "calibration": got["calibration"]["file"]}
        for name, c in got["diagnostics"].items():
            row[f"{name}_statistic"], row[f"{name}_threshold"], row[f"{name}_fired"] = c["statistic"], c["threshold"], c["fired"]
        out.append(row)
    return out


def _step(e: float, corner: float, points_per_cycle: float, n: int, seed0: int) -> dict:
    """``dt``, ``burn_in`` and the load's ``pole`` of records of ``n`` samples at ``e`` and
    ``points_per_cycle``: :func:`rockdec.physics.simulate.calibrate_dt` for a white load
    (``corner`` 0), :func:`rockdec.studies.coverage.stage` (pilot seeds from ``seed0``) for
    a low-pass load of ``corner`` rocking frequencies."""
    if corner == 0.0:
        return {**calibrate_dt(e=e, g=1.0, sigma_p=1.0, points_per_cycle=points_per_cycle), "pole": 0.0}
    from rockdec.studies.coverage import stage

    return stage(e, n, corner, seed0, points_per_cycle)


def run(
    e_values=DIAGNOSTICS_E, defects=DEFECTS, n_records: int = RECORDS, n_points: int = N_POINTS, cache_dir=None, noise_levels=DIAGNOSTICS_NOISE,
    corners=DIAGNOSTICS_CORNERS, coloured_noise=DIAGNOSTICS_COLOURED_NOISE, coloured_defects=COLOURED_DEFECTS,
) -> pd.DataFrame:
    """One row per record and cell (``e``, sensor ``noise``, load ``corner``, ``defect``,
    ``size``; ``defect`` ``"clean"`` for the records without one): the corrected ``e`` and
    interval ``rockdec estimate`` gives (:func:`rockdec.estimation.estimate`, the
    record model measured off the record), and per check its statistic, threshold and
    whether it fired; under a coloured load (``corners`` other than 0) at the noise levels
    of ``coloured_noise`` and with the defects of ``coloured_defects`` only. Calibrations are stored in ``cache_dir`` and built before the records
    are estimated. The result's attributes ``statistics_s`` and ``simulate_analyse_s`` hold
    the seconds spent on the checks' statistics and on simulating and analysing the records
    (their ratio is the checks' share of a calibration's work), ``calibrations`` how many
    calibrations the records used.

    The records of each ``e`` draw the seeds of its place in :data:`rockdec.pipeline.layout.DIAGNOSTICS_E`, so a run of
    some of them gives the rows a run of all gives them (the workflow runs one ``e``, load and
    noise level a job: :data:`rockdec.pipeline.layout.DIAGNOSTICS_PARTS`).
    """
    unknown = [e for e in e_values if e not in DIAGNOSTICS_E]
    if unknown:
        raise ValueError(f"e = {unknown} is not one of the study's values {DIAGNOSTICS_E}: add it to rockdec.pipeline.layout.DIAGNOSTICS_E")
    cells = []
    for e in e_values:
        seeds = STUDY_SEED_OFFSET + DIAGNOSTICS_E.index(e) * 10**6 + np.arange(n_records)
        for corner in corners:
            for noise in diagnostics_noise(corner, noise_levels, coloured_noise):
                cells.append((e, noise, corner, "clean", 0.0, seeds, n_points, POINTS_PER_CYCLE))
                for defect, sizes in defects.items():
                    if corner != 0.0 and defect not in coloured_defects:
                        continue
                    for size in sizes:
                        if defect == "coarse_sampling":
                            cells.append((e, noise, corner, defect, size, seeds, COARSE_POINTS, size))
                        else:
                            cells.append((e, noise, corner, defect, size, seeds, n_points, POINTS_PER_CYCLE))
    steps = {}
    for e, _, corner, _, _, _, n, ppc in cells:
        if (e, corner, ppc) not in steps:
            steps[e, corner, ppc] = _step(e, corner, ppc, n, STUDY_SEED_OFFSET + PILOT_SEEDS)

    def simulated(e, corner, defect, size, ppc):
        step = steps[e, corner, ppc]
        return None if defect in ("clean", "coarse_sampling") else defect, size, step["dt"], step["burn_in"], step["pole"]

    staged = []
    for e, noise, corner, defect, size, seeds, n, ppc in cells:
        d, size, dt, burn_in, pole = simulated(e, corner, defect, size, ppc)
        staged.append(dask.delayed(_cell)(e, d, size, noise, seeds, n, dt, burn_in, pole))
    settings = engine.compute(*staged)
    keys = {calibration.settings_hash(s): s for records in settings for s, _, _ in records if s is not None}
    print(f"diagnostics study: {len(cells)} cells of {n_records} records simulated and analysed; {len(keys)} calibrations",
          file=sys.stderr, flush=True)
    for key in keys.values():
        calibration.load_or_build(key, cache_dir)
    tasks = []
    for e, noise, corner, defect, size, seeds, n, ppc in cells:
        d, size, dt, burn_in, pole = simulated(e, corner, defect, size, ppc)
        tasks.append(dask.delayed(_estimates)(e, d, size, noise, seeds, n, dt, burn_in, pole, cache_dir))
    results = engine.compute(*tasks)
    rows = []
    cost = np.zeros(2)
    for (e, noise, corner, defect, size, seeds, n, _), staged_cell, got in zip(cells, settings, results):
        for seed, (_, work_s, statistics_s), estimated in zip(seeds, staged_cell, got):
            cost += (work_s, statistics_s)
            rows.append({"e_true": e, "noise": noise, "corner": corner, "defect": defect, "size": size, "seed": int(seed), "n_points": n,
                         **(estimated or {})})
    table = pd.DataFrame(rows)
    table.attrs.update(simulate_analyse_s=float(cost[0]), statistics_s=float(cost[1]), calibrations=len(keys))
    return table


def summary(table: pd.DataFrame) -> pd.DataFrame:
    """Per check, ``e``, sensor noise, load corner and size: records analysed; the median shift of the corrected ``e``
    from the same seeds' clean records (``coarse_sampling``: from their mean) over the
    records that keep an ``e``; the share of records that lose the ``e`` their clean record
    had (``lost_pct``); half the median 95 % interval of the clean records; whether the
    defect matters (the shift beyond half the interval, or half the records losing their
    ``e``); and the share of records on which the check fires (on the clean records, size
    0: the false-alarm rate; NaN with no record checked: under a low-pass load at one
    rocking frequency with 2 % noise ``rockdec estimate`` declines every record)."""
    table = table.assign(**{f"{c}_fired": np.nan for c in diagnostics.CHECKS if f"{c}_fired" not in table})
    rows = []
    for (e, noise, corner), at_e in table.groupby(["e_true", "noise", "corner"]):
        clean = at_e[at_e["defect"] == "clean"].set_index("seed")
        widths = (clean["high"] - clean["low"]).dropna()
        half = 0.5 * float(np.median(widths)) if widths.size else np.nan
        for check in diagnostics.CHECKS:
            fired = clean[f"{check}_fired"].dropna().astype(bool)
            rows.append({"check": check, "e_true": e, "noise": noise, "corner": corner, "size": 0.0, "records": int(fired.size), "e_shift": 0.0, "lost_pct": 0.0,
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
                rows.append({"check": check, "e_true": e, "noise": noise, "corner": corner, "size": size, "records": int(fired.size), "e_shift": shift,
                             "lost_pct": 100.0 * lost, "half_interval": half, "matters": bool(abs(shift) > half or lost >= 0.5),
                             "fired_pct": 100.0 * float(fired.mean()) if fired.size else np.nan})
    return pd.DataFrame(rows)


def digest(summary_table: pd.DataFrame) -> pd.DataFrame:
    """One row per check of :func:`summary`'s table: its false alarms on the clean records
    (size 0), under white impulses (corner 0) and under a low-pass load, as the worst cell's
    rate and the mean over the cells (each cell weighted by its records), the white load's
    mean also at each noise level; whether its defect is studied (``defect_studied``); and, on the defective records of the smallest size that
    matters in each cell (``e``, noise, load), the share caught: the check fired, or
    ``rockdec estimate`` declined the record (``lost_pct``), as the mean over those cells
    weighted by the records checked in each (one for a cell whose every record was
    declined) and the lowest cell's (NaN where no size studied matters); and the share
    caught at the most severe size of :data:`DEFECTS`, averaged alike (``caught_severe``,
    ``severe_size``).

    Examples
    --------
    >>> rows = pd.DataFrame({"check": "drift", "e_true": 0.8, "noise": 0.0, "corner": 0.0, "size": [0.0, 1.0, 3.0],
    ...                      "records": 40, "lost_pct": [0.0, 50.0, 100.0], "matters": [False, True, True],
    ...                      "fired_pct": [2.5, 60.0, np.nan]})
    >>> digest(rows)[["check", "false_white_worst", "caught_mean", "caught_sizes"]].to_dict("records")
    [{'check': 'drift', 'false_white_worst': 2.5, 'caught_mean': 80.0, 'caught_sizes': '1'}]
    """
    def rate(rows: pd.DataFrame) -> tuple[float, float]:
        rows = rows[rows["records"] > 0]
        if rows.empty:
            return np.nan, np.nan
        return float(rows["fired_pct"].max()), float(np.average(rows["fired_pct"], weights=rows["records"]))

    out = []
    for check, rows in summary_table.groupby("check", sort=False):
        clean = rows[rows["size"] == 0.0]
        white, coloured = clean[clean["corner"] == 0.0], clean[clean["corner"] > 0.0]
        row = {"check": check}
        row["false_white_worst"], row["false_white_mean"] = rate(white)
        row["false_white_by_noise"] = "; ".join(f"{100 * noise:g} %: {rate(part)[1]:.1f}" for noise, part in white.groupby("noise"))
        row["false_lowpass_worst"], row["false_lowpass_mean"] = rate(coloured)
        defective = rows[rows["size"] > 0.0]
        row["defect_studied"] = not defective.empty
        smallest = defective[defective["matters"].astype(bool)].sort_values("size").groupby(["e_true", "noise", "corner"]).head(1)
        caught = _caught(smallest)
        row["caught_mean"] = float(np.average(caught, weights=smallest["records"].clip(lower=1))) if len(smallest) else np.nan
        row["caught_lowest"] = float(caught.min()) if len(smallest) else np.nan
        row["caught_sizes"] = ", ".join(f"{s:g}" for s in sorted(smallest["size"].unique()))
        severe = defective[defective["size"] == DEFECTS[check][-1]] if check in DEFECTS else defective.iloc[:0]
        row["severe_size"] = DEFECTS[check][-1] if len(severe) else np.nan
        row["caught_severe"] = float(np.average(_caught(severe), weights=severe["records"].clip(lower=1))) if len(severe) else np.nan
        out.append(row)
    return pd.DataFrame(out)


def _caught(rows: pd.DataFrame) -> pd.Series:
    """Per row of :func:`summary`: the share (%) of its records on which the check fired
    or which lost their ``e``; a row with no record checked (every record declined, with or
    without its clean twin) counts as caught in full when any record lost its ``e``."""
    caught = 100.0 - (100.0 - rows["lost_pct"]) * (1.0 - rows["fired_pct"].fillna(0.0) / 100.0)
    return caught.where(rows["records"] > 0, np.where(rows["lost_pct"] > 0.0, 100.0, np.nan))


def digest_markdown(table: pd.DataFrame) -> str:
    """:func:`digest`'s table as Markdown (rates in per cent, ``-`` where none was read)."""
    def pct(x) -> str:
        return "-" if not np.isfinite(x) else f"{x:.1f} %"

    lines = ["| check | false alarms, white load: worst cell (mean) | mean by sensor noise | "
             "false alarms, low-pass load: worst cell (mean) | caught where it moves `e`: mean (lowest cell) | at sizes | "
             "caught at the most severe size studied (mean) |",
             "| --- | --- | --- | --- | --- | --- | --- |"]
    for r in table.itertuples():
        caught = (f"{pct(r.caught_mean)} ({pct(r.caught_lowest)})" if np.isfinite(r.caught_mean)
                  else "no size studied moves `e`" if r.defect_studied else "its defect is not studied here")
        lines.append(f"| `{r.check}` | {pct(r.false_white_worst)} ({pct(r.false_white_mean)}) | {r.false_white_by_noise or '-'} | "
                     f"{pct(r.false_lowpass_worst)} ({pct(r.false_lowpass_mean)}) | {caught} | {r.caught_sizes or '-'} | "
                     + (f"{pct(r.caught_severe)} at {r.severe_size:g} |" if np.isfinite(r.caught_severe) else "- |"))
    return "\n".join(lines) + "\n"

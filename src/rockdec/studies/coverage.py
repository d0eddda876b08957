"""Does the interval of ``rockdec estimate`` hold? Coverage on simulated records of known ``e``.

A cell of the study is a true ``e``, a condition (a sensor noise in units of ``sigma_Y``, a
first-order low-pass load with its corner in rocking frequencies ``1/T(sigma_Y)``, eq. 5, or
both; :data:`rockdec.pipeline.layout.COVERAGE_CONDITIONS`) and the simulator that makes its records
(the compiled kernel of :mod:`rockdec.physics.simulate`, or a reference written apart and passed in,
``tests/rocking_vectorised.py``). Every record goes through exactly the path of
``rockdec estimate``: :func:`rockdec.estimation.estimate` with the record model measured
from the record (``model=None``), and once more with the paper's model (white load,
noise-free sensor: :data:`rockdec.physics.record_model.PAPER`), the calibration the tool used
before it measured the record, for its width and coverage beside.

Placing a record at its condition (:func:`stage`). Under a low-pass load the samples per
cycle no longer go as ``dt^-2``, and a corner set in rocking frequencies moves with them:
the pole ``c = exp(-2 pi corner / N)`` places the corner only for the ``N`` samples per
cycle that the records actually have. :func:`stage` fixes ``c`` for the target ``N`` and
searches the step until the median of the pilot records' own ``N = T(sigma_Y)/dt`` (the
true ``g``) is within :data:`STAGE_TOLERANCE` of the target, so that ``N`` and the corner
are both what the cell states; the records' achieved medians are reported per cell
(:func:`summary`), beside the samples per cycle the tool reads off them.

A cell's coverage is its calibrations' and its records' sample together: :func:`fresh_coverage`
reads the cell's calibrations with fresh records of its route, :func:`recorrect` reads the
cell again through the belt as it is from the raw values it stores.

Seeds: the study's records and pilots start at :data:`STUDY_SEED_OFFSET` (fresh records at
:data:`FRESH_SEED_OFFSET`), apart from the
calibration's (:data:`rockdec.calibrate.calibration.CALIBRATION_SEED_OFFSET`) and the scenes'.
"""

from __future__ import annotations

import math
import re
import sys
from collections import Counter

import numpy as np
import pandas as pd
import xarray as xr
from scipy import stats

from rockdec import engine
from rockdec import estimation
from rockdec.report.estimate_report import document
from rockdec.calibrate.belt import Z95
from rockdec.rdd import registry
from rockdec.pipeline.layout import COVERAGE_CASES, COVERAGE_CONDITIONS, COVERAGE_SIMULATORS
from rockdec.physics.models import SCALE_CONSTANT_GUESS, period_from_g, step_for_density
from rockdec.physics.record_model import PAPER, Load, RecordModel
from rockdec.record.records import Record, RecordError

__all__ = [
    "BAND_MIN_ANSWERED", "BIAS_RATIO", "CELL_SEEDS", "COVERAGE_BAND", "MAD_NORMAL", "MEASURED", "NOMINAL",
    "PILOT_SEEDS", "POINTS_PER_CYCLE", "SHARPNESS_BAND", "STAGE_TOLERANCE", "STUDY_SEED_OFFSET",
    "band_chance", "band_markdown", "band_probability", "calibration_error", "estimate_record",
    "fresh_calibrations", "fresh_coverage", "fresh_markdown", "fresh_summary", "in_band",
    "in_sharpness_band", "kernel_records", "kurtosis_about", "markdown", "recorrect", "run_cell",
    "sharpness", "sharpness_probability", "simulator_of", "stage", "summary", "table",
]

#: Seeds of the study's records start here (apart from calibration and pilot seeds).
STUDY_SEED_OFFSET = 2**60

#: Seeds of the fresh records of :func:`fresh_coverage` start here: apart from the study's
#: records (:data:`STUDY_SEED_OFFSET`), the calibration's and the scenes'.
FRESH_SEED_OFFSET = 2**59

#: Seeds of one cell: records at ``offset + cell * CELL_SEEDS``, its pilots
#: :data:`PILOT_SEEDS` further on.
CELL_SEEDS, PILOT_SEEDS = 10**7, 9 * 10**6

#: Samples per cycle at ``sigma_Y`` the records are placed at (the paper's, eq. 5).
POINTS_PER_CYCLE = 75.0

#: Pilot records of :func:`stage`, relative tolerance on their median samples per cycle,
#: and largest number of step updates.
STAGE_PILOTS, STAGE_TOLERANCE, STAGE_ITERATIONS = 16, 0.015, 14

#: Lower and upper end of the coverage a 95 % interval is held to on 200 records
#: (the binomial 95 % range of 200 draws at 0.95 is about 92-98 %).
COVERAGE_BAND = (0.92, 0.98)

#: Largest ``|corrected bias| / sd`` the study accepts.
BIAS_RATIO = 0.25

#: Nominal coverage of the reported interval.
NOMINAL = 0.95

#: The target the study's cells are judged by together (:func:`band_chance`): pooled
#: coverage within ``POOLED_BAND``; the covered counts' dispersion about :data:`NOMINAL` at
#: most ``DISPERSION_MAX`` times the binomial's; the number of cells outside
#: :data:`COVERAGE_BAND` at least ``P_OUTSIDE_MIN`` probable under an exactly calibrated
#: interval; no cell answered on ``FLOOR_ANSWERED`` records or more below ``CELL_FLOOR``.
POOLED_BAND, DISPERSION_MAX, P_OUTSIDE_MIN = (0.94, 0.96), 1.3, 0.05
CELL_FLOOR, FLOOR_ANSWERED = 0.90, 100

#: Median of ``|x|`` for a standard normal ``x`` (its 75 % quantile): a normal scatter's
#: median distance from its centre over its sd (:func:`sharpness`).
MAD_NORMAL = float(stats.norm.ppf(0.75))

#: Range of a cell's sharpness (:func:`sharpness`: median interval width over 3.92 times
#: the spread of the reported ``e`` about the truth) a calibrated interval is held to: below
#: it the interval is narrower than the scatter it must hold, above it wider than the
#: record needs.
SHARPNESS_BAND = (0.9, 1.15)

#: Fewest answered records for a cell to count in :func:`band_chance` (fewer cannot tell
#: 92 % from 98 %: the binomial sd at 50 records is 3 points).
BAND_MIN_ANSWERED = 50

#: The model argument of :func:`rockdec.estimation.estimate` that measures the record's own model.
MEASURED = None


def true_points_per_cycle(theta: np.ndarray, dt: float) -> np.ndarray:
    """Samples per cycle at each record's ``sigma_Y`` with the true ``g = 1`` (eq. 5)."""
    sigma = np.sqrt(np.mean(np.atleast_2d(theta) ** 2, axis=1))
    return period_from_g(sigma, 1.0) / dt


def corner_of(pole: float, points_per_cycle) -> np.ndarray:
    """The load's corner in rocking frequencies for a filter ``pole`` and records of
    ``points_per_cycle``: ``-ln(c) N / (2 pi)`` (NaN for white noise)."""
    return np.full(np.shape(points_per_cycle), np.nan) if pole == 0.0 else -math.log(pole) * np.asarray(points_per_cycle) / (2 * math.pi)


def kernel_records(seeds, n_points: int, *, dt, e, burn_in, pole, noise) -> np.ndarray:
    """Records of the compiled kernel (:func:`rockdec.physics.simulate.simulate_block`, ``g = sigma_p
    = 1``) plus white sensor noise of ``noise`` times each record's rms
    (:func:`rockdec.physics.loading.add_sensor_noise`, as the calibration adds it)."""
    from rockdec.physics.loading import add_sensor_noise
    from rockdec.physics.simulate import simulate_block

    theta = simulate_block(seeds, n_points, dt=dt, g=1.0, e=e, sigma_p=1.0, burn_in=burn_in, pole=pole)[0]
    if noise > 0.0:
        for row, seed in zip(theta, seeds):
            add_sensor_noise(row[None], [seed], noise * float(np.sqrt(np.mean(row**2))))
    return theta


def stage(e: float, n_points: int, corner: float | None, seed0: int, points_per_cycle: float = POINTS_PER_CYCLE) -> dict:
    """Step ``dt`` and load pole placing records of ``n_points`` at ``points_per_cycle`` and
    the load's ``corner`` (module docstring); ``g = sigma_p = 1``.

    Secant steps in ``ln dt`` (:func:`rockdec.physics.simulate.secant_step`) on the median samples
    per cycle of :data:`STAGE_PILOTS` pilot records (seeds from ``seed0``). Returns ``dt``,
    ``pole``, ``burn_in`` and the pilots' median ``points_per_cycle``.
    """
    from rockdec.physics.simulate import default_burn_in, secant_step

    pole = Load().pole(points_per_cycle) if corner is None else Load("lowpass", corner).pole(points_per_cycle)
    burn_in = default_burn_in(e, points_per_cycle)
    dt = step_for_density(SCALE_CONSTANT_GUESS, 1.0, 1.0, points_per_cycle)
    seeds = seed0 + np.arange(STAGE_PILOTS)
    history: list = []
    best = (math.inf, dt, math.nan)
    for _ in range(STAGE_ITERATIONS):
        theta = kernel_records(seeds, n_points, dt=dt, e=e, burn_in=burn_in, pole=pole, noise=0.0)
        achieved = float(np.median(true_points_per_cycle(theta, dt)))
        miss = abs(math.log(achieved / points_per_cycle))
        if miss < best[0]:
            best = (miss, dt, achieved)
        if miss < STAGE_TOLERANCE:
            break
        dt = secant_step(history, dt, achieved, points_per_cycle)
    _, dt, achieved = best
    return {"dt": dt, "pole": pole, "burn_in": burn_in, "points_per_cycle": achieved}


def _num(x) -> float:
    return math.nan if x is None else float(x)


def _model_read(report: dict | None) -> dict:
    """What the tool measured of the record's model (``record_model`` of
    :func:`rockdec.estimation.estimate`): the sensor noise in ``sigma_Y`` and the load's
    corner in rocking frequencies (NaN when not measured), and the model it simulated."""
    measured = (report or {}).get("measured") or {}
    detected = measured.get("detected") or {}
    noise = (measured.get("sensor_noise_sigma_y") or {}).get("value")
    corner = (measured.get("load_corner_rocking") or {}).get("value") if detected.get("colour") else None
    simulated = (report or {}).get("simulated") or {}
    paper = bool(simulated) and RecordModel.from_key(simulated) == PAPER
    return {"noise_read": _num(noise), "corner_read": _num(corner), "model": simulated.get("described", ""), "paper": paper,
            "noisy": bool(detected.get("sensor_noise")), "coloured": bool(detected.get("colour"))}


def estimate_record(theta: np.ndarray, dt: float, source: str, cache_dir, model) -> dict:
    """:func:`rockdec.estimation.estimate` of one record, flattened; a refusal
    (:class:`rockdec.record.records.RecordError`) is a null ``e`` with the refusal as its reason."""
    try:
        out = document(estimation.estimate([Record(theta, dt, source)], cache_dir=cache_dir, model=model))
    except RecordError as exc:
        return {"e": math.nan, "low": math.nan, "high": math.nan, "reason": f"refused: {exc}", "estimator": "", "warnings": [],
                "points_per_cycle": math.nan, "calibration": "", "per": {}, **_model_read(None)}
    interval = out["interval"] or [None, None]
    return {
        "e": _num(out["e"]),
        "low": _num(interval[0]) if out["e"] is not None else math.nan,
        "high": _num(interval[1]) if out["e"] is not None else math.nan,
        "reason": out["reason"] or "",
        "estimator": out["estimator"] or "",
        "warnings": list(out["warnings"]),
        "points_per_cycle": _num(out["points_per_cycle"]),
        "calibration": out["calibration"]["file"] or "",
        "per": {name: (_num(v["e"]), *((_num(x) for x in v["interval"]) if v["e"] is not None else (math.nan, math.nan)), _num(v["raw"]))
                for name, v in out["estimators"].items()},
        **_model_read(out.get("record_model")),
    }


def _batch(simulate, seeds, n_points, staged, e, noise, cache_dir, model, done: str = "") -> list[tuple]:
    """Simulate records ``seeds`` and estimate each with ``model`` and with the paper's;
    ``done``, when given, is printed to stderr at the end (the cell's progress in its log)."""
    theta = simulate(seeds, n_points, dt=staged["dt"], e=e, burn_in=staged["burn_in"], pole=staged["pole"], noise=noise)
    ppc = true_points_per_cycle(theta, staged["dt"])  # the noise moves it by noise^2 / 2 (0.1 % at 5 %)
    out = []
    for seed, row, n in zip(seeds, theta, ppc):
        got = estimate_record(row, staged["dt"], f"record {seed}", cache_dir, model)
        # a record whose measured model is the paper's went through the paper's calibration already
        paper = got if got["paper"] else estimate_record(row, staged["dt"], f"record {seed}", cache_dir, PAPER)
        out.append((float(n), got, paper))
    if done:
        print(done, file=sys.stderr, flush=True)
    return out


def run_cell(cell: str, n_records: int, n_points: int, cache_dir, *, simulate=kernel_records, model=MEASURED, batch: int = 10) -> xr.Dataset:
    """The study's cell ``cell`` (:data:`rockdec.pipeline.layout.COVERAGE_CASES`): ``n_records``
    records of ``n_points`` samples, made by ``simulate`` (:func:`kernel_records`, or a
    function of the same signature), each estimated by :func:`estimate_record` with
    ``model`` and with :data:`rockdec.physics.record_model.PAPER`.

    Records run in Dask tasks of ``batch``; calibrations are built as the records ask for
    them and stored in ``cache_dir`` (shared by every cell). Returns per record (and
    estimator): the reported ``e_hat``, ``low``, ``high``, ``reason`` (empty unless ``e`` is
    null), ``reported_by`` (the estimator), ``warnings`` (joined by `` | ``), the tool's samples per cycle,
    the calibration file, each estimator's ``est_e``/``est_low``/``est_high`` and its raw value
    ``est_raw`` (a belt variant is judged offline by inverting ``est_raw`` through the stored
    calibration), the paper
    model's ``paper_e``/``paper_low``/``paper_high``/``paper_reason``, and the record's
    true samples per cycle and corner.
    """
    import dask

    simulator, condition, e = COVERAGE_CASES[cell]
    noise, corner = COVERAGE_CONDITIONS[condition]
    index = list(COVERAGE_CASES).index(cell)
    seed0 = STUDY_SEED_OFFSET + index * CELL_SEEDS
    staged = stage(e, n_points, corner, seed0 + PILOT_SEEDS)
    print(f"coverage {cell}: dt = {staged['dt']:.4g}, pole = {staged['pole']:.6g}, pilots' median samples per cycle "
          f"{staged['points_per_cycle']:.1f}", file=sys.stderr, flush=True)
    seeds = seed0 + np.arange(n_records)
    tasks = [dask.delayed(_batch)(simulate, seeds[i:i + batch], n_points, staged, e, noise, cache_dir, model,
                                  f"coverage {cell}: records {i + 1}-{min(i + batch, n_records)} of {n_records} done")
             for i in range(0, n_records, batch)]
    rows = [row for part in engine.compute(*tasks) for row in part]
    names = list(registry.ESTIMATORS)
    ppc = np.array([r[0] for r in rows])
    got = [r[1] for r in rows]
    paper = [r[2] for r in rows]
    per = np.array([[g["per"].get(name, (math.nan,) * 4) for name in names] for g in got]).reshape(n_records, len(names), 4)
    rec, rest = ("record",), ("record", "estimator")

    def strings(values):
        return np.array(values, dtype=object).astype(str)

    ds = xr.Dataset(
        {
            "e_hat": (rec, [g["e"] for g in got], {"units": "1", "long_name": "reported e (NaN: null)"}),
            "low": (rec, [g["low"] for g in got], {"units": "1", "long_name": "lower end of the reported 95 % interval"}),
            "high": (rec, [g["high"] for g in got], {"units": "1", "long_name": "upper end of the reported 95 % interval"}),
            "reason": (rec, strings([g["reason"] for g in got]), {"long_name": "why e is null (empty when it is not)"}),
            "reported_by": (rec, strings([g["estimator"] for g in got]), {"long_name": "estimator the tool reported"}),
            "warnings": (rec, strings([" | ".join(g["warnings"]) for g in got]), {"long_name": "warnings of the tool, joined by ' | '"}),
            "record_model": (rec, strings([g["model"] for g in got]), {"long_name": "record model the tool's calibration simulated"}),
            "noise_read": (rec, [g["noise_read"] for g in got], {"units": "1", "long_name": "sensor noise the tool measured, in sigma_Y"}),
            "corner_read": (rec, [g["corner_read"] for g in got], {"units": "1", "long_name": "load corner the tool measured, in rocking frequencies (NaN: no colour detected)"}),
            "noisy": (rec, [g["noisy"] for g in got], {"long_name": "whether the tool detected sensor noise"}),
            "coloured": (rec, [g["coloured"] for g in got], {"long_name": "whether the tool detected a coloured load"}),
            "calibration": (rec, strings([g["calibration"] for g in got]), {"long_name": "calibration file the tool used"}),
            "ppc_read": (rec, [g["points_per_cycle"] for g in got], {"units": "1", "long_name": "samples per cycle the tool read"}),
            "ppc_true": (rec, ppc, {"units": "1", "long_name": "samples per cycle at the record's sigma_Y with the true g (eq. 5)"}),
            "corner_true": (rec, corner_of(staged["pole"], ppc), {"units": "1", "long_name": "load corner in the record's rocking frequencies"}),
            "est_e": (rest, per[..., 0], {"units": "1", "long_name": "corrected e of each estimator (NaN: none)"}),
            "est_low": (rest, per[..., 1], {"units": "1", "long_name": "lower end of each estimator's 95 % interval"}),
            "est_high": (rest, per[..., 2], {"units": "1", "long_name": "upper end of each estimator's 95 % interval"}),
            "est_raw": (rest, per[..., 3], {"units": "1", "long_name": "raw value of each estimator, before the belt (NaN: none)"}),
            "paper_e": (rec, [p["e"] for p in paper], {"units": "1", "long_name": "reported e under the paper's model"}),
            "paper_low": (rec, [p["low"] for p in paper], {"units": "1", "long_name": "lower end under the paper's model"}),
            "paper_high": (rec, [p["high"] for p in paper], {"units": "1", "long_name": "upper end under the paper's model"}),
            "paper_reason": (rec, strings([p["reason"] for p in paper]), {"long_name": "why e is null under the paper's model"}),
        },
        coords={
            "record": ("record", np.arange(n_records), {"long_name": "simulated record"}),
            "estimator": ("estimator", names, {"long_name": "estimator of e"}),
        },
        attrs={
            "cell": cell, "simulator": simulator, "condition": condition, "e_true": float(e),
            "noise": float(noise), "corner": math.nan if corner is None else float(corner),
            "n_points": int(n_points), "dt": float(staged["dt"]), "pole": float(staged["pole"]),
            "burn_in": int(staged["burn_in"]), "pilot_points_per_cycle": float(staged["points_per_cycle"]),
            "first_seed": int(seed0),
        },
    )
    return ds


def recorrect(ds: xr.Dataset, cache_dir) -> xr.Dataset:
    """The cell ``ds`` (:func:`run_cell`) read again offline: each record's raw value of the
    estimator the tool reported (``est_raw``) inverted through the belt of the calibration
    file it used (in ``cache_dir``), by :mod:`rockdec.calibrate.belt` as it is, its spread
    scaled to the record's length (:func:`rockdec.calibrate.calibration.spread_scale`).

    A belt variant is judged on the study's records this way without simulating them again:
    with the belt that ran the cell, ``e_hat``, ``low`` and ``high`` come back unchanged.
    The estimator reported stays the one the cell stored (a variant that would change the
    choice needs the cell run again); a record with a null ``e`` stays null, and a raw value
    beyond the belt's mean curve gives a null (:func:`rockdec.estimation.beyond`).
    Returns a copy of ``ds`` with ``e_hat``, ``low`` and ``high`` replaced.
    """
    if "est_raw" not in ds:
        raise ValueError(f"cell {ds.attrs.get('cell', '?')} stores no raw values (est_raw): run it again to read it offline")
    invert = _Inverter(cache_dir, int(ds.attrs["n_points"]))
    out = ds.copy(deep=True)
    for k in range(ds.sizes["record"]):
        name, file = str(ds["reported_by"].values[k]), str(ds["calibration"].values[k])
        if name and file and np.isfinite(ds["e_hat"].values[k]):
            raw = float(ds["est_raw"].sel(estimator=name).values[k])
            out["e_hat"].values[k], out["low"].values[k], out["high"].values[k] = invert(file, name, raw)
    return out


class _Inverter:
    """Raw values inverted through the belts of stored calibrations (``cache_dir``), as
    :func:`rockdec.estimation.estimate` inverts a record's: each calibration's belts
    read once, their spread scaled to records of ``n_points``
    (:func:`rockdec.calibrate.calibration.spread_scale`)."""

    def __init__(self, cache_dir, n_points: int):
        self.cache_dir, self.n_points, self.belts = cache_dir, n_points, {}

    def __call__(self, file: str, name: str, raw: float) -> tuple[float, float, float]:
        """Corrected ``e``, low and high of ``raw`` of estimator ``name`` through the calibration
        ``file``; NaN for each when the belt gives no value or the raw value lies beyond its
        mean curve (:func:`rockdec.estimation.beyond`)."""
        import json
        from pathlib import Path

        from rockdec.calibrate import belt, calibration, ncread

        if file not in self.belts:
            cal = ncread.read(Path(self.cache_dir) / file)
            self.belts[file] = belt.belts(cal, calibration.spread_scale(json.loads(cal.attrs["settings"]), self.n_points))
        b = self.belts[file][name]
        c = belt.correct(b, raw)
        if estimation.beyond(b, raw, c) is not None or not np.isfinite(c.value):
            return math.nan, math.nan, math.nan
        return c.value, c.low, c.high


def _fresh_raw(simulate, seeds, attrs: dict) -> list[tuple]:
    """Records ``seeds`` of the route of a cell of attributes ``attrs`` (:func:`run_cell`),
    each analysed as :func:`rockdec.estimation.estimate` analyses it: the samples
    per cycle read and every estimator's raw value."""
    from rockdec.rdd import measured

    theta = simulate(seeds, int(attrs["n_points"]), dt=attrs["dt"], e=attrs["e_true"], burn_in=int(attrs["burn_in"]), pole=attrs["pole"],
                     noise=attrs["noise"])
    out = []
    for row in theta:
        try:
            analysis = measured.analyse([row], attrs["dt"], dict(measured.DEFAULT_SETTINGS))
        except ValueError:
            out.append((math.nan, {}))
            continue
        out.append((analysis.points_per_cycle, dict(analysis.raw)))
    return out


def fresh_coverage(ds: xr.Dataset, cache_dir, n_records: int, *, seed0: int | None = None, simulate=kernel_records,
                   batch: int = 20) -> pd.DataFrame:
    """The calibrations of the cell ``ds`` (:func:`run_cell`) judged on ``n_records`` fresh
    records of its route: its step, burn-in, load and sensor noise, seeds from ``seed0``
    (default: :data:`FRESH_SEED_OFFSET` plus the cell's place times :data:`CELL_SEEDS`).

    A cell's coverage mixes what its calibrations give and the sample of its own records;
    fresh records separate the two. Each fresh record is analysed as the tool analyses it
    (same raw values: with the cell's own seeds they are its ``est_raw``), and its raw value
    is inverted (:func:`rockdec.calibrate.belt.correct`) through the calibration file and
    estimator that the cell's own records of its samples-per-cycle bin
    (:func:`rockdec.calibrate.calibration.ppc_key`) used most; the record model is not
    measured again, so a calibration of another noise bin that some of the cell's records
    of that bin used is stood in for by the commonest. A fresh record in a bin none of the
    cell's records read has no calibration (empty ``calibration``, NaN ends).

    One row per fresh record: ``ppc_read``, ``bin``, ``calibration``, ``estimator``,
    ``raw``, corrected ``e``, ``low``, ``high`` and ``covered``.
    """
    import dask

    from rockdec.calibrate import calibration

    attrs = dict(ds.attrs)
    if seed0 is None:
        seed0 = FRESH_SEED_OFFSET + list(COVERAGE_CASES).index(attrs["cell"]) * CELL_SEEDS
    used: dict[float, Counter] = {}
    for k in range(ds.sizes["record"]):
        name, file, ppc = str(ds["reported_by"].values[k]), str(ds["calibration"].values[k]), float(ds["ppc_read"].values[k])
        if name and file and np.isfinite(ppc):
            used.setdefault(calibration.ppc_key(ppc), Counter())[(file, name)] += 1
    seeds = seed0 + np.arange(n_records)
    tasks = [dask.delayed(_fresh_raw)(simulate, seeds[i:i + batch], attrs) for i in range(0, n_records, batch)]
    invert = _Inverter(cache_dir, int(attrs["n_points"]))
    rows = []
    for ppc, raw in (r for part in engine.compute(*tasks) for r in part):
        key = calibration.ppc_key(ppc) if np.isfinite(ppc) else math.nan
        file, name = used[key].most_common(1)[0][0] if key in used else ("", "")
        value, low, high = invert(file, name, raw[name]) if file else (math.nan,) * 3
        rows.append({"ppc_read": ppc, "bin": key, "calibration": file, "estimator": name, "raw": raw.get(name, math.nan),
                     "e": value, "low": low, "high": high, "covered": bool(low <= attrs["e_true"] <= high)})
    return pd.DataFrame(rows)


def fresh_summary(ds: xr.Dataset, fresh: pd.DataFrame) -> dict:
    """One row of the fresh-records table: the cell ``ds``'s coverage on its own records
    (:func:`summary`: of the answered) beside its calibrations' on the fresh records
    ``fresh`` (:func:`fresh_coverage`): of the answered, its binomial standard error, and of
    every fresh record (a null or a bin without calibration counted as not covered); the
    share of fresh records declined or without a calibration; the corrected sd of both and
    their sharpness (:func:`sharpness`); and the coverage of the answered fresh records in
    the bin most of them read and in the others."""
    own = summary(ds)
    answered = fresh[np.isfinite(fresh["low"]) & np.isfinite(fresh["high"])]
    n = len(answered)
    cov = float(answered["covered"].mean()) if n else math.nan
    main = answered["bin"].mode().iloc[0] if n else math.nan
    in_main = answered["bin"] == main
    return {
        "cell": ds.attrs["cell"], "e_true": ds.attrs["e_true"], "records": own["answered"], "coverage": own["answered_coverage"],
        "sd": own["sd"], "sharpness": own["sharpness"], "fresh": len(fresh), "fresh_answered": n, "fresh_coverage": cov,
        "fresh_coverage_se": math.sqrt(cov * (1.0 - cov) / n) if n else math.nan,
        "fresh_coverage_all": float(fresh["covered"].mean()) if len(fresh) else math.nan,
        "fresh_declined": 1.0 - n / len(fresh) if len(fresh) else math.nan,
        "fresh_sd": float(np.std(answered["e"], ddof=1)) if n > 1 else math.nan,
        "fresh_sharpness": sharpness(ds.attrs["e_true"], answered["e"], answered["high"] - answered["low"]),
        "main_bin": float(main), "main_coverage": float(answered[in_main]["covered"].mean()) if in_main.any() else math.nan,
        "main_share": float(in_main.mean()) if n else math.nan,
        "other_coverage": float(answered[~in_main]["covered"].mean()) if (~in_main).any() else math.nan,
    }


def fresh_calibrations(ds: xr.Dataset, fresh: pd.DataFrame) -> pd.DataFrame:
    """Each calibration of the cell ``ds`` judged on its own: one row per calibration file
    that served fresh records (:func:`fresh_coverage`'s ``fresh``), with the estimator it
    inverted, the cell's own records it served, the fresh records it answered, their
    coverage and its binomial standard error, their sharpness (:func:`sharpness`) and
    whether both lie in their bands (:func:`in_band`, :func:`in_sharpness_band`)."""
    e = ds.attrs["e_true"]
    own = Counter(str(c) for c in ds["calibration"].values if c)
    answered = fresh[np.isfinite(fresh["low"]) & np.isfinite(fresh["high"])]
    rows = []
    for file, part in answered.groupby("calibration", sort=False):
        n, cov = len(part), float(part["covered"].mean())
        ratio = sharpness(e, part["e"], part["high"] - part["low"])
        rows.append({"cell": ds.attrs["cell"], "e_true": e, "calibration": file, "estimator": part["estimator"].mode().iloc[0],
                     "records": own[file], "fresh_answered": n, "fresh_coverage": cov, "fresh_coverage_se": math.sqrt(cov * (1.0 - cov) / n),
                     "fresh_sharpness": ratio, "in_band": bool(in_band(cov)), "sharp": bool(in_sharpness_band(ratio))})
    return pd.DataFrame(rows, columns=["cell", "e_true", "calibration", "estimator", "records", "fresh_answered", "fresh_coverage",
                                       "fresh_coverage_se", "fresh_sharpness", "in_band", "sharp"])


def fresh_chance(rows: pd.DataFrame) -> tuple[dict, dict]:
    """:func:`band_chance` of the cells of the fresh-records table ``rows``
    (:func:`fresh_summary`) read on their own records and on the fresh ones."""
    own = pd.DataFrame({"answered": rows["records"], "answered_coverage": rows["coverage"], "in_band": in_band(rows["coverage"]),
                        "sharpness": rows["sharpness"]})
    fresh = pd.DataFrame({"answered": rows["fresh_answered"], "answered_coverage": rows["fresh_coverage"],
                          "in_band": in_band(rows["fresh_coverage"]), "sharpness": rows["fresh_sharpness"]})
    return band_chance(own), band_chance(fresh)


def calibration_error(rows: pd.DataFrame, calibrations: pd.DataFrame) -> dict:
    """How far single calibrations stray from :data:`NOMINAL`, and what that does to the
    dispersion of the cells (:func:`band_chance`) whose records share them.

    ``sd``: the spread of the calibrations' own coverage beyond the binomial, by moments
    over the calibrations answered on at least :data:`BAND_MIN_ANSWERED` fresh records
    (``calibrations``, :func:`fresh_calibrations`): ``sqrt(mean((c - p)^2 - p (1 - p) / n))``,
    0 when the binomial explains it all. ``dispersion``: the covered counts' dispersion a
    study of the cells ``rows`` (:func:`fresh_summary`) has on average when each cell's
    records are spread over its calibrations as its own records were: a cell of ``n``
    records whose calibrations serve shares ``w`` has
    ``var(k) = n p (1 - p) + (n sum(w^2) - 1) n sd^2``, so the ratio is the mean over the
    cells answered on at least :data:`BAND_MIN_ANSWERED` records of
    ``1 + (n sum(w^2) - 1) sd^2 / (p (1 - p))``; ``shares``: the mean ``sum(w^2)``.

    Examples
    --------
    >>> rows = pd.DataFrame({"cell": ["a"], "records": [200]})
    >>> cals = pd.DataFrame({"cell": ["a", "a"], "records": [100, 100], "fresh_answered": [400, 400],
    ...                      "fresh_coverage": [0.93, 0.97]})
    >>> out = calibration_error(rows, cals)
    >>> round(out["sd"], 4), round(out["shares"], 2), round(out["dispersion"], 2)
    (0.0168, 0.5, 1.59)
    """
    p = NOMINAL
    judged = calibrations[calibrations["fresh_answered"] >= BAND_MIN_ANSWERED]
    n = judged["fresh_answered"].to_numpy(dtype=float)
    excess = np.mean((judged["fresh_coverage"].to_numpy(dtype=float) - p) ** 2 - p * (1.0 - p) / n) if len(judged) else math.nan
    sd = math.sqrt(max(excess, 0.0)) if np.isfinite(excess) else math.nan
    served = calibrations.groupby("cell")["records"]
    shares = (served.apply(lambda r: float(np.sum((r / r.sum()) ** 2)) if r.sum() else math.nan)).reindex(rows["cell"]).to_numpy()
    cells = rows["records"].to_numpy(dtype=float)
    used = (cells >= BAND_MIN_ANSWERED) & np.isfinite(shares)
    ratio = 1.0 + (cells[used] * shares[used] - 1.0) * sd**2 / (p * (1.0 - p))
    return {"calibrations": len(judged), "sd": sd, "shares": float(np.mean(shares[used])) if used.any() else math.nan,
            "dispersion": float(np.mean(ratio)) if used.any() else math.nan}


def fresh_markdown(rows: pd.DataFrame, calibrations: pd.DataFrame | None = None) -> str:
    """The fresh-records table (:func:`fresh_summary` rows) as Markdown, coverages outside
    :data:`COVERAGE_BAND` and sharpness outside :data:`SHARPNESS_BAND` in bold; below it
    the cells read against chance on their own records and on the fresh ones
    (:func:`fresh_chance`, :func:`band_markdown`), and, given ``calibrations``
    (:func:`fresh_calibrations` rows), how far single calibrations stray and the dispersion
    that makes (:func:`calibration_error`), and each calibration's check on the fresh records
    it served (bold marks only those answered on :data:`BAND_MIN_ANSWERED` or more)."""
    lines = ["| cell | own records: coverage (n) | fresh: coverage ± se (answered / n) | fresh: every record | fresh declined | "
             "sd own, fresh | width / (3.92 sd) own, fresh | fresh: main bin (share) | fresh: other bins |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"]

    def pct(x, bold=True):
        if not np.isfinite(x):
            return "-"
        flag = "**" if bold and not in_band(x) else ""
        return f"{flag}{100 * x:.1f} %{flag}"

    for r in rows.itertuples():
        lines.append(f"| {r.cell} | {pct(r.coverage)} ({r.records}) | {pct(r.fresh_coverage)} ± {100 * r.fresh_coverage_se:.1f} "
                     f"({r.fresh_answered} / {r.fresh}) | {pct(r.fresh_coverage_all, False)} | {100 * r.fresh_declined:.1f} % | "
                     f"{r.sd:.4f}, {r.fresh_sd:.4f} | {_sharp_cell(r.sharpness)}, {_sharp_cell(r.fresh_sharpness)} | "
                     f"{pct(r.main_coverage, False)} ({100 * r.main_share:.0f} %) | {pct(r.other_coverage, False)} |")
    own, fresh = fresh_chance(rows)
    lines += ["", f"On their own records: {band_markdown(own)}", "", f"On the fresh records: {band_markdown(fresh)}"]
    if calibrations is not None and len(calibrations):
        error = calibration_error(rows, calibrations)
        lines += ["", f"Single calibrations on fresh records ({error['calibrations']} answered on at least {BAND_MIN_ANSWERED}): "
                  f"their coverage strays from {100 * NOMINAL:.0f} % by a standard deviation of {100 * error['sd']:.1f} points "
                  f"beyond the binomial. The cells' records share their calibrations (mean sum of squared shares "
                  f"{error['shares']:.2f}), so that error alone makes the own records' dispersion {error['dispersion']:.2f} times "
                  f"the binomial on average (read on them: {own['chi2_ratio']:.2f})."]
        lines += ["", "| cell | calibration | estimator | own records served | fresh: coverage ± se (answered) | fresh: width / (3.92 sd) |",
                  "| --- | --- | --- | --- | --- | --- |"]
        for r in calibrations.itertuples():
            judged = r.fresh_answered >= BAND_MIN_ANSWERED
            lines.append(f"| {r.cell} | {r.calibration} | {r.estimator} | {r.records} | {pct(r.fresh_coverage, judged)} ± "
                         f"{100 * r.fresh_coverage_se:.1f} ({r.fresh_answered}) | "
                         f"{_sharp_cell(r.fresh_sharpness, judged)} |")
    return "\n".join(lines) + "\n"


def simulator_of(cell: str, reference=None):
    """The simulator of the cell ``cell``: :func:`kernel_records`, or the reference
    simulator (``rocking_vectorised.simulate_records`` of the file ``reference``, the
    checkout's tests/rocking_vectorised.py) at ``g = sigma_p = 1``."""
    if COVERAGE_CASES[cell][0] == "kernel":
        return kernel_records
    import functools
    from pathlib import Path

    reference_dir = Path(reference).resolve().parent
    if str(reference_dir) not in sys.path:
        sys.path.insert(0, str(reference_dir))
    import rocking_vectorised

    return functools.partial(rocking_vectorised.simulate_records, g=1.0, sigma_p=1.0)


_NUMBER = re.compile(r"[-+]?\d[\d.,]*(?:e[-+]?\d+)?")


def _kind(sentence: str, clause: bool) -> str:
    """A warning or reason without its numbers (``#``) and record names: what the counts of
    :func:`summary` group by; cut at 80 characters, or at its first colon (``clause``: a
    reason's details differ from record to record)."""
    text = _NUMBER.sub("#", sentence).replace("record #: ", "")
    return (text.split(":")[0] if clause else text)[:80].strip()


def _counts(sentences, n: int, clause: bool = False) -> str:
    """``"12 % <kind>; 3 % <kind>"``: how often each kind (:func:`_kind`) occurs among ``n`` records."""
    counter = Counter(_kind(s, clause) for s in sentences if s)
    return "; ".join(f"{100 * c / n:.0f} % {k}" for k, c in counter.most_common())


def _coverage(e: float, low, high) -> float:
    """Share of records whose interval holds ``e``; NaN ends (a null) count as not covered."""
    low, high = np.asarray(low, dtype=float), np.asarray(high, dtype=float)
    return float(np.mean((low <= e) & (e <= high)))


def _answered(e: float, low, high) -> tuple[float, float, int]:
    """Coverage of ``e`` among the records answered (finite ends), its binomial standard
    error and the number answered; NaN coverage and error when none is."""
    low, high = np.asarray(low, dtype=float), np.asarray(high, dtype=float)
    ok = np.isfinite(low) & np.isfinite(high)
    n = int(ok.sum())
    if n == 0:
        return math.nan, math.nan, 0
    cov = _coverage(e, low[ok], high[ok])
    return cov, math.sqrt(cov * (1 - cov) / n), n


def _median(values) -> float:
    """Median of the finite ``values``; NaN when there is none."""
    values = np.asarray(values, dtype=float)
    return float(np.median(values[np.isfinite(values)])) if np.isfinite(values).any() else math.nan


def sharpness(e: float, values, widths, robust: bool = False) -> float:
    """Median of the finite ``widths`` over ``2 x 1.96`` times the spread of the finite
    ``values`` about the true ``e``: 1 for a 95 % interval exactly as wide as a normal
    scatter of the reported ``e`` about the truth needs. The spread is the root mean square
    of ``value - e`` (a bias widens it), the target's measure; ``robust``: the median of
    ``|value - e|`` over its normal value :data:`MAD_NORMAL`, read as the width is, which a
    few records reported by a much wider estimator (far off, their own intervals holding
    them) do not move, but which heavy tails lower. NaN with fewer than two values or none
    off the truth.

    Parameters
    ----------
    e : float
        True value.
    values : array_like
        Reported values (NaN: none).
    widths : array_like
        Widths of their intervals (NaN: none).
    robust : bool, optional
        Read the spread by the median distance from ``e`` instead of the root mean square.

    Returns
    -------
    float
        The ratio (judged against :data:`SHARPNESS_BAND`).

    Examples
    --------
    A scatter of 0.01 about the truth each way, intervals twice 3.92 times 0.01:

    >>> round(sharpness(0.5, [0.49, 0.51], [4 * 1.959963984540054 * 0.01] * 2), 6)
    2.0
    >>> round(sharpness(0.5, [0.49, 0.51], [4 * 1.959963984540054 * 0.01] * 2, robust=True) / MAD_NORMAL, 6)
    2.0
    """
    values = np.asarray(values, dtype=float)
    values = values[np.isfinite(values)]
    if values.size < 2 or not np.any(values != e):
        return math.nan
    spread = float(np.median(np.abs(values - e))) / MAD_NORMAL if robust else float(np.sqrt(np.mean((values - e) ** 2)))
    return _median(widths) / (2.0 * Z95 * spread)


def in_sharpness_band(ratio):
    """Whether ``ratio`` (:func:`sharpness`, a number or an array) lies inside :data:`SHARPNESS_BAND`."""
    return (SHARPNESS_BAND[0] <= ratio) & (ratio <= SHARPNESS_BAND[1])


def summary(ds: xr.Dataset) -> dict:
    """One row of the study's table for the cell ``ds`` (:func:`run_cell`): ``coverage`` over
    every record (a null counted as not covered) and, apart, ``declined`` (the share of
    records with a null ``e``) and ``answered_coverage`` with its binomial standard error
    over the ``answered`` records, by which ``in_band`` judges the cell (a cell declined
    whole is not in the band); ``sharpness``, the median width over 3.92 times the spread
    of the reported ``e`` about the truth (:func:`sharpness`), by which ``sharp`` judges it
    (:data:`SHARPNESS_BAND`), and beside it ``sharpness_robust`` (its spread read by the
    median distance from the truth)."""
    e = ds.attrs["e_true"]
    n = ds.sizes["record"]
    values = ds["e_hat"].values
    ok = np.isfinite(values)
    cov = _coverage(e, ds["low"].values, ds["high"].values)
    bias = float(np.mean(values[ok]) - e) if ok.any() else math.nan
    sd = float(np.std(values[ok], ddof=1)) if ok.sum() > 1 else math.nan
    paper_ok = np.isfinite(ds["paper_e"].values)
    answered, answered_se, n_answered = _answered(e, ds["low"].values, ds["high"].values)
    row = {
        "simulator": ds.attrs["simulator"],
        "condition": ds.attrs["condition"],
        "noise": ds.attrs["noise"],
        "corner": ds.attrs["corner"],
        "e_true": e,
        "records": n,
        "coverage": cov,
        "coverage_se": math.sqrt(max(cov * (1 - cov), 0.0) / n),
        "answered": n_answered,
        "answered_coverage": answered,
        "answered_coverage_se": answered_se,
        "declined": 1.0 - n_answered / n,
        "bias": bias,
        "sd": sd,
        "bias_over_sd": bias / sd if sd > 0 else math.nan,
        "median_width": _median(ds["high"].values - ds["low"].values),
        "sharpness": sharpness(e, values, ds["high"].values - ds["low"].values),
        "sharpness_robust": sharpness(e, values, ds["high"].values - ds["low"].values, robust=True),
        "kurtosis": kurtosis_about(e, values),
        "nulls": int((~ok).sum()),
        "null_reasons": _counts(ds["reason"].values[~ok], n, clause=True),
        "estimators": "; ".join(f"{k} {v}" for k, v in Counter(s for s in ds["reported_by"].values if s).most_common()),
        "warnings": _counts([w for ws in ds["warnings"].values for w in set(str(ws).split(" | "))], n),
        **{f"coverage_{name}": _coverage(e, ds["est_low"].sel(estimator=name).values, ds["est_high"].sel(estimator=name).values)
           for name in ds["estimator"].values},
        "paper_coverage": _coverage(e, ds["paper_low"].values, ds["paper_high"].values),
        "paper_bias": float(np.mean(ds["paper_e"].values[paper_ok]) - e) if paper_ok.any() else math.nan,
        "paper_median_width": _median(ds["paper_high"].values - ds["paper_low"].values),
        "paper_nulls": int((~paper_ok).sum()),
        "ppc_true": float(np.median(ds["ppc_true"].values)),
        "corner_true": float(np.median(ds["corner_true"].values)),
        "ppc_read": _median(ds["ppc_read"].values),
        "noise_read": _median(ds["noise_read"].values),
        "corner_read": _median(ds["corner_read"].values),
        "noisy": float(np.mean(ds["noisy"].values)),
        "coloured": float(np.mean(ds["coloured"].values)),
        "calibrations": len({c for c in ds["calibration"].values if c}),
    }
    row["in_band"] = bool(in_band(answered))
    row["sharp"] = bool(in_sharpness_band(row["sharpness"]))
    row["bias_ok"] = bool(abs(row["bias_over_sd"]) <= BIAS_RATIO)
    return row


def table(datasets) -> pd.DataFrame:
    """The study's table: one :func:`summary` row per cell, in the order of
    :data:`rockdec.pipeline.layout.COVERAGE_CONDITIONS`, e and simulator."""
    out = pd.DataFrame([summary(ds) for ds in datasets])
    order = {name: i for i, name in enumerate(COVERAGE_CONDITIONS)}
    sims = {name: i for i, name in enumerate(COVERAGE_SIMULATORS)}
    out["_c"], out["_s"] = out["condition"].map(order), out["simulator"].map(sims)
    return out.sort_values(["_s", "_c", "e_true"]).drop(columns=["_c", "_s"]).reset_index(drop=True)


def in_band(coverage):
    """Whether ``coverage`` (a share, or an array of them) lies inside :data:`COVERAGE_BAND`."""
    return (COVERAGE_BAND[0] <= coverage) & (coverage <= COVERAGE_BAND[1])


def band_probability(n: int, p: float = NOMINAL) -> float:
    """Probability that ``n`` records whose intervals each hold ``e`` with probability ``p``
    give a coverage :func:`in_band` (binomial)."""
    covered = np.arange(n + 1)
    return float(stats.binom.pmf(covered, n, p)[in_band(covered / n)].sum())


def sharpness_probability(n: int, kurtosis: float = 3.0) -> float:
    """Probability that a cell of ``n`` answered records gives a sharpness
    (:func:`sharpness`) inside :data:`SHARPNESS_BAND` when its intervals are exactly 3.92
    times the spread of the reported ``e`` about the truth (unbiased), from the sampling error
    of that spread alone. The mean square of ``n`` distances from the truth whose
    distribution has ``kurtosis`` (3: normal) has a relative variance ``(kurtosis - 1) / n``;
    it is read as ``chi2_nu / nu`` with ``nu = 2 n / (kurtosis - 1)`` (exact for normal
    distances, ``nu = n``; within a few per cent of simulation for kurtosis up to about 6),
    so the ratio lies inside when ``chi2_nu`` lies between ``nu / 1.15^2`` and ``nu / 0.9^2``.
    Heavy tails (a few records reported far off by a much wider estimator) make the spread
    of a cell less certain and a ratio outside the band likelier. The widths' median is
    taken as known (its own scatter only adds to the chance of straying). NaN below two
    records.

    Examples
    --------
    >>> sharpness_probability(1000) > sharpness_probability(200) > sharpness_probability(100)
    True
    >>> sharpness_probability(200, kurtosis=6.0) < sharpness_probability(200)
    True
    """
    if n < 2:
        return math.nan
    nu = 2.0 * n / (max(float(kurtosis), 1.0 + 1e-9) - 1.0) if np.isfinite(kurtosis) else float(n)
    low, high = SHARPNESS_BAND
    return float(stats.chi2.cdf(nu / low**2, nu) - stats.chi2.cdf(nu / high**2, nu))


def kurtosis_about(e: float, values) -> float:
    """``mean(r^4) / mean(r^2)^2`` of the finite ``values`` about ``e`` (``r = value - e``): 3
    for a normal scatter about the truth, more for heavy tails; NaN below two values or none
    off ``e``.

    Examples
    --------
    >>> round(kurtosis_about(0.0, [-1.0, 1.0, -1.0, 1.0]), 6)
    1.0
    """
    r = np.asarray(values, dtype=float)
    r = r[np.isfinite(r)] - e
    m2 = float(np.mean(r**2)) if r.size > 1 else 0.0
    return float(np.mean(r**4)) / m2**2 if m2 > 0.0 else math.nan


def band_chance(tab: pd.DataFrame) -> dict:
    """Whether the cells of ``tab`` (:func:`table`) stray from :data:`NOMINAL` more than
    chance: over the cells answered on at least :data:`BAND_MIN_ANSWERED` records, the number
    outside :data:`COVERAGE_BAND`, the number a calibrated interval leaves outside on average
    (each cell's :func:`band_probability` at its own answered count) and the probability of
    at least as many (their sum's exact distribution, a Poisson binomial); and the dispersion
    ``chi2 = sum((k - p n)^2 / (n p (1 - p)))`` of the covered counts ``k`` about ``p n``
    with its ratio to the cells' number and its upper-tail probability (``chi2`` with one
    degree of freedom per cell: a calibrated interval gives a ratio near 1); the cells
    below :data:`CELL_FLOOR` among those answered on :data:`FLOOR_ANSWERED` records or more,
    the cells whose sharpness lies outside :data:`SHARPNESS_BAND` (``unsharp``, and
    ``too_narrow`` of them below it; a table without the column counts none) with the
    number an interval exactly as wide as the scatter leaves outside on average from the
    spread's sampling error alone (``expected_unsharp``, each cell's
    :func:`sharpness_probability` at its answered count and its ``kurtosis``, 3 where the
    table has none) and the probability of at least as many
    (``p_unsharp``), and whether the whole target holds (``meets``: the module's target
    constants)."""
    used = tab[tab["answered"] >= BAND_MIN_ANSWERED]
    n = used["answered"].to_numpy(dtype=int)
    k = np.rint(used["answered_coverage"].to_numpy() * n)
    inside = np.array([band_probability(int(m)) for m in n])
    count = _outside_count(inside)
    out = int((~used["in_band"]).sum())
    chi2 = float(np.sum((k - NOMINAL * n) ** 2 / (n * NOMINAL * (1.0 - NOMINAL))))
    cells = len(used)
    ratio = used["sharpness"].to_numpy(dtype=float) if "sharpness" in used else np.full(cells, np.nan)
    known = np.isfinite(ratio)
    kurt = used["kurtosis"].to_numpy(dtype=float) if "kurtosis" in used else np.full(cells, 3.0)
    sharp_inside = np.array([sharpness_probability(int(m), k) for m, k in zip(n[known], kurt[known])])
    unsharp = int((known & ~in_sharpness_band(ratio)).sum())
    chance = {
        "cells": cells, "outside": out, "expected_outside": float(np.sum(1.0 - inside)),
        "p_outside": float(count[out:].sum()), "p_all_inside": float(count[0]),
        "pooled_coverage": float(k.sum() / n.sum()) if cells else math.nan,
        "chi2_ratio": chi2 / cells if cells else math.nan,
        "p_chi2": float(stats.chi2.sf(chi2, cells)) if cells else math.nan,
        "below_floor": int((used[used["answered"] >= FLOOR_ANSWERED]["answered_coverage"] < CELL_FLOOR).sum()),
        "sharpness_cells": int(known.sum()),
        "unsharp": unsharp,
        "expected_unsharp": float(np.sum(1.0 - sharp_inside)),
        "p_unsharp": float(_outside_count(sharp_inside)[unsharp:].sum()),
        "too_narrow": int((known & (ratio < SHARPNESS_BAND[0])).sum()),
        "few": int(((tab["answered"] > 0) & (tab["answered"] < BAND_MIN_ANSWERED)).sum()),
        "declined_whole": int((tab["answered"] == 0).sum()),
    }
    chance["meets"] = bool(cells and POOLED_BAND[0] <= chance["pooled_coverage"] <= POOLED_BAND[1]
                           and chance["chi2_ratio"] <= DISPERSION_MAX and chance["p_outside"] >= P_OUTSIDE_MIN
                           and chance["below_floor"] == 0 and chance["unsharp"] == 0)
    return chance


def _outside_count(inside: np.ndarray) -> np.ndarray:
    """Distribution of the number of cells outside a band, cell ``i`` inside it with
    probability ``inside[i]`` (a Poisson binomial): entry ``k`` is the probability of ``k``."""
    count = np.array([1.0])
    for q in inside:
        count = np.convolve(count, [q, 1.0 - q])
    return count


def markdown(tab: pd.DataFrame) -> str:
    """The table as Markdown: the share of records declined (``e`` null), the coverage of
    the reported interval on the records answered (its binomial standard error; bold
    outside :data:`COVERAGE_BAND`, ``-`` when every record is declined), corrected bias and
    sd, median width and its sharpness (:func:`sharpness`; bold outside
    :data:`SHARPNESS_BAND`; the robust reading beside it), the paper model's width and coverage (every record, a null counted
    as not covered), and the records' samples per cycle, corner and noise (true, and as the
    tool read them); the warnings and null reasons of each cell below."""
    lines = [
        "| simulator | condition | e | n | declined | coverage of answered | bias | sd | bias/sd | width | width / (3.92 sd) (robust) | "
        "paper-model width | paper-model coverage | samples/cycle (true, read) | corner (true, read) | noise read | noisy, coloured "
        "| reported by |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]

    def num(x, fmt):
        return "-" if not np.isfinite(x) else format(x, fmt)

    for r in tab.itertuples():
        flag = "" if r.in_band else "**"
        covered = "-" if not r.answered else (f"{flag}{100 * r.answered_coverage:.0f} %{flag} (±{100 * r.answered_coverage_se:.0f}, "
                                              f"n = {r.answered})")
        lines.append(
            f"| {r.simulator} | {r.condition} | {r.e_true:g} | {r.records} | {100 * r.declined:.0f} % | {covered} "
            f"| {num(r.bias, '+.4f')} | {num(r.sd, '.4f')} | {num(r.bias_over_sd, '+.2f')} | "
            f"{num(r.median_width, '.4f')} | {_sharp_cell(r.sharpness)} ({num(r.sharpness_robust, '.2f')}) | {num(r.paper_median_width, '.4f')} | {100 * r.paper_coverage:.0f} % | "
            f"{num(r.ppc_true, '.0f')}, {num(r.ppc_read, '.0f')} | {num(r.corner_true, '.2f')}, {num(r.corner_read, '.2f')} | "
            f"{num(r.noise_read, '.3f')} | {100 * r.noisy:.0f} %, {100 * r.coloured:.0f} % | {r.estimators or '-'} |"
        )
    notes = [f"- {r.simulator} {r.condition} e = {r.e_true:g}: warnings: {r.warnings or 'none'}"
             + (f"; nulls: {r.null_reasons}" if r.nulls else "") for r in tab.itertuples() if r.warnings or r.nulls]
    return "\n".join(lines) + "\n\n" + band_markdown(band_chance(tab)) + "\n\n" + "\n".join(notes) + "\n"


def _sharp_cell(ratio: float, bold: bool = True) -> str:
    """A sharpness in a table: two decimals, bold outside :data:`SHARPNESS_BAND` (``bold``), ``-`` when unknown."""
    if not np.isfinite(ratio):
        return "-"
    flag = "**" if bold and not in_sharpness_band(ratio) else ""
    return f"{flag}{ratio:.2f}{flag}"


def band_markdown(chance: dict) -> str:
    """:func:`band_chance` in one paragraph, closed by the target it is judged by and whether it holds."""
    return (f"Cells answered on at least {BAND_MIN_ANSWERED} records: {chance['cells']}, pooled coverage "
            f"{100 * chance['pooled_coverage']:.1f} %; outside {100 * COVERAGE_BAND[0]:.0f}-{100 * COVERAGE_BAND[1]:.0f} %: "
            f"{chance['outside']}, where an interval that holds e {100 * NOMINAL:.0f} % of the time leaves "
            f"{chance['expected_outside']:.1f} outside on average, {chance['outside']} or more with probability "
            f"{chance['p_outside']:.2g}, none with probability {chance['p_all_inside']:.2f}; the covered counts' dispersion "
            f"about {100 * NOMINAL:.0f} % is {chance['chi2_ratio']:.2f} times the binomial (chi2 upper tail "
            f"{chance['p_chi2']:.2g}). Cells answered on 1-{BAND_MIN_ANSWERED - 1} records: {chance['few']}; "
            f"declined whole: {chance['declined_whole']}. Cells below {100 * CELL_FLOOR:.0f} % on {FLOOR_ANSWERED} records or "
            f"more: {chance['below_floor']}; width / (3.92 sd) outside {SHARPNESS_BAND[0]:g}-{SHARPNESS_BAND[1]:g}: "
            f"{chance['unsharp']} of {chance['sharpness_cells']} ({chance['too_narrow']} too narrow), where intervals exactly "
            f"as wide as the scatter leave {chance['expected_unsharp']:.1f} outside on average from the spread's sampling "
            f"error alone (at each cell's kurtosis), {chance['unsharp']} or more with probability {chance['p_unsharp']:.2g}. Target (pooled "
            f"{100 * POOLED_BAND[0]:.0f}-{100 * POOLED_BAND[1]:.0f} %, dispersion at most {DISPERSION_MAX:g}, out-of-band "
            f"probability at least {P_OUTSIDE_MIN:g}, no cell below {100 * CELL_FLOOR:.0f} %, every cell's width / (3.92 sd) "
            f"inside {SHARPNESS_BAND[0]:g}-{SHARPNESS_BAND[1]:g}): {'met' if chance['meets'] else 'not met'}.")

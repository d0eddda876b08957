"""The coverage study (rockdec.studies.coverage) on tiny cells, and its second simulator
(tests/rocking_vectorised.py) against the pure-Python reference flight."""

import functools
import math

import numpy as np
import pandas as pd
import pytest
import xarray as xr

import fake_calibration
import rocking_vectorised
from rocking_reference import flight_reference
from rockdec.studies import coverage
from rockdec.rdd import registry
from rockdec.pipeline.layout import COVERAGE_CASES, COVERAGE_CONDITIONS
from rockdec.physics.record_model import PAPER

REFERENCE = functools.partial(rocking_vectorised.simulate_records, g=1.0, sigma_p=1.0)


@pytest.mark.parametrize("e", [0.0, 0.5, 0.9, 1.0])
def test_vectorised_flight_matches_the_reference_impact_by_impact(e):
    rng = np.random.default_rng(4)
    theta, omega = rng.normal(size=400) * 0.01, rng.normal(size=400) * 0.1
    theta[:60] = 0.0  # at the pivot, moving or at rest
    omega[:20] = 0.0
    got_theta, got_omega = rocking_vectorised.flight(theta, omega, 0.05, 1.3, e)
    want = np.array([flight_reference(t, w, 0.05, 1.3, e) for t, w in zip(theta, omega)])
    np.testing.assert_allclose(got_theta, want[:, 0], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(got_omega, want[:, 1], rtol=1e-12, atol=1e-15)


def test_vectorised_records_depend_on_their_own_seed_only():
    kw = dict(dt=0.3, e=0.9, burn_in=50, pole=0.8, noise=0.02)
    together = REFERENCE([5, 6, 7], 3000, **kw)
    alone = REFERENCE([6], 3000, **kw)
    np.testing.assert_array_equal(together[1], alone[0])
    assert not np.array_equal(together[0], together[2])


def test_vectorised_records_without_load_stay_at_rest():
    theta = rocking_vectorised.simulate_records([1, 2], 500, dt=0.1, g=1.0, e=0.8, sigma_p=0.0, burn_in=10)
    assert not theta.any()


def test_stage_places_white_records_at_75_samples_per_cycle():
    staged = coverage.stage(0.9, 20_000, None, coverage.STUDY_SEED_OFFSET - 10**6)
    assert abs(math.log(staged["points_per_cycle"] / coverage.POINTS_PER_CYCLE)) < coverage.STAGE_TOLERANCE
    assert staged["pole"] == 0.0


@pytest.fixture(scope="module")
def calibrations(tmp_path_factory):
    """One calibration folder for the module, shared as the study's cells share it
    (:func:`rockdec.studies.coverage.run_cell`): a calibration is built once per key."""
    return tmp_path_factory.mktemp("coverage-cal")


@pytest.fixture(scope="module")
def tiny_table(tmp_path_factory):
    """Two records of 20,000 samples in a cell of each class: clean (on the reference
    simulator's records), sensor noise, and colour with noise. The tests of the table read
    its bookkeeping (columns, intervals, nulls and their reasons, the declined share, the
    staged corner), not the calibration's numbers: the calibration's grid points are
    tests/fake_calibration.py's (in a folder of their own), whose intervals
    test_reduced_coverage_holds and the workflow's coverage study measure for real."""
    from rockdec.calibrate import calibration

    cells = ["reference_clean_e0.9", "kernel_noise3_e0.9", "kernel_corner1_noise2_e0.9"]
    folder = tmp_path_factory.mktemp("coverage-fake-cal")
    with pytest.MonkeyPatch.context() as monkeypatch:
        monkeypatch.setattr(calibration, "_grid_point", fake_calibration.grid_point)
        datasets = [coverage.run_cell(c, 2, 20_000, folder, simulate=REFERENCE if c.startswith("reference") else coverage.kernel_records)
                    for c in cells]
    return datasets, coverage.table(datasets)


@pytest.mark.slow
def test_tiny_study_table_has_its_columns_and_invariants(tiny_table):
    datasets, table = tiny_table
    need = {"simulator", "condition", "e_true", "records", "coverage", "bias", "sd", "median_width", "nulls", "null_reasons",
            "estimators", "warnings", "paper_coverage", "paper_median_width", "ppc_true", "corner_true", "ppc_read",
            *(f"coverage_{name}" for name in registry.ESTIMATORS)}
    assert need <= set(table.columns)
    assert len(table) == len(datasets)
    for column in ["coverage", "paper_coverage", *(f"coverage_{name}" for name in registry.ESTIMATORS)]:
        assert ((table[column] >= 0.0) & (table[column] <= 1.0)).all()
    assert (table["nulls"] <= table["records"]).all()
    for ds in datasets:
        e_hat, low, high = ds["e_hat"].values, ds["low"].values, ds["high"].values
        ok = np.isfinite(e_hat)
        assert np.all((low[ok] <= e_hat[ok]) & (e_hat[ok] <= high[ok]))
        assert all(reason for reason in ds["reason"].values[~ok])  # a null says why
        assert all(not reason for reason in ds["reason"].values[ok])
    markdown = coverage.markdown(table)
    assert markdown.count("\n| kernel") + markdown.count("\n| reference") == len(table)


@pytest.mark.slow
def test_tiny_study_counts_declined_records_apart(tiny_table):
    """Coverage of the answered records times their number is the coverage of every record
    (a null not covered) times theirs; the declined share is the nulls' share; the table
    shows it and the figure draws a cell of any kind."""
    from rockdec.studies import figures

    datasets, table = tiny_table
    for ds in datasets:
        row = coverage.summary(ds)
        n = ds.sizes["record"]
        answered = np.isfinite(ds["low"].values) & np.isfinite(ds["high"].values)
        assert row["answered"] == answered.sum() and row["declined"] == pytest.approx(1 - answered.sum() / n)
        if answered.any():
            assert row["answered_coverage"] * row["answered"] == pytest.approx(row["coverage"] * n)
            assert 0.0 <= row["answered_coverage_se"] <= 0.5
        else:
            assert math.isnan(row["answered_coverage"]) and not row["in_band"]
    markdown = coverage.markdown(table)
    assert "| declined | coverage of answered |" in markdown
    figures.fig_coverage(table)


@pytest.mark.slow
def test_tiny_study_places_the_corner(tiny_table):
    """The records' own corner, in their own rocking frequencies, is the cell's within the
    spread of two records' sigma_Y (the median of the pilots is placed within 1.5 %)."""
    datasets, _ = tiny_table
    for ds in datasets:
        noise, corner = COVERAGE_CONDITIONS[ds.attrs["condition"]]
        if corner is not None:
            assert np.median(ds["corner_true"].values) == pytest.approx(corner, rel=0.5)
            assert ds.attrs["pilot_points_per_cycle"] == pytest.approx(coverage.POINTS_PER_CYCLE, rel=coverage.STAGE_TOLERANCE * 1.01)


def test_every_cell_names_a_condition_and_a_simulator():
    for simulator, condition, e in COVERAGE_CASES.values():
        assert condition in COVERAGE_CONDITIONS and simulator in ("kernel", "reference") and 0.0 < e < 1.0


@pytest.mark.usefixtures("capped_sets")
@pytest.mark.slow
def test_reduced_coverage_holds(calibrations):
    """40 records of 20,000 samples at e = 0.9: the 95 % interval of e_v covers e >= 85 %
    (on the paper model's calibrations of those records, of the capped calibration's sets per
    ``e``: the study's route is tested here, the number of sets by the coverage study and
    ``benchmarks/calibration_replicates.py``)."""
    ds = coverage.run_cell("kernel_clean_e0.9", 40, 20_000, calibrations, model=PAPER)
    row = coverage.summary(ds)
    assert row["coverage_e_v"] >= 0.85
    assert np.isfinite(ds["est_e"].sel(estimator="e_v").values).all()


@pytest.mark.slow
def test_a_cell_read_again_offline_gives_back_its_intervals(tmp_path):
    """:func:`rockdec.studies.coverage.recorrect`: the stored raw values inverted through the
    stored calibrations by the belt that ran the cell give back every reported ``e`` and
    interval (the offline reading of a belt variant starts from the cell as it ran); a
    belt twice as wide gives intervals that hold the stored ones."""
    from rockdec.calibrate import belt, calibration

    with pytest.MonkeyPatch.context() as monkeypatch:
        monkeypatch.setattr(calibration, "_grid_point", fake_calibration.grid_point)
        ds = coverage.run_cell("kernel_noise3_e0.9", 3, 20_000, tmp_path)
    answered = np.isfinite(ds["e_hat"].values)
    assert answered.any()
    assert np.isfinite(ds["est_raw"].sel(estimator=ds["reported_by"].values[answered][0]).values).all()
    again = coverage.recorrect(ds, tmp_path)
    for name in ("e_hat", "low", "high"):
        np.testing.assert_allclose(again[name].values, ds[name].values, rtol=0, atol=1e-12, equal_nan=True)
    fit = belt.fit
    with pytest.MonkeyPatch.context() as monkeypatch:
        monkeypatch.setattr(belt, "fit", lambda *a, **k: (lambda b: b._replace(spread=2.0 * b.spread))(fit(*a, **k)))
        wide = coverage.recorrect(ds, tmp_path)
    ok = answered & np.isfinite(wide["low"].values)
    assert np.all(wide["low"].values[ok] <= ds["low"].values[ok]) and np.all(wide["high"].values[ok] >= ds["high"].values[ok])


def test_fresh_records_of_a_cell_read_like_its_own(tmp_path):
    """:func:`rockdec.studies.coverage.fresh_coverage` with the cell's own seeds: the same raw
    values as the cell stored (the tool's analysis of the same records), each inverted
    through the calibration its bin used, giving back the cell's intervals where the bin has
    one calibration; other seeds give other records."""
    from rockdec.calibrate import calibration

    with pytest.MonkeyPatch.context() as monkeypatch:
        monkeypatch.setattr(calibration, "_grid_point", fake_calibration.grid_point)
        ds = coverage.run_cell("kernel_clean_e0.9", 3, 20_000, tmp_path)
    own = coverage.fresh_coverage(ds, tmp_path, 3, seed0=ds.attrs["first_seed"])
    same = 0
    for k, row in own.iterrows():
        name = str(ds["reported_by"].values[k])
        if not name:
            continue
        assert row["raw"] == ds["est_raw"].sel(estimator=name).values[k]
        assert row["ppc_read"] == ds["ppc_read"].values[k]
        if row["calibration"] == ds["calibration"].values[k] and row["estimator"] == name:
            np.testing.assert_allclose([row["e"], row["low"], row["high"]], [ds[v].values[k] for v in ("e_hat", "low", "high")], atol=1e-12)
            same += 1
    assert same >= 1
    other = coverage.fresh_coverage(ds, tmp_path, 3)
    assert not np.array_equal(other["raw"].values, own["raw"].values)
    row = coverage.fresh_summary(ds, own)
    assert row["fresh"] == 3 and row["fresh_answered"] == np.isfinite(own["low"]).sum()
    if row["fresh_answered"]:
        assert row["fresh_coverage"] * row["fresh_answered"] == pytest.approx(row["fresh_coverage_all"] * row["fresh"])
        assert row["fresh_coverage"] == pytest.approx(row["main_share"] * row["main_coverage"]
                                                      + (1 - row["main_share"]) * np.nan_to_num(row["other_coverage"]))
    assert "kernel_clean_e0.9" in coverage.fresh_markdown(pd.DataFrame([row]))


def _table_of_counts(answered, covered):
    """A study table holding only what band_chance reads."""
    answered, covered = np.asarray(answered), np.asarray(covered)
    cov = np.where(answered > 0, covered / np.maximum(answered, 1), np.nan)
    return pd.DataFrame({"answered": answered, "answered_coverage": cov,
                         "in_band": coverage.in_band(cov)})


@pytest.mark.parametrize("n", [1, 20, 50, 200])
def test_band_probability_sums_the_binomial_inside_the_band(n):
    """Against the binomial summed term by term with exact integers."""
    inside = [k for k in range(n + 1) if coverage.COVERAGE_BAND[0] <= k / n <= coverage.COVERAGE_BAND[1]]
    direct = sum(math.comb(n, k) * 0.95**k * 0.05 ** (n - k) for k in inside)
    assert coverage.band_probability(n) == pytest.approx(direct, rel=1e-9, abs=1e-15)


def test_band_chance_of_equal_cells_is_a_binomial_count():
    """Cells of one size: the number outside the band is binomial over the cells (closed
    form), and a cell answered on too few records is counted apart."""
    from scipy import stats

    n, cells = 200, 12
    answered = [n] * cells + [10, 0]
    covered = [190] * (cells - 2) + [180, 199] + [10, 0]
    chance = coverage.band_chance(_table_of_counts(answered, covered))
    q = 1.0 - coverage.band_probability(n)
    assert chance["cells"] == cells and chance["outside"] == 2 and chance["few"] == 1 and chance["declined_whole"] == 1
    assert chance["expected_outside"] == pytest.approx(cells * q)
    assert chance["p_outside"] == pytest.approx(stats.binom.sf(1, cells, q))
    assert chance["p_all_inside"] == pytest.approx((1.0 - q) ** cells)
    assert chance["pooled_coverage"] == pytest.approx((190 * 10 + 180 + 199) / (n * cells))


@pytest.mark.parametrize("n", [100, 200])
def test_sharpness_probability_is_what_exact_intervals_show_on_normal_records(n):
    """Against simulation: cells of ``n`` normal values about the truth, every interval
    exactly 3.92 sd wide, read by :func:`rockdec.studies.coverage.sharpness`; the share of
    cells inside the band matches the closed form within four Monte Carlo errors."""
    rng = np.random.default_rng(n)
    cells, e, sd = 4000, 0.9, 0.01
    widths = np.full(n, 2 * 1.959963984540054 * sd)
    ratios = np.array([coverage.sharpness(e, e + sd * rng.standard_normal(n), widths) for _ in range(cells)])
    p = coverage.sharpness_probability(n)
    assert 0.8 < p < 1.0
    assert np.mean(coverage.in_sharpness_band(ratios)) == pytest.approx(p, abs=4 * math.sqrt(p * (1 - p) / cells))


def test_sharpness_probability_at_a_kurtosis_is_what_heavy_tailed_records_show():
    """Against simulation: cells of 200 values scattered about the truth as Student's t
    with 8 degrees of freedom (kurtosis 4.5), every interval exactly 3.92 sd wide: the share
    of cells inside the band matches the closed form at that kurtosis within four Monte Carlo
    errors, and lies below the normal records' share; at kurtosis 3 the closed form is the
    normal one. The kurtosis read about the truth is the distribution's within 0.3 on
    20,000 values of a Laplace scatter (kurtosis 6; every moment finite, so its reading
    settles)."""
    rng = np.random.default_rng(21)
    n, cells, e, sd, df = 200, 4000, 0.9, 0.01, 8
    scale = sd / math.sqrt(df / (df - 2))
    widths = np.full(n, 2 * 1.959963984540054 * sd)
    ratios = np.array([coverage.sharpness(e, e + scale * rng.standard_t(df, n), widths) for _ in range(cells)])
    kurt = 3.0 + 6.0 / (df - 4)
    p = coverage.sharpness_probability(n, kurt)
    assert p < coverage.sharpness_probability(n) == coverage.sharpness_probability(n, 3.0)
    assert np.mean(coverage.in_sharpness_band(ratios)) == pytest.approx(p, abs=4 * math.sqrt(p * (1 - p) / cells))
    assert coverage.kurtosis_about(e, e + rng.laplace(0.0, sd, 20_000)) == pytest.approx(6.0, abs=0.3)


def test_band_chance_reads_the_sharpness_against_chance():
    """Equal cells: the number outside the sharpness band is binomial over the cells at one
    minus :func:`rockdec.studies.coverage.sharpness_probability` (closed form)."""
    from scipy import stats

    n, cells = 100, 20
    tab = _table_of_counts([n] * cells, [95] * cells).assign(sharpness=np.r_[0.85, 1.2, 1.3, np.ones(cells - 3)])
    chance = coverage.band_chance(tab)
    q = 1.0 - coverage.sharpness_probability(n)
    assert chance["unsharp"] == 3 and chance["too_narrow"] == 1
    assert chance["expected_unsharp"] == pytest.approx(cells * q)
    assert chance["p_unsharp"] == pytest.approx(stats.binom.sf(2, cells, q))
    assert "sampling error alone" in coverage.band_markdown(chance)


def test_band_chance_tells_a_calibrated_interval_from_an_overdispersed_one():
    """Counts drawn binomial at 95 % read a dispersion near 1; counts whose cells hold e
    90 % or 99 % of the time (the same 94.5 % pooled), well above it."""
    rng = np.random.default_rng(7)
    n = np.full(400, 200)
    calibrated = coverage.band_chance(_table_of_counts(n, rng.binomial(n, 0.95)))
    assert 0.85 < calibrated["chi2_ratio"] < 1.15 and calibrated["p_chi2"] > 0.01
    assert abs(calibrated["outside"] - calibrated["expected_outside"]) < 4 * math.sqrt(calibrated["expected_outside"])
    spread = coverage.band_chance(_table_of_counts(n, rng.binomial(n, np.where(np.arange(400) % 2, 0.90, 0.99))))
    assert spread["chi2_ratio"] > 2.0 and spread["p_chi2"] < 1e-6 and spread["p_outside"] < 1e-6


def _synthetic_cell(e, values, widths, cell="kernel_noise3_e0.95"):
    """A cell (as :func:`rockdec.studies.coverage.run_cell` returns it) whose reported values
    and interval widths are given, every interval centred on its value; the rest filler."""
    values, widths = np.asarray(values, float), np.asarray(widths, float)
    n, names = len(values), list(registry.ESTIMATORS)
    rec, rest = ("record",), ("record", "estimator")
    text = np.array([""] * n, dtype=object).astype(str)
    low, high = values - widths / 2, values + widths / 2
    simulator, condition, _ = COVERAGE_CASES[cell]
    ds = xr.Dataset(
        {"e_hat": (rec, values), "low": (rec, low), "high": (rec, high), "reason": (rec, text),
         "reported_by": (rec, np.array(["e_0"] * n, dtype=object).astype(str)), "warnings": (rec, text),
         "calibration": (rec, np.array(["cal.nc"] * n, dtype=object).astype(str)),
         "paper_e": (rec, values), "paper_low": (rec, low), "paper_high": (rec, high),
         "est_low": (rest, np.repeat(low[:, None], len(names), 1)), "est_high": (rest, np.repeat(high[:, None], len(names), 1)),
         **{v: (rec, np.full(n, 75.0)) for v in ("ppc_true", "ppc_read")},
         **{v: (rec, np.full(n, np.nan)) for v in ("corner_true", "corner_read", "noise_read")},
         "noisy": (rec, np.ones(n, bool)), "coloured": (rec, np.zeros(n, bool))},
        coords={"record": np.arange(n), "estimator": names},
        attrs={"cell": cell, "simulator": simulator, "condition": condition, "e_true": e, "noise": 0.03, "corner": np.nan},
    )
    return ds


def _standard(n):
    """``n`` normal quantiles, symmetric about 0 (mean 0), scaled to a root mean square of 1
    exactly (a scatter of sd 1 about the truth as :func:`rockdec.studies.coverage.sharpness` reads it)."""
    from scipy import stats

    z = stats.norm.ppf((np.arange(n) + 0.5) / n)
    return z / np.sqrt(np.mean(z**2))


@pytest.mark.parametrize("ratio", [0.8, 1.0, 1.3])
def test_sharpness_of_a_cell_of_known_spread_and_width(ratio):
    """Reported values scattered about the truth with sd ``sd`` exactly and intervals all
    ``ratio x 3.92 sd`` wide read ``ratio`` (the robust reading too, within the quantiles'
    departure from a normal's median); the cell is sharp only inside 0.9-1.15, and the table
    marks it bold outside."""
    e, sd, n = 0.95, 0.004, 200
    ds = _synthetic_cell(e, e + sd * _standard(n), np.full(n, ratio * 2 * 1.959963984540054 * sd))
    row = coverage.summary(ds)
    assert row["sharpness"] == pytest.approx(ratio, rel=1e-12)
    assert row["sharpness_robust"] == pytest.approx(ratio, rel=0.02)
    assert row["sharp"] == (coverage.SHARPNESS_BAND[0] <= ratio <= coverage.SHARPNESS_BAND[1])
    markdown = coverage.markdown(coverage.table([ds]))
    assert (f"**{ratio:.2f}**" in markdown) == (not row["sharp"])
    assert "width / (3.92 sd)" in markdown


def test_sharpness_measures_the_scatter_about_the_truth_not_the_mean():
    """Values all off the truth on one side: their scatter about their own mean is a third
    of their distance from the truth, the ratio reads the distance (root mean square, or
    median); widths are read by their median (the widest half can be anything)."""
    e, n = 0.9, 101
    values = e + np.r_[np.full(50, 0.01), np.full(51, 0.03)]
    widths = np.full(n, 0.05)
    widths[: n // 2] = np.linspace(0.06, 9.0, n // 2)
    rms = math.sqrt((50 * 0.01**2 + 51 * 0.03**2) / n)
    assert coverage.sharpness(e, values, widths) == pytest.approx(0.05 / (2 * 1.959963984540054 * rms), rel=1e-12)
    robust = coverage.sharpness(e, values, widths, robust=True)
    assert robust == pytest.approx(0.05 * coverage.MAD_NORMAL / (2 * 1.959963984540054 * 0.03), rel=1e-12)
    assert math.isnan(coverage.sharpness(e, [e, np.nan], [0.1, 0.1]))  # one value: no scatter to read


def test_a_few_wild_records_move_the_sd_reading_not_the_robust_one():
    """Five of 200 records reported by an estimator far wider, far off but covered: the
    root mean square reads the cell much too narrow, the median distance moves by a few per
    cent."""
    e, sd, n = 0.98, 0.005, 200
    values, widths = e + sd * _standard(n), np.full(n, 2 * 1.959963984540054 * sd)
    clean = coverage.summary(_synthetic_cell(e, values, widths))
    values[::40], widths[::40] = e - 0.1, 0.3
    wild = coverage.summary(_synthetic_cell(e, values, widths))
    assert clean["sharpness"] == pytest.approx(1.0, rel=1e-12) and wild["sharpness"] < 0.5
    assert wild["sharpness_robust"] == pytest.approx(clean["sharpness_robust"], rel=0.05)


def test_band_chance_reads_the_target():
    """Cells at 95 % on 200 records, each as wide as its scatter, meet the target; one cell
    too narrow (0.8) or one below 90 % does not, and each is counted."""
    n = np.full(10, 200)
    good = _table_of_counts(n, np.full(10, 190)).assign(sharpness=1.0)
    chance = coverage.band_chance(good)
    assert chance["meets"] and chance["unsharp"] == 0 and chance["below_floor"] == 0 and chance["sharpness_cells"] == 10
    narrow = good.assign(sharpness=np.r_[0.8, np.ones(9)])
    chance = coverage.band_chance(narrow)
    assert not chance["meets"] and chance["unsharp"] == 1 and chance["too_narrow"] == 1
    low = _table_of_counts(n, np.r_[176, np.full(9, 191)]).assign(sharpness=1.0)
    chance = coverage.band_chance(low)
    assert not chance["meets"] and chance["below_floor"] == 1
    assert "not met" in coverage.band_markdown(chance) and "Target" in coverage.band_markdown(coverage.band_chance(good))


def test_fresh_records_are_judged_per_calibration():
    """Two calibrations of one cell, on fresh records of known coverage and sharpness each:
    one row per calibration with its own numbers; the table reads the cells on their own and
    on fresh records against chance, and lists each calibration."""
    e, sd, n = 0.95, 0.004, 100
    z = _standard(n)
    unit = 2 * 1.959963984540054 * sd
    rows = []
    for file, ratio in (("a.nc", 1.0), ("b.nc", 0.7)):
        values, width = e + sd * z, ratio * unit
        rows += [{"ppc_read": 75.0, "bin": 75.0, "calibration": file, "estimator": "e_0", "raw": v, "e": v,
                  "low": v - width / 2, "high": v + width / 2, "covered": bool(abs(v - e) <= width / 2)} for v in values]
    fresh = pd.DataFrame(rows)
    ds = _synthetic_cell(e, e + sd * _standard(40), np.full(40, unit))
    ds["calibration"].values[:] = np.where(np.arange(40) < 30, "a.nc", "b.nc")
    by = coverage.fresh_calibrations(ds, fresh).set_index("calibration")
    assert list(by.index) == ["a.nc", "b.nc"] and list(by["records"]) == [30, 10] and list(by["fresh_answered"]) == [n, n]
    for file, ratio in (("a.nc", 1.0), ("b.nc", 0.7)):
        assert by.loc[file, "fresh_sharpness"] == pytest.approx(ratio, rel=1e-12)
        assert by.loc[file, "fresh_coverage"] == pytest.approx(np.mean(np.abs(z) <= ratio * 1.959963984540054))
    assert by.loc["a.nc", "sharp"] and not by.loc["b.nc", "sharp"]
    row = coverage.fresh_summary(ds, fresh)
    assert row["sharpness"] == pytest.approx(1.0) and row["fresh_sharpness"] == pytest.approx(0.85, rel=1e-12)
    markdown = coverage.fresh_markdown(pd.DataFrame([row]), by.reset_index())
    assert "On their own records:" in markdown and "On the fresh records:" in markdown
    assert "| b.nc | e_0 | 10 |" in markdown and "**0.70**" in markdown
    assert "Single calibrations on fresh records (2 answered on at least 50)" in markdown


@pytest.mark.parametrize("sd", [0.0, 0.02])
@pytest.mark.slow
def test_calibration_error_predicts_the_dispersion_of_cells_that_share_calibrations(sd):
    """Studies of 31 cells of 200 records, each cell's records served by three calibrations
    (shares 0.5, 0.3, 0.2) whose own coverage is 95 % plus a normal error of ``sd``, the
    records binomial about it: the calibrations' error read back from 600 fresh records a
    calibration lies within 0.004 of ``sd``, and the mean of the cells' dispersion
    (band_chance, 300 studies) lies within 4 % of the predicted one (1 for ``sd`` = 0)."""
    rng = np.random.default_rng(3)
    shares, n, cells = np.array([0.5, 0.3, 0.2]), 200, 31
    served = (shares * n).astype(int)
    ratios, fitted = [], []
    for _ in range(300):
        true = np.clip(coverage.NOMINAL + sd * rng.standard_normal((cells, 3)), 0.0, 1.0)
        k = rng.binomial(served, true).sum(axis=1)
        tab = pd.DataFrame({"answered": n, "answered_coverage": k / n, "in_band": coverage.in_band(k / n)})
        ratios.append(coverage.band_chance(tab)["chi2_ratio"])
    true = np.clip(coverage.NOMINAL + sd * rng.standard_normal((cells, 3)), 0.0, 1.0)
    cals = pd.DataFrame({"cell": np.repeat(np.arange(cells), 3), "records": np.tile(served, cells), "fresh_answered": 600,
                         "fresh_coverage": rng.binomial(600, true.ravel()) / 600})
    out = coverage.calibration_error(pd.DataFrame({"cell": np.arange(cells), "records": n}), cals)
    assert out["calibrations"] == 3 * cells and out["shares"] == pytest.approx(np.sum(shares**2))
    assert out["sd"] == pytest.approx(sd, abs=0.004)
    expected = 1.0 + (n * np.sum(shares**2) - 1.0) * sd**2 / (coverage.NOMINAL * (1.0 - coverage.NOMINAL))
    assert np.mean(ratios) == pytest.approx(expected, rel=0.04), (np.mean(ratios), expected)
    assert coverage.calibration_error(pd.DataFrame({"cell": np.arange(cells), "records": n}), cals.assign(fresh_coverage=0.95))["sd"] == 0.0

"""The warnings of `rockdec estimate` (rockdec.record.diagnostics): thresholds from the calibration's
own records, a clean record that fires nothing, and each gross defect named by its check.

The calibration here is the checks' statistics on clean simulated records at the test
record's e, length and sampling: what `rockdec.calibrate.calibration.build` stores for them.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import xarray as xr

from conftest import calibrated_step
from rockdec.calibrate import calibration
from rockdec.record import diagnostics
from rockdec.rdd import fits, measured
from rockdec.estimation import diagnose
from rockdec.record.records import Record
from rockdec.physics.simulate import simulate_block

E, N, SETS = 0.9, 40_000, 30
LEVEL = measured.DEFAULT_SETTINGS["level"]


def _calibration(values: np.ndarray, grid=(E,)) -> xr.Dataset:
    """A calibration holding only the checks' statistics ``values(e_true, set, check)``."""
    return xr.Dataset(
        {"diagnostic": (("e_true", "set", "check"), values)},
        coords={"e_true": list(grid), "set": np.arange(values.shape[1]), "check": list(diagnostics.CHECKS)},
    )


@pytest.fixture(scope="module")
def clean():
    """Clean records at e = 0.9 (75 samples per cycle, 40,000 samples): the first is the test
    record, the others the calibration's sets."""
    cal = calibrated_step(E, 1.0, 0.003)
    theta, _ = simulate_block(np.arange(SETS + 1) + 500, N, dt=cal["dt"], g=1.0, e=E, sigma_p=0.003, burn_in=cal["burn_in"])
    dt = cal["dt"]
    values = np.stack([diagnostics.statistics([y], measured.analyse([y], dt)) for y in theta[1:]])
    return theta[0], dt, _calibration(values[None])


def _fired(y, dt, cal):
    """The checks that fire on record ``y`` and the warnings' text."""
    analysis = measured.analyse([y], dt)
    notes, checks = diagnose([Record(y, dt, "r")], analysis, {}, cal, E, (E - 0.05, E + 0.05))
    return {name for name, c in checks.items() if c.fired}, " ".join(n.message for n in notes)


def test_thresholds_fire_on_at_most_5_percent_of_the_calibrations_own_records():
    rng = np.random.default_rng(1)
    values = rng.lognormal(size=(len(calibration.E_GRID), 200, len(diagnostics.CHECKS)))
    cal = _calibration(values, calibration.E_GRID)
    limits = diagnostics.thresholds(cal, 0.85, (0.8, 0.9), LEVEL)
    pooled = values[np.isin(calibration.E_GRID, (0.8, 0.85, 0.88))]  # inside the interval, and the grid points about e
    for j, check in enumerate(diagnostics.REGISTRY):
        if check.threshold == "structural":
            continue
        share = np.mean(pooled[..., j] > limits[check.name]) if check.side == "high" else np.mean(pooled[..., j] < limits[check.name])
        assert 0.0 < share <= 0.05, check.name


def test_a_doctored_calibration_moves_the_thresholds_and_the_structural_one_stays():
    rng = np.random.default_rng(2)
    values = rng.lognormal(size=(len(calibration.E_GRID), 40, len(diagnostics.CHECKS)))
    base = diagnostics.thresholds(_calibration(values, calibration.E_GRID), 0.85, (0.8, 0.9), LEVEL)
    doubled = diagnostics.thresholds(_calibration(3.0 * values, calibration.E_GRID), 0.85, (0.8, 0.9), LEVEL)
    for check in diagnostics.REGISTRY:
        if check.threshold == "structural":
            assert doubled[check.name] == base[check.name] == check.floor(0.85, LEVEL)
        else:
            assert doubled[check.name] == pytest.approx(3.0 * base[check.name], rel=1e-12)
    assert base["coarse_sampling"] == fits.min_points_per_cycle(0.85, LEVEL)
    assert base["few_triggers"] == diagnostics.MIN_SEGMENTS


def test_with_an_e_its_neighbours_are_pooled_and_without_one_the_strictest_grid_point_rules():
    dense = np.array([0.4, 0.5, 0.6, 0.7, 0.75, 0.8, 0.85, 0.88, 0.91, 0.93, 0.95, 0.98, 0.995])
    assert list(dense[diagnostics._near(dense, 0.86, (0.79, 0.9))]) == [0.75, 0.8, 0.85, 0.88, 0.91]  # inside, and the nearest beyond each end
    assert list(dense[diagnostics._near(dense, 0.86, None)]) == [0.85, 0.88]  # without an interval: a neighbour each side of e
    assert list(dense[diagnostics._near(dense, 0.995, (None, None))]) == [0.995]
    grid = np.asarray(calibration.E_GRID)
    rng = np.random.default_rng(3)
    spread = np.linspace(2.0, 1.0, grid.size)[:, None, None]  # the null narrows as e grows
    values = spread * rng.lognormal(size=(grid.size, 200, len(diagnostics.CHECKS)))
    cal = _calibration(values, calibration.E_GRID)
    unplaced = diagnostics.thresholds(cal, None, None, LEVEL)
    for j, check in enumerate(diagnostics.REGISTRY):
        if check.threshold == "calibrated" and check.side == "high":
            per_point = [diagnostics.thresholds(cal, float(e), None, LEVEL)[check.name] for e in grid]
            assert unplaced[check.name] == pytest.approx(min(per_point))  # no looser than any e's
            pooled = np.quantile(values[..., j], diagnostics.QUANTILE)
            assert unplaced[check.name] < pooled  # pooling every e would let the widest null rule


def test_a_record_without_a_reported_e_is_checked_where_its_estimators_place_it():
    """No estimator reported: the checks read the null at the median of the candidates'
    corrected values, a raw value beyond the calibrated range counted at the end it lies
    beyond (a record at e = 0.98 whose estimators all read above the top of the grid is
    checked at the top, not at the grid point whose null is narrowest); none at all leaves
    the strictest grid point. A reported e is used as it is."""
    from rockdec.estimation import Reading, checks_place
    from rockdec.rdd import registry

    top, bottom = calibration.E_GRID[-1], calibration.E_GRID[0]
    span = (bottom, top)

    def reading(e, side=None, low=math.nan, high=math.nan):
        return Reading(math.nan, math.nan if e is None else e, side, span, low, high, 0.95, 100, ())

    def per(*entries):
        return {name: reading(*entry) for name, entry in zip(registry.CANDIDATES, entries)}

    none = None
    assert len(registry.CANDIDATES) == 3
    assert checks_place(per((None, "above"), (None, "above"), (None, "above")), none) == (top, None)
    assert checks_place(per((None, "above"), (0.97, None), (None, "above")), none) == (top, None)
    assert checks_place(per((None, "below"), (0.5, None), (0.6, None)), none) == (0.5, None)
    assert checks_place(per((None, "unreached"), (None, None), (None, None)), none) == (None, None)
    assert checks_place(per(*[(None, "above")] * 3), reading(0.9, None, 0.85, 0.95)) == (0.9, [0.85, 0.95])
    grid = np.asarray(calibration.E_GRID)
    rising = np.linspace(0.0, 3.0, grid.size)[:, None, None]  # the statistic grows with e (the nonstationary z does)
    cal = _calibration(rising + np.random.default_rng(8).standard_normal((grid.size, 30, len(diagnostics.CHECKS))), calibration.E_GRID)
    at_top = diagnostics.thresholds(cal, top, None, LEVEL)["nonstationary"]
    assert at_top > diagnostics.thresholds(cal, None, None, LEVEL)["nonstationary"] + 2.0
    assert np.mean(cal["diagnostic"].values[-1, :, 0] > at_top) < 0.1


def test_every_statistic_is_scale_free(clean):
    """The calibration has g = sigma_p = 1: a record's statistics must not depend on its units."""
    theta, dt, _ = clean
    base = diagnostics.statistics([theta], measured.analyse([theta], dt))
    scaled = diagnostics.statistics([7.0 * theta], measured.analyse([7.0 * theta], 2.0 * dt))
    np.testing.assert_allclose(scaled, base, rtol=1e-9)


def test_a_clean_record_fires_nothing(clean):
    theta, dt, cal = clean
    fired, notes = _fired(theta, dt, cal)
    assert fired == set() and notes == ""


def test_warnings_name_what_looks_wrong(clean):
    """Drift, a spike and a lean each raise their warning; the clean record raises none of them.
    (Moved from test_estimate; the wording of the checks replaced 'spike or overturning'.)"""
    theta, dt, cal = clean
    sigma = float(np.std(theta))
    assert not any(w in _fired(theta, dt, cal)[1] for w in ("stationary", "spike", "asymmetric"))
    drifting = theta.copy()
    drifting[-theta.size // 4 :] *= 3.0
    assert "not stationary" in _fired(drifting, dt, cal)[1]
    spiky = theta.copy()
    spiky[500] = 40 * sigma
    assert "spike" in _fired(spiky, dt, cal)[1]
    assert "asymmetric" in _fired(theta + 0.8 * np.abs(theta), dt, cal)[1]


@pytest.mark.parametrize("defect, words", [
    ("nonstationary", "not stationary"),
    ("drift", "zero drifts"),
    ("spikes", "holds spikes"),
    ("asymmetry", "lean on one side"),
    ("few_triggers", "cut the record into pieces without gaps"),
    ("coarse_sampling", "too coarse"),
])
def test_a_gross_defect_fires_its_check_and_names_it(clean, defect, words):
    theta, dt, cal = clean
    sigma = float(np.std(theta))
    y, step = theta.copy(), dt
    if defect == "nonstationary":
        y *= np.linspace(0.3, 3.0, y.size)
    elif defect == "drift":
        y += 3.0 * sigma * np.linspace(-0.5, 0.5, y.size)
    elif defect == "spikes":
        y[::4000] = 5.0 * sigma
    elif defect == "asymmetry":
        y += 0.8 * np.abs(y)
    elif defect == "few_triggers":
        for start in range(1000, y.size, 5000):
            y[start : start + 1000] = np.nan  # 20 % in gaps
    else:
        y, step = theta[::4], 4 * dt  # about 19 samples per cycle
    fired, notes = _fired(y, step, cal)
    assert defect in fired and words in notes


class _Lag:
    """What :func:`rockdec.record.diagnostics.segments` reads of an analysis: its ``n_lag``."""

    def __init__(self, n_lag):
        self.n_lag = n_lag


def test_the_segments_share_counts_the_positions_gaps_cost():
    """Positions L .. n - L - 1 hold a whole segment of 2 L + 1 samples; a gap of G samples
    costs G + 2 L of them (less at a record's ends), overlapping costs once; pooled over
    records, position-weighted; 1 without NaN, NaN when no segment fits."""
    n, lag = 10_000, 100
    y = np.random.default_rng(4).normal(size=n)
    share = (lambda *records, L=lag: diagnostics.segments(diagnostics.sums(records), _Lag(L)))
    assert share(y) == 1.0
    gap = y.copy()
    gap[5000:5500] = np.nan
    assert share(gap) == pytest.approx(1 - 700 / 9800, rel=1e-12)
    gap[:50], gap[9990:] = np.nan, np.nan  # at the ends: positions 100..149 and 9890..9899
    assert share(gap) == pytest.approx(1 - 760 / 9800, rel=1e-12)
    gap[5600:5650] = np.nan  # its reach [5500, 5750) overlaps the first gap's [4900, 5600)
    assert share(gap) == pytest.approx(1 - 910 / 9800, rel=1e-12)
    assert share(gap, y) == pytest.approx(1 - 910 / 19_600, rel=1e-12)
    assert share(gap[::-1]) == share(gap)  # the mirrored record
    every = y.copy()
    every[::150] = np.nan  # every segment of 201 samples holds one
    assert share(every) == 0.0
    assert np.isnan(share(y[:200]))


def test_the_trigger_count_falls_as_the_segments_share(clean):
    """The study's gaps (2000 samples each, diagnostics_study.add_defect) in the test record:
    the triggers of the largest window fall to the share of positions they leave (triggers
    fall on the lost positions as on the kept ones), within 4 % of the clean count."""
    from rockdec.studies.diagnostics_study import add_defect

    theta, dt, _ = clean
    whole = measured.analyse([theta], dt, g=1.0)
    count = (lambda a: float(a.count["a"][-1] + a.count["v"][-1]))
    for size in (0.1, 0.3):
        y = add_defect(theta, "few_triggers", size, 1)
        analysis = measured.analyse([y], dt, g=1.0)  # the same lag range as the whole record's
        share = diagnostics.segments(diagnostics.sums([y]), analysis)
        assert share < 1.0 - size
        assert count(analysis) / count(whole) == pytest.approx(share, abs=0.04)


def test_the_trend_statistic_is_the_least_squares_slopes_t():
    """One record: ``_trend_z`` is ``|slope / se|`` of scipy's straight-line fit; several: the
    root mean square of the records' slopes over the pooled residual spread, so records with
    opposite trends do not cancel; a trendless record stays near 1 and a trend grows it."""
    from scipy import stats

    rng = np.random.default_rng(3)
    v = rng.normal(size=20)
    fit = stats.linregress(np.arange(20), v)
    assert diagnostics._trend_z(v, np.zeros(20, int)) == pytest.approx(abs(fit.slope / fit.stderr), rel=1e-12)
    up, down = v + np.linspace(0, 4, 20), v[::-1] - np.linspace(0, 4, 20)
    pooled = diagnostics._trend_z(np.r_[up, down], np.repeat([0, 1], 20))
    assert pooled > 3 and pooled == pytest.approx(diagnostics._trend_z(np.r_[up, -down], np.repeat([0, 1], 20)), rel=1e-12)
    assert np.isnan(diagnostics._trend_z(np.ones(20), np.zeros(20, int)))


def test_the_split_statistic_is_the_largest_two_sample_t_over_the_splits():
    """One record: ``_split_t`` is the largest ``|t|`` of scipy's pooled two-sample t test over
    the splits with two values or more on each side; unchanged by the values' scale, offset
    and order reversed; several records: the root mean square of theirs."""
    from scipy import stats

    rng = np.random.default_rng(4)
    v = rng.normal(size=20)
    best = max(abs(stats.ttest_ind(v[:k], v[k:]).statistic) for k in range(2, 19))
    assert diagnostics._split_t(v, np.zeros(20, int)) == pytest.approx(best, rel=1e-10)
    assert diagnostics._split_t(3.0 * v[::-1] - 7.0, np.zeros(20, int)) == pytest.approx(best, rel=1e-10)
    w = rng.normal(size=20)
    both = diagnostics._split_t(np.r_[v, w], np.repeat([0, 1], 20))
    assert both == pytest.approx(np.sqrt((best**2 + diagnostics._split_t(w, np.zeros(20, int)) ** 2) / 2), rel=1e-10)
    assert np.isnan(diagnostics._split_t(np.ones(20), np.zeros(20, int)))
    assert np.isnan(diagnostics._split_t(v[:3], np.zeros(3, int)))


def test_a_step_in_the_loads_strength_lifts_the_nonstationarity_without_bound():
    """Von Neumann's ratio of 20 block variances stays below 4.3 however large a step in them
    (its ceiling); the split's t grows with the step, and the nonstationarity statistic is the
    larger of the two. On independent normal values the split's 98.5 % point lies between
    the middle split's alone (Student's t, 18 degrees of freedom) and the Bonferroni bound
    over the 17 splits."""
    from scipy import stats

    rng = np.random.default_rng(5)
    noise = rng.normal(size=20)
    sizes = (2.0, 10.0, 100.0)
    steps = [np.r_[np.zeros(10), np.full(10, size)] + noise for size in sizes]
    vn = [diagnostics._von_neumann_z(v, np.zeros(20, int)) for v in steps]
    split = [diagnostics._split_t(v, np.zeros(20, int)) for v in steps]
    assert max(vn) < 4.3 and split[2] > 10 * split[0] > 10 * vn[0]
    point = np.percentile([diagnostics._split_t(rng.normal(size=20), np.zeros(20, int)) for _ in range(4000)], 98.5)
    assert stats.t.ppf(1 - 0.015 / 2, 18) < point < stats.t.ppf(1 - 0.015 / 2 / 17, 18)


@pytest.mark.slow
def test_a_load_that_doubles_halfway_stands_above_every_clean_record_at_e_098():
    """At e = 0.98 stationary records' block variances wander and von Neumann's ratio of
    them reaches its ceiling's range; a record whose impulses double in strength halfway
    (its rms rises about tenfold) reads a nonstationarity above the largest of 40 clean
    records of the same e and sampling."""
    from rockdec.physics.loading import draw_impulses, series_rng
    from rockdec.physics.simulate import integrate

    step = calibrated_step(0.98, 1.0, 1.0)
    n, burn_in = 100_000, step["burn_in"]
    theta, _ = simulate_block(np.arange(40) + 900, n, dt=step["dt"], g=1.0, e=0.98, sigma_p=1.0, burn_in=burn_in)
    clean = max(diagnostics.nonstationarity(diagnostics.sums([y]), None) for y in theta)
    impulses = np.empty(burn_in + n - 1)
    draw_impulses(series_rng(3), impulses, 1.0, 0.0)
    impulses[burn_in + n // 2:] *= 2.0
    doubled, omega = np.empty(n), np.empty(n)
    integrate(impulses, step["dt"], 1.0, 0.98, 0.0, 0.0, burn_in, doubled, omega)
    assert diagnostics.nonstationarity(diagnostics.sums([doubled]), None) > clean


def test_the_spikes_statistic_does_not_grow_with_the_sensor_noise(clean):
    """The largest distance off the neighbours' line is read against the record's own 99th
    percentile of it, so white sensor noise of 1, 3 or 5 % of sigma_Y gives the same ratio
    (within 10 %), while the largest distance itself, in sigma_Y, grows about fivefold."""
    theta, dt, _ = clean
    sigma = float(np.std(theta))
    draw = np.random.default_rng(4).standard_normal(theta.size)
    ratio, largest = [], []
    for level in (0.01, 0.03, 0.05):
        y = theta + level * sigma * draw
        ratio.append(diagnostics.spikes(diagnostics.sums([y]), None))
        largest.append(np.max(np.abs(y[2:] - 2 * y[1:-1] + y[:-2])) / 2 / sigma)
    assert max(ratio) / min(ratio) < 1.1
    assert largest[-1] / largest[0] > 3.0


def test_the_spikes_statistic_leaves_out_nan_and_needs_a_spread():
    """Triples touching a NaN are left out; a record without a triple, or whose distances
    are all zero (a straight line), gives no statistic (NaN, which never fires)."""
    y = np.sin(np.linspace(0.0, 60.0, 5000)) + 1e-3 * np.random.default_rng(5).standard_normal(5000)
    gappy = y.copy()
    gappy[1000:1100] = np.nan
    assert np.isfinite(diagnostics.sums([gappy]).off)
    assert diagnostics.sums([gappy]).off == pytest.approx(diagnostics.sums([y]).off, rel=0.2)
    gappy[3000] = 1.0  # a spike beside the gap's edge is still seen
    assert diagnostics.sums([gappy]).off > 50.0 * diagnostics.sums([y]).off
    assert np.isnan(diagnostics.sums([np.full(50, np.nan)]).off)
    assert np.isnan(diagnostics.sums([np.arange(50.0)]).off)


def _leaning(b: float, pole: float, dt: float, burn_in: int, seed: int = 21) -> np.ndarray:
    """A record at e = 0.9 (g = sigma_p = 1) whose impulses carry the mean ``b g dt``: the
    block falls back with ``g (1 - b)`` on one side and ``g (1 + b)`` on the other (eq. 4);
    the load low-pass filtered with ``pole`` per sample (0: white)."""
    from rockdec.physics.loading import draw_impulses, series_rng
    from rockdec.physics.simulate import integrate

    impulses = np.empty(burn_in + N - 1)
    draw_impulses(series_rng(seed), impulses, 1.0, pole)
    impulses += b * dt
    theta, omega = np.empty(N), np.empty(N)
    integrate(impulses, dt, 1.0, E, 0.0, 0.0, burn_in, theta, omega)
    return theta


@pytest.mark.parametrize("pole", [0.0, 0.78])
def test_the_asymmetry_reads_the_lean_itself_under_a_white_or_a_coloured_load(clean, pole):
    """Each side's g is read about the record's impact level, beyond a guard: a lean of b
    (g (1 - b) on one side, g (1 + b) on the other) reads b within 0.01 from b = 0.03 to
    0.6, and a clean record reads under 0.01 also under a low-pass load (pole 0.78 per
    sample), where a block chatters near rest and the sides split at the record's mean read
    0.05-0.1. An offset of the record (a sensor's zero) changes nothing."""
    _, dt, _ = clean
    step = calibrated_step(E, 1.0, 1.0)
    asymmetry = (lambda y: diagnostics.asymmetry(diagnostics.sums([y]), None))
    clean_value = asymmetry(_leaning(0.0, pole, step["dt"], step["burn_in"]))
    assert clean_value < 0.01
    for b in (0.03, 0.1, 0.3, 0.6):
        y = _leaning(b, pole, step["dt"], step["burn_in"])
        assert asymmetry(y) == pytest.approx(b, abs=0.01)
        assert asymmetry(y + 5.0 * np.std(y)) == pytest.approx(asymmetry(y), rel=1e-6)


def test_the_impact_level_is_where_the_sides_part():
    """Parabolic flights (eq. 4) of g = 2 about a level 3: the second differences are
    +g dt^2 below it and -g dt^2 above it, so from any centre within the search range the
    level found lies within the samples' spacing at the impacts (0.02), the sides read
    about it are exactly +-g dt^2, and the mirrored record's sides are their mirror image."""
    dt = 0.01
    t = (np.arange(20_000) + 0.5) * dt  # no sample on an impact
    phase = np.mod(t, 2.0)
    y = 3.0 + np.where(np.mod(t, 4.0) < 2.0, 1.0, -1.0) * phase * (2.0 - phase)
    guard = 8 * 2.0 * dt**2
    for centre in (2.9, 3.0, 3.05):
        level = diagnostics.impact_level(y, centre, float(np.std(y)), guard)
        assert abs(level - 3.0) < 0.02
        n0, n1, s0, s1 = diagnostics.side_sums(y, level, guard)
        assert s0 / n0 == pytest.approx(2.0 * dt**2, rel=1e-6) and s1 / n1 == pytest.approx(-2.0 * dt**2, rel=1e-6)
        mirrored = diagnostics.side_sums(-y, diagnostics.impact_level(-y, -centre, float(np.std(y)), guard), guard)
        assert mirrored == pytest.approx((n1, n0, -s1, -s0), rel=1e-9)


def test_a_mirrored_record_gives_the_same_statistics(clean):
    """A block leaning left or right is the same defect: mirroring the record (``-y``) swaps
    the sides' g and leaves the asymmetry's magnitude, and every other statistic, unchanged."""
    theta, dt, _ = clean
    leaning = theta + 0.3 * np.abs(theta)
    for y in (theta, leaning):
        base = diagnostics.statistics([y], measured.analyse([y], dt))
        mirrored = diagnostics.statistics([-y], measured.analyse([-y], dt))
        np.testing.assert_allclose(mirrored, base, rtol=1e-9)
    j = diagnostics.CHECKS.index("asymmetry")
    assert diagnostics.statistics([leaning], measured.analyse([leaning], dt))[j] > 0.1


def test_the_null_takes_its_shape_from_every_grid_point_and_its_place_from_the_nearest():
    """When every grid point's values are one shape located and scaled (``m_j + s_j z``), the
    null of a point is exactly that point's values. On normal values (30 sets a point, 10
    points, the null narrowing with the grid), the null's quantile fires on the true null of
    the pooled points at about ``1 - QUANTILE``, and fewer of 400 calibrations fire on more
    than 5 % of it than with the quantile of the pooled points' own sets."""
    from scipy.stats import norm

    z = np.random.default_rng(6).standard_normal(30)
    m, s = np.linspace(1.0, 5.0, 10)[:, None], np.linspace(0.5, 2.0, 10)[:, None]
    values = m + s * z  # the same standardized values at every point
    for j in (0, 4, 9):
        group = np.arange(10) == j
        np.testing.assert_allclose(np.sort(diagnostics.null(values, group)), np.sort(np.tile(values[j], 10)), rtol=1e-12)
    rng = np.random.default_rng(7)
    near = (3, 4, 5)
    group = np.isin(np.arange(10), near)

    def fires(limit):  # share of the pooled points' true null above the limit
        return np.mean([norm.sf((limit - m[j, 0]) / s[j, 0]) for j in near])

    null, own = [], []
    for _ in range(400):
        v = m + s * rng.standard_normal((10, 30))
        null.append(fires(np.quantile(diagnostics.null(v, group), diagnostics.QUANTILE)))
        own.append(fires(np.quantile(v[group], diagnostics.QUANTILE)))
    null, own = np.array(null), np.array(own)
    assert np.mean(null) < 1.0 - diagnostics.QUANTILE + 0.01
    assert np.mean(null > 0.05) < 0.5 * np.mean(own > 0.05)


def test_a_statistic_that_moves_with_e_is_read_against_points_that_bracket_the_interval():
    """A clean record of true ``e`` = 0.6 whose reported ``e`` came out low, 0.52 in
    (0.43, 0.61): its statistic, whose location climbs steeply with ``e`` (as ``filtered``'s
    does at low ``e``), follows the truth. The threshold pools the grid points beyond both
    ends of the interval, so it lies at or above the truth's own 98.5 % point; points on the
    low side of the truth alone (0.4 and 0.55) would put it below, and the check would fire on
    a clean record far more often than 1.5 %."""
    from scipy.stats import norm

    grid = np.asarray(calibration.E_GRID)
    j = diagnostics.CHECKS.index("filtered")
    assert diagnostics.REGISTRY[j].side == "high"
    location = lambda e: -0.3 + 0.4 * e  # noqa: E731  (0.02 a unit of spread per 0.05 of e)
    rng = np.random.default_rng(5)
    values = np.ones((grid.size, 120, len(diagnostics.CHECKS)))
    values[:, :, j] = location(grid)[:, None] + 0.01 * rng.standard_normal((grid.size, 120))
    e, interval, truth = 0.52, (0.43, 0.61), 0.6
    limit = diagnostics.thresholds(_calibration(values, calibration.E_GRID), e, interval, LEVEL)["filtered"]
    truth_point = location(truth) + 0.01 * norm.ppf(diagnostics.QUANTILE)
    assert limit >= truth_point
    one_side = np.quantile(diagnostics.null(values[:, :, j], (grid == 0.4) | (grid == 0.55)), diagnostics.QUANTILE)
    assert one_side < truth_point  # what the low side alone gives: the clean record would fire


def test_the_asymmetry_null_takes_the_widest_point_with_one_spread_for_the_grid():
    """The asymmetry of a clean record is about ``|N(0, s(e))|``: as a logarithm its spread is
    the same at every ``e`` and only its location moves (falling from ``e`` = 0.55 to 0.7). On
    200 calibrations of 30 such sets a grid point, for a record at ``e`` = 0.6 whose interval
    reaches the tighter point 0.7, the threshold (each point's location, one spread for the
    grid, the widest point) fires on the record's true null below ``1 - QUANTILE`` on
    average, and on more than 5 % of it for fewer calibrations than the quantile of the
    points' nulls pooled."""
    from scipy.stats import norm

    grid = np.asarray(calibration.E_GRID)
    j = diagnostics.CHECKS.index("asymmetry")
    assert diagnostics.REGISTRY[j].null_model == "widest"
    knots, knot_scales = [0.4, 0.55, 0.7, 1.0], np.log([0.007, 0.0097, 0.0058, 0.0007])
    scale = np.exp(np.interp(grid, knots, knot_scales))
    e, interval = 0.6, (0.52, 0.66)
    true_scale = float(np.exp(np.interp(e, knots, knot_scales)))
    near = diagnostics._near(grid, e, interval)
    assert list(grid[near]) == [0.4, 0.55, 0.7]
    rng = np.random.default_rng(9)
    widest, pooled = [], []
    for _ in range(200):
        values = np.ones((grid.size, 30, len(diagnostics.CHECKS)))  # the other checks' columns play no part
        values[:, :, j] = np.abs(scale[:, None] * rng.standard_normal((grid.size, 30)))
        limit = diagnostics.thresholds(_calibration(values, calibration.E_GRID), e, interval, LEVEL)["asymmetry"]
        widest.append(2.0 * norm.sf(limit / true_scale))  # share of |N(0, s)| above the limit
        pooled.append(2.0 * norm.sf(np.quantile(diagnostics.null(values[:, :, j], near), diagnostics.QUANTILE) / true_scale))
    widest, pooled = np.array(widest), np.array(pooled)
    assert np.mean(widest) < 1.0 - diagnostics.QUANTILE
    assert np.mean(widest > 0.05) < np.mean(pooled > 0.05)


def test_the_split_statistic_of_no_blocks_is_nan_without_a_warning():
    """A record too short for one block (a calibration set of 2,000 samples) has no blocks:
    the statistic is NaN, and NumPy's 'mean of empty slice' never reaches the user."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert np.isnan(diagnostics._split_t(np.array([]), np.array([])))

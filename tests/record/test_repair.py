"""The repair of a record (rockdec.record.repair): spikes found and replaced, drift high-passed,
the calibration's sets repaired by the same function, the report and the command line."""

import warnings

import numpy as np
import pytest

import rockdec
from rockdec import cli
from rockdec.calibrate import calibration
from rockdec import estimation
from rockdec.physics.record_model import NO_NOISE
from rockdec.report.estimate_report import document
from stand_in_outcome import stand_in
from rockdec.rdd import measured
from rockdec.record import repair
from rockdec.record.records import Record
from rockdec.report import summary


@pytest.fixture(scope="module")
def clean():
    """A clean record of 40,000 samples at e = 0.9 (the simplified model holds: theta_cr 1)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        theta = rockdec.simulate(0.9, 40_000, seed=11, theta_cr=1.0)
    return np.asarray(theta.values, dtype=float).ravel(), float(theta.attrs["dt"])


def test_spikes_of_25_sigma_are_all_found_and_a_clean_record_has_none(clean):
    y, _ = clean
    assert repair.find_spikes(y).size == 0
    rng = np.random.default_rng(3)
    where = np.sort(rng.choice(np.arange(10, y.size - 10), 60, replace=False))
    spiked = y.copy()
    spiked[where] += rng.choice([-1.0, 1.0], where.size) * 25.0 * y.std()
    found = repair.find_spikes(spiked)
    assert set(where) <= set(found.tolist())
    assert found.size <= where.size + 2 * np.count_nonzero(np.diff(where) <= 2)  # at most the neighbours of touching spikes
    out, done = repair.apply([spiked], repair.settings(True, False), np.nan)
    assert done.removed == found.size
    assert np.max(np.abs(out[0] - y)) < 0.2 * y.std()  # each replaced by its neighbours' line, near the true sample


def test_the_spikes_check_reads_a_repaired_record_like_a_clean_one():
    """Spikes on 1 % of the samples of a record at e = 0.98, replaced by their neighbours'
    line: those samples sit on the line, so read with the others the record's 99th
    percentile of distances (there the impacts' small jumps) falls and its spikes statistic
    rises above the clean record's; with the replaced samples left out (what the repair
    hands the checks) it is the clean record's within 2 %."""
    from rockdec.record import diagnostics

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        y = np.asarray(rockdec.simulate(0.98, 100_000, seed=12, theta_cr=1.0).values, dtype=float).ravel()
    rng = np.random.default_rng(8)
    where = rng.choice(np.arange(10, y.size - 10), y.size // 100, replace=False)
    spiked = y.copy()
    spiked[where] += rng.choice([-1.0, 1.0], where.size) * rng.uniform(5.0, 50.0, where.size) * y.std()
    out, done = repair.apply([spiked], repair.settings(True, False), np.nan)
    ratio = lambda records, replaced=None: diagnostics.spikes(diagnostics.sums(records, replaced), None)  # noqa: E731
    assert ratio(out) > 1.1 * ratio([y])
    assert ratio(out, done.spikes) == pytest.approx(ratio([y]), rel=0.02)
    assert ratio([y], [np.empty(0, dtype=int)]) == ratio([y])


def test_spikes_found_beside_a_gap_and_in_a_mirrored_record(clean):
    y, _ = clean
    spiked = y.copy()
    spiked[1000:1002] += 30.0 * y.std()  # two touching spikes
    spiked[5000] = np.nan
    spiked[5001] -= 30.0 * y.std()  # a spike beside a gap
    found = set(repair.find_spikes(spiked).tolist())
    assert {1000, 1001, 5001} <= found
    assert set(repair.find_spikes(-spiked).tolist()) == found  # a sign of the record changes nothing


def test_a_linear_drift_is_removed_and_a_clean_record_barely_moves(clean):
    y, dt = clean
    ppc = measured.analyse([y], dt).points_per_cycle
    t = np.arange(y.size)
    drifting = y + 5.0 * y.std() * t / y.size
    out, done = repair.apply([drifting], repair.settings(False, True), ppc)
    slope = np.polyfit(t, out[0], 1)[0] * y.size
    assert abs(slope) < 0.05 * y.std()  # of 5 sigma_Y over the record
    assert done.corner == repair.HIGHPASS_CORNER and done.per_sample == pytest.approx(repair.HIGHPASS_CORNER / ppc)
    filtered = repair.highpass(y, repair.HIGHPASS_CORNER / ppc)
    before, after = measured.analyse([y], dt), measured.analyse([filtered], dt)
    m = min(before.free_response.size, after.free_response.size)  # the lag ranges may differ by a sample
    r0, r1 = before.free_response[:m], after.free_response[:m]
    assert np.max(np.abs(r1 - r0)) < 0.05 * np.max(np.abs(r0))  # the signature within 5 % of its peak
    assert abs(after.raw["e4"] - before.raw["e4"]) < 0.02


def test_the_highpass_keeps_gaps_and_scales_with_the_record(clean):
    y, _ = clean
    gappy = y.copy()
    gappy[100:110] = np.nan
    out = repair.highpass(gappy, 0.002)
    assert np.isnan(out[100:110]).all() and np.isfinite(np.delete(out, np.arange(100, 110))).all()
    np.testing.assert_allclose(repair.highpass(3.0 * y, 0.002), 3.0 * repair.highpass(y, 0.002), rtol=1e-9, atol=1e-12)


def test_the_calibration_repairs_its_sets_with_the_record_s_function_and_keys_them_apart(clean, monkeypatch):
    y, _ = clean
    settings = repair.settings(True, True)
    seen = []
    original = repair.apply
    monkeypatch.setattr(repair, "apply", lambda *a: seen.append(a) or original(*a))
    got, replaced = calibration._repaired([y], settings, 75.0)
    assert seen and seen[0][1] == settings and seen[0][2] == 75.0
    np.testing.assert_array_equal(got[0], original([y], settings, 75.0)[0][0])
    assert [w.size for w in replaced] == [0]
    plain = calibration.calibration_settings([y.size], 75.0)
    assert "repair" not in plain and calibration.calibration_settings([y.size], 75.0, repaired=repair.settings(False, False)) == plain
    fixed = calibration.calibration_settings([y.size], 75.0, repaired=settings)
    assert fixed["repair"] == settings and calibration.settings_hash(fixed) != calibration.settings_hash(plain)


@pytest.fixture
def fake_cal(monkeypatch, tmp_path):
    """A calibration without simulation: every estimator reads the true e with a spread of 0.01."""
    import fake_calibration

    monkeypatch.setattr(calibration, "_grid_point", fake_calibration.grid_point)
    return tmp_path / "calibration"


def test_the_report_names_the_repair_and_the_repair_can_be_turned_off(clean, fake_cal):
    y, dt = clean
    spiked = y.copy()
    spiked[[5000, 9000, 20000]] += 25.0 * y.std()
    options = dict(cache_dir=fake_cal, load="white", sensor=NO_NOISE)
    doc = document(estimation.estimate([Record(spiked, dt, "spiked")], **options))
    assert doc["repair"]["spikes_removed"] == 3 and doc["repair"]["repaired"] and doc["repair"]["enabled"]
    assert "3 spikes replaced" in summary.text(doc)
    off = document(estimation.estimate([Record(spiked, dt, "spiked")], repair_records=False, **options))
    assert off["repair"] == {**off["repair"], "enabled": False, "repaired": False, "spikes_removed": 0}
    assert "repair: off" in summary.text(off)
    plain = document(estimation.estimate([Record(y, dt, "clean")], **options))
    assert not plain["repair"]["repaired"] and "repaired" not in summary.text(plain)


def test_the_command_line_turns_the_repair_off():
    parser = cli.build_parser()
    assert parser.parse_args(["estimate", "r.csv"]).repair is True
    assert parser.parse_args(["estimate", "r.csv", "--no-repair"]).repair is False
    assert cli.FLAGS["repair"] == "--no-repair"
    with pytest.raises(rockdec.InputError, match="`repair`"):
        rockdec.estimate(np.zeros(10), dt=0.01, repair="no")


@pytest.mark.parametrize("check, declined", [("nonstationary", True), ("asymmetry", True), ("drift", True), ("spikes", True),
                                             ("few_triggers", False), ("coarse_sampling", False)])
def test_a_check_left_fired_by_the_repair_declines_e_when_its_defect_moves_e(check, declined):
    verdict = estimation.Verdict(True, False, False, False, {check: f"the {check} message"}, True)
    given = stand_in(verdict, estimator="e_v")
    out = estimation.decline_unrepaired(given)
    assert (out.declined is not None) == declined and (out.shown is None) == declined
    if declined:
        assert f"{check}: the {check} message" in out.declined and "after the repair" in out.declined
    else:
        assert out == given


@pytest.mark.parametrize("gaps", [0, 40])
def test_the_robust_scale_is_scipys_median_absolute_deviation(clean, gaps):
    """The scale of the second differences is 1.4826 times their median absolute deviation as
    scipy.stats computes it, to the bit, with NaN samples (their differences left out)."""
    from scipy.stats import median_abs_deviation

    y = clean[0].copy()
    y[np.random.default_rng(5).choice(y.size, gaps, replace=False)] = np.nan
    d = np.diff(y, 2)
    assert repair.second_difference_scale(y) == repair.MAD_TO_SD * float(median_abs_deviation(d[np.isfinite(d)]))
    assert np.isnan(repair.second_difference_scale(np.full(50, np.nan)))

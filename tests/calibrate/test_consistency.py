"""Records given together are checked for one e: Cochran's Q of their own raw values.

Closed forms of the statistic and of its null (chi-square with one degree of freedom fewer
than the records, on raw values drawn about one mean with known spreads), its invariants,
and the stage of the estimate (:func:`rockdec.estimation.check_pooled`) on records
of 20,000 samples with a calibration made without simulation (``tests/fake_calibration.py``).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import rockdec
from rockdec.calibrate import belt, calibration, consistency
from rockdec import estimation
from rockdec.physics.record_model import NO_NOISE
from rockdec.report.estimate_report import document
from rockdec.rdd import measured
from rockdec.record.records import Record


def test_two_records_give_their_difference_over_its_spread_squared():
    x, s = np.array([0.81, 0.86]), np.array([0.01, 0.02])
    q, z = consistency.statistic(x, s)
    assert q == pytest.approx((x[1] - x[0]) ** 2 / (s[0] ** 2 + s[1] ** 2))
    assert np.sum(z / s) == pytest.approx(0.0, abs=1e-9)  # offsets about the weighted mean: weighted sum 0


def test_the_statistic_is_invariant_to_a_shift_and_a_common_scale():
    rng = np.random.default_rng(3)
    x, s = 0.8 + 0.02 * rng.standard_normal(5), 0.01 + 0.01 * rng.random(5)
    q, _ = consistency.statistic(x, s)
    assert consistency.statistic(0.3 + 7.0 * x, 7.0 * s)[0] == pytest.approx(q)
    assert consistency.statistic(x[::-1], s[::-1])[0] == pytest.approx(q)  # the records' order does not count


E = np.linspace(0.4, 0.995, 600)


def flat(spread: float):
    """A belt whose raw value reads ``e`` unbiased with one spread at every ``e``."""
    return E, E, np.full(E.size, spread)


@pytest.mark.parametrize("lengths", [[200_000, 200_000], [50_000, 200_000, 400_000]])
def test_on_one_mean_the_statistic_is_chi_square_and_fires_on_its_tail_share(lengths):
    """Raw values drawn about one mean with the spread of a belt of sets of 400,000 samples
    (biased by +0.01, its spread falling as ``1 - e``: 0.004 at the truth), scaled to each
    record's length: Q's mean is k - 1, its variance 2 (k - 1), and it fires on 1 - LEVEL of
    pools within the binomial's 4 standard deviations."""
    rng = np.random.default_rng(11)
    draws, spread, simulated = 8_000, 0.004, 400_000
    belt_ = (E, E + 0.01, spread * (1 - E) / 0.15)
    s = consistency.record_spreads(spread, simulated, lengths)
    x = 0.86 + s * rng.standard_normal((draws, len(lengths)))
    outcomes = [consistency.check(row, lengths, *belt_, simulated) for row in x]
    q = np.array([o.statistic for o in outcomes])
    k = len(lengths)
    assert q.mean() == pytest.approx(k - 1, abs=4 * math.sqrt(2 * (k - 1) / draws))
    assert q.var() == pytest.approx(2 * (k - 1), rel=0.15)
    p = 1 - consistency.LEVEL
    fired = np.mean([o.fired for o in outcomes])
    assert abs(fired - p) < 4 * math.sqrt(p * (1 - p) / draws)
    assert {o.dof for o in outcomes} == {k - 1}


def test_thresholds_are_chi_squares_closed_form_quantiles():
    assert consistency.threshold(1, 0.95) == pytest.approx(belt.Z95**2)
    for level in (0.9, 0.99, 0.999):  # chi-square with 2 degrees of freedom: -2 ln(1 - level)
        assert consistency.threshold(2, level) == pytest.approx(-2 * math.log(1 - level))
    assert math.isnan(consistency.threshold(0))


def test_the_spread_of_a_record_alone_grows_as_the_root_of_the_length_ratio():
    s = consistency.record_spreads(0.003, 400_000, [400_000, 100_000, 25_000])
    assert s == pytest.approx([0.003, 0.006, 0.012])


def test_a_record_without_a_value_is_left_out_and_one_left_is_not_tested():
    both = consistency.check([0.80, 0.84, math.nan], [100_000] * 3, *flat(0.004), 300_000)
    assert both.dof == 1 and math.isnan(both.z[2])
    assert both.statistic == pytest.approx(consistency.check([0.80, 0.84], [100_000] * 2, *flat(0.004), 300_000).statistic)
    alone = consistency.check([0.80, math.nan], [100_000] * 2, *flat(0.004), 200_000)
    assert math.isnan(alone.statistic) and not alone.fired and alone.dof == 0


def test_the_spread_is_read_where_the_mean_curve_takes_the_records_weighted_mean():
    """Records of two blocks (raw 0.85 and 0.60, the first three times as long) on a belt
    whose spread falls as ``1 - e`` and whose mean is biased by +0.02: the spread is the
    belt's at ``e = 0.7875 - 0.02``, wherever the pooled records' own estimate lies."""
    mean, spread = E + 0.02, 0.01 * (1 - E)
    lengths = [300_000, 100_000]
    c = consistency.check([0.85, 0.60], lengths, E, mean, spread, 400_000)
    s = 0.01 * (1 - 0.7675) * np.sqrt(400_000 / np.array(lengths))
    assert c.statistic == pytest.approx(consistency.statistic([0.85, 0.60], s)[0], rel=1e-6)
    assert consistency.spread_at(E, mean, spread, 2.0) == pytest.approx(spread[-1])  # beyond the curve: its nearest end
    assert math.isnan(consistency.spread_at(E[:0], mean[:0], spread[:0], 0.8))


def test_reads_inverts_the_mean_curve():
    e = np.linspace(0.4, 0.995, 400)
    mean = e - 0.05 * (1 - e) ** 2  # a bias that bends
    for truth in (0.45, 0.8, 0.97):
        assert consistency.reads(e, mean, truth - 0.05 * (1 - truth) ** 2) == pytest.approx(truth, abs=1e-6)
    assert math.isnan(consistency.reads(e, mean, 1.2))


@pytest.fixture
def fake_cal(monkeypatch, tmp_path):
    """A calibration without simulation: every estimator reads the true e with a spread of 0.01."""
    import fake_calibration

    monkeypatch.setattr(calibration, "_grid_point", fake_calibration.grid_point)
    return tmp_path / "calibration"


def records(*spec):
    """Records ``(e, samples, seed)`` of one step (the first record's), as the estimate takes them."""
    first = rockdec.simulate(spec[0][0], spec[0][1], seed=spec[0][2], theta_cr=1.0)  # small angles: the simplified model holds
    dt = float(first.attrs["dt"])
    out = [first] + [rockdec.simulate(e, n, seed=seed, dt=dt, theta_cr=1.0) for e, n, seed in spec[1:]]
    return [Record(np.asarray(r.values, dtype=float), dt, f"record {i}") for i, r in enumerate(out)]


def test_a_pair_of_short_records_reports_its_check_and_declines_e_when_they_disagree(fake_cal):
    """20,000 samples at e = 0.7 and 0.95 against a calibration whose spread is 0.01: the
    records' own raw values lie tens of spreads apart, so the check fires, e is declined and
    the reason names what each record reads alone."""
    doc = document(estimation.estimate(records((0.7, 20_000, 1), (0.95, 20_000, 2)), cache_dir=fake_cal, load="white",
                             sensor=NO_NOISE))
    check = doc["diagnostics"]["pooled_consistency"]
    assert set(check) == {"statistic", "threshold", "fired"}
    assert check["fired"] and check["statistic"] > check["threshold"] == pytest.approx(consistency.threshold(1))
    assert doc["e"] is None and doc["estimator"] is None and doc["interval"] == [None, None]
    assert "disagree on one e" in doc["reason"] and "alone, record 0 " in doc["reason"] and ", record 1 " in doc["reason"]
    assert ". " not in doc["reason"] and "nan" not in doc["reason"]  # one sentence, every record placed
    assert "pooled_disagree" in doc["warning_codes"]


def test_a_single_record_is_not_checked_and_its_report_has_no_pooled_entry(fake_cal, monkeypatch):
    (rec,) = records((0.85, 20_000, 4))
    doc = document(estimation.estimate([rec], cache_dir=fake_cal, load="white", sensor=NO_NOISE))
    assert "pooled_consistency" not in doc["diagnostics"]
    assert not {"pooled_disagree", "pooled_unchecked"} & set(doc["warning_codes"])

    def refuse(*args, **kwargs):
        raise AssertionError("a single record is analysed once")

    selection = estimation.Selection("e_v", (), None)
    analysed = estimation.Analysed((rec,), rec.dt, rec.theta.size, dict(measured.DEFAULT_SETTINGS), None, None, None, ())
    monkeypatch.setattr(measured, "analyse", refuse)
    assert estimation.check_pooled(analysed, None, None, selection) == (selection, (), {})


@pytest.mark.parametrize("given", [3, 2])
def test_a_record_that_cannot_be_analysed_alone_is_named_and_left_out(fake_cal, monkeypatch, given):
    """The last record (15,000 samples) fails alone: with two others they are still checked
    against each other, with one other nothing is checked; either way it is named, the
    estimate answers, and nothing crashes."""
    recs = records((0.85, 20_000, 5), (0.85, 20_000, 6), (0.85, 15_000, 7))[-given:]
    short = recs[-1].source
    analyse = measured.analyse

    def failing(rs, *args, **kwargs):
        if len(rs) == 1 and len(rs[0]) == 15_000:
            raise ValueError("too short for the test's sake")
        return analyse(rs, *args, **kwargs)

    monkeypatch.setattr(measured, "analyse", failing)
    doc = document(estimation.estimate(recs, cache_dir=fake_cal, load="white", sensor=NO_NOISE))
    notes = [w for w, code in zip(doc["warnings"], doc["warning_codes"]) if code == "pooled_unchecked"]
    assert len(notes) == 1 and short in notes[0] and "too short for the test's sake" in notes[0]
    check = doc["diagnostics"]["pooled_consistency"]
    if given == 3:
        assert "checked against each other" in notes[0] and check["statistic"] is not None
    else:
        assert "was not checked" in notes[0] and check["statistic"] is None and not check["fired"]

"""The shake-table test on records of an independent transient generator (tests/transient_reference.py)."""

import math

import numpy as np
import pytest
from scipy import stats

import transient_reference as tr
from rockdec.free.shake import analyse_shake_table, load_intensity, shaking_end
from rockdec.timeaxis import RecordError


def _base(e, seed):
    """The generator's base acceleration (rad/s^2)."""
    return tr.transient_with_base(e, seed)[1]


def test_shaking_end_is_after_the_last_loud_sample():
    a = _base(0.9, 0)
    end = shaking_end(a / tr.G, 1 / tr.FS)
    assert np.all(np.abs(a[end:]) <= 0.05 * tr.G) and abs(a[end - 1]) > 0.05 * tr.G


@pytest.mark.slow
def test_answered_tails_cover_e_over_seeds():
    covered = answered = 0
    for e in (0.8, 0.9, 0.95):
        for seed in range(3):
            theta, base = tr.transient_with_base(e, seed, noise=0.0)
            res = analyse_shake_table(theta, base, 1 / tr.FS, base_units="rad/s2", g_block=tr.G)
            if res.reason is None:
                answered += 1
                covered += res.e_interval[0] <= e <= res.e_interval[1]
            else:
                assert res.refused
    assert answered >= 4 and covered >= answered - 1


def test_a_tail_cut_while_the_base_moves_is_refused():
    res = analyse_shake_table(*tr.transient_with_base(0.9, 0), 1 / tr.FS, base_units="rad/s2", g_block=tr.G, start=8.0)
    assert res.reason is not None and "uplift level" in res.refused[0][2]


def test_base_of_another_length_is_refused():
    with pytest.raises(RecordError, match="base"):
        analyse_shake_table(np.zeros(100), np.zeros(99), 0.01, base_units="rad/s2", g_block=2.0)


@pytest.mark.slow
def test_a_residual_base_motion_in_the_tails_widens_the_interval_to_hold():
    """The base still moving at 2 % of the uplift level (white) in the tails: the intervals
    hold e over seeds, their z scores of unit spread, because the load's random walk of the
    block's speed enters the impacts' covariance (rockdec.free.analysis.load_covariance);
    without it, the z scores spread about 3.7 times too wide (benchmarks/shake_coverage.py)."""
    z = []
    for e in (0.9, 0.95):
        for seed in range(8):
            theta, base = tr.transient_with_base(e, seed, peak=1.6, noise=0.01, residual=0.02)
            res = analyse_shake_table(theta, base, 1 / tr.FS, base_units="rad/s2", g_block=tr.G)
            if res.reason is None:
                low, high = np.log(res.e_interval)
                z.append((np.log(res.e) - np.log(e)) / ((high - low) / 3.92))
    z = np.abs(np.array(z))
    assert z.size >= 10 and np.sum(z > 1.96) <= 1 and np.sqrt(np.mean(z**2)) < 1.5


def test_the_load_intensity_of_white_noise_is_its_variance_times_the_step():
    r = np.random.default_rng(1).uniform(-0.02, 0.02, 400_000)
    assert load_intensity(r, 0.005) == pytest.approx(0.02**2 / 3 * 0.005, rel=0.05)
    assert load_intensity(r + 0.3, 0.005) == pytest.approx(load_intensity(r, 0.005), rel=1e-9)  # a constant offset is not motion


@pytest.mark.parametrize("into_the_fall", [0, 8, 15])
def test_a_tail_that_starts_as_the_block_falls_is_read_from_its_first_impact(into_the_fall):
    """A free decay whose first arc is cut as the block falls from its apex (the base falls
    quiet mid-flight): the arcs after the first impact are the free flight's (eq. 4), so ``e``
    is the simulated one however much of the first fall the tail lost."""
    from rockdec.physics.simulate import simulate_model

    free = simulate_model("simplified", [0], 3000, dt=0.005, g=2.0, e=0.9, sigma_p=0.0, theta0=0.01)[0][0]
    theta = np.concatenate([np.zeros(400), free[into_the_fall:]])
    base = np.concatenate([np.where(np.arange(400) % 2, 3.0, -3.0), np.zeros(free.size - into_the_fall)])
    res = analyse_shake_table(theta, base, 0.005, base_units="rad/s2", g_block=2.0)
    assert res.reason is None and res.e == pytest.approx(0.9, abs=1e-6)
    first_negative = int(np.flatnonzero(free[into_the_fall:] < 0)[0])  # the impact falls within a sample before it
    assert 0.0 <= res.tails[0][1] - (400 + first_negative) * 0.005 <= 0.005 + 1e-12


def test_a_tail_whose_one_impact_cannot_be_bounded_is_refused_not_raised():
    """A tail of the independent generator (e 0.8, strong shaking, 1 % noise) whose single impact's
    error is enormous: refused with that reason; the record is still answered by every impact."""
    theta, base = tr.transient_with_base(0.8, 28, peak=2.2, noise=0.01)
    res = analyse_shake_table(theta, base, 1 / tr.FS, base_units="rad/s2", g_block=tr.G)
    source, e, (low, high) = res.answer
    assert all(isinstance(why, str) for _, _, why in res.refused)
    assert source is None or (math.isfinite(low) and math.isfinite(high) and low <= e <= high)


@pytest.mark.slow
def test_records_are_pooled_by_their_own_errors():
    """Tails in several records: each record's tails read alone (its ``record_fits`` entry is
    the record analysed by itself), the block's ``e`` their error-weighted mean, its error
    the weighted mean's widened by the Birge ratio (computed here by hand), Student's ``t`` at
    the records' degrees of freedom summed; one record alone keeps its own reading."""
    records = [tr.transient_with_base(0.95, seed, strong=8.0, free=12.0, peak=1.6, noise=0.01) for seed in (3, 4, 5, 6)]
    pooled = analyse_shake_table([t for t, _ in records], [b for _, b in records], 1 / tr.FS, base_units="rad/s2", g_block=tr.G)
    alone = [analyse_shake_table(t, b, 1 / tr.FS, base_units="rad/s2", g_block=tr.G) for t, b in records]
    alone = [a for a in alone if a.tails]
    assert len(pooled.record_fits) == len(alone) >= 2 and all(not a.record_fits for a in alone)
    for fit, one in zip(pooled.record_fits, alone):
        assert fit.e == pytest.approx(one.e, rel=1e-12) and one.e == one.fit.e
    log_e, se = np.log([a.e for a in alone]), np.array([a.log_e_se for a in alone])
    w = se ** -2
    mu = np.sum(w * log_e) / np.sum(w)
    birge = math.sqrt(np.sum(w * (log_e - mu) ** 2) / (len(alone) - 1))
    assert pooled.e == pytest.approx(math.exp(mu), rel=1e-12)
    assert pooled.log_e_se == pytest.approx(max(1.0, birge) / math.sqrt(np.sum(w)), rel=1e-9)
    half = math.log(pooled.e_interval[1] / pooled.e)
    assert half == pytest.approx(stats.t.ppf(0.975, sum(f.dof for f in pooled.record_fits)) * pooled.log_e_se, rel=1e-9)

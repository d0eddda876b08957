"""The forced reading of a shake-table record (rockdec.free.forced): every impact, the base a
known load in the arcs. Checked on the tests' independent transient generator
(transient_reference.py: its own stepper, the base held over each sample or linear between
samples), statistics over seeds, and invariants."""

from __future__ import annotations

import math

import numpy as np
import pytest

import transient_reference as tr
from rockdec.free.forced import FLOOR, analyse_forced, base_integrals, pool_forced
from rockdec.free.shake import analyse_shake_table

DT = 1.0 / tr.FS


def _fit(theta, base, **kw):
    return analyse_forced(theta, base / tr.G, DT, **kw)


@pytest.mark.parametrize(("substeps", "tolerance"), [(0, 5e-4), (8, 2e-5)], ids=["held", "linear"])
def test_a_noise_free_record_gives_e_and_a_load_gain_of_one(substeps, tolerance):
    """A base linear between samples, as the fit reads it: ``e`` to 2e-5. A base held over each
    sample (a simulator's staircase): the lag search takes up its half sample, ``e`` to 5e-4."""
    for seed in range(3):
        theta, base = tr.transient_with_base(0.8, seed, peak=1.6, noise=0.0, substeps=substeps)
        fit = _fit(theta, base)
        assert fit.reason is None and fit.impacts >= 20
        assert abs(fit.e - 0.8) < tolerance and abs(fit.load_gain - 1.0) < 2e-3, (seed, fit)
        assert abs(fit.shift - (0.5 if substeps == 0 else 0.0)) < 0.01


def test_the_interval_holds_e_on_most_noisy_records_where_the_tails_give_none():
    """e = 0.8: the block comes to rest before the base falls quiet, so no tail answers; the
    impacts under the shaking do (1 % sensor noise, 12 records: a miss rate of 5 % would leave
    fewer than 10 held with probability 0.02)."""
    held, tails = 0, 0
    for seed in range(12):
        theta, base = tr.transient_with_base(0.8, 100 + seed, peak=1.6, noise=0.01, substeps=8)
        shake = analyse_shake_table(theta, base, DT, base_units="rad/s2", g_block=tr.G)
        fit = shake.forced[0]
        assert fit.reason is None and fit.e_interval[1] - fit.e_interval[0] < 0.02
        held += fit.e_interval[0] <= 0.8 <= fit.e_interval[1]
        tails += math.isfinite(shake.e)
    assert held >= 10 and tails <= 3


def test_mirrored_and_sign_flipped_records_give_the_same_e():
    """theta -> -theta with the base -> -base is the same block; the base's sign alone is a
    sensor's convention (the fitted load's sign takes it up)."""
    theta, base = tr.transient_with_base(0.9, 5, peak=1.6, noise=0.005, substeps=8)
    one = _fit(theta, base)
    assert _fit(-theta, -base).e == pytest.approx(one.e, abs=1e-9)
    assert _fit(theta, -base).e == pytest.approx(one.e, abs=1e-9)


def test_a_block_of_three_times_the_angle_gives_the_same_e_and_three_times_g():
    """The base over the uplift level unchanged, the angle three times: a block of three times
    ``g`` under three times the load."""
    theta, base = tr.transient_with_base(0.9, 6, peak=1.6, noise=0.005, substeps=8)
    one = _fit(theta, base)
    scaled = _fit(3.0 * theta, base)
    assert scaled.e == pytest.approx(one.e, abs=1e-9) and scaled.g == pytest.approx(3.0 * one.g, rel=1e-9)
    assert scaled.load_gain == pytest.approx(one.load_gain, rel=1e-9)


def test_a_base_in_the_wrong_units_is_refused_with_the_load_it_reads():
    theta, base = tr.transient_with_base(0.9, 7, peak=1.6, noise=0.005, substeps=8)
    fit = analyse_forced(theta, base / (2.0 * tr.G), DT)
    assert math.isnan(fit.e) and "2 times what its units" in fit.reason and fit.load_gain == pytest.approx(2.0, rel=0.01)


def test_pooled_records_read_their_impacts_together():
    fits = [_fit(*tr.transient_with_base(0.9, seed, peak=1.6, noise=0.01, substeps=8)) for seed in range(3)]
    pooled = pool_forced(fits)
    assert pooled.impacts <= sum(f.impacts for f in fits) and pooled.impacts >= max(f.impacts for f in fits)
    assert pooled.e_interval[0] <= 0.9 <= pooled.e_interval[1]
    assert pooled.e_interval[1] - pooled.e_interval[0] < np.median([f.e_interval[1] - f.e_interval[0] for f in fits])


@pytest.mark.parametrize("theta", [np.zeros(400), np.zeros(5)], ids=["at rest", "five samples"])
def test_a_record_without_flights_gives_a_reason(theta):
    fit = analyse_forced(theta, np.ones(theta.size), DT)
    assert math.isnan(fit.e) and fit.reason and fit.impacts == 0


def test_base_integrals_are_exact_for_a_base_linear_between_samples():
    """V and L of a ramp a(t) = t: t^2 / 2 and t^3 / 6 at every sample."""
    t = np.arange(11) * 0.1
    v, l = base_integrals(t, 0.1)
    np.testing.assert_allclose(v, t**2 / 2, atol=1e-15)
    np.testing.assert_allclose(l, t**3 / 6, atol=1e-15)


def test_the_interval_is_never_narrower_than_its_floor():
    theta, base = tr.transient_with_base(0.95, 0, peak=1.6, noise=0.0, substeps=8)
    lo, hi = _fit(theta, base).e_interval
    assert math.log(hi) - math.log(lo) >= 2 * FLOOR * (1 - 1e-9)

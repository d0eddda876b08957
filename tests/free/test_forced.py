"""The forced reading of a shake-table record (rockdec.free.forced): every impact, the base a
known load in the arcs. Checked on the tests' independent transient generator
(transient_reference.py: its own stepper, the base held over each sample or linear between
samples), statistics over seeds, and invariants."""

from __future__ import annotations

import math

import numpy as np
import pytest

import transient_reference as tr
from rockdec.free import forced
from rockdec.free.forced import FLOOR, READINGS, ForcedFit, analyse_forced, base_integrals, pool_forced
from rockdec.free.shake import analyse_shake_table

DT = 1.0 / tr.FS

#: A shorter record (8 s of shaking, 4 s free) for the invariants, which hold on any record.
SHORT = {"strong": 8.0, "free": 4.0}


def _fit(theta, base, **kw):
    return analyse_forced(theta, base / tr.G, DT, **kw)


@pytest.mark.parametrize(("substeps", "right", "wrong", "lag"), [(0, "held", "linear", 0.5), (8, "linear", "held", -0.5)],
                         ids=["held", "linear"])
def test_a_noise_free_record_gives_e_under_its_own_reading_and_the_envelope_holds_it(substeps, right, wrong, lag):
    """A base held over each sample (a simulator's staircase) or linear between samples: the
    reading that matches it gives ``e`` to 2e-5 with no lag and a load gain of one; the other
    reads the base half a sample off (a staircase is a smooth base half a sample late) and
    ``e`` a little off; the answer's interval is the union of both and holds ``e``."""
    for seed in range(2):
        theta, base = tr.transient_with_base(0.8, seed, peak=1.6, noise=0.0, substeps=substeps)
        fit = _fit(theta, base)
        assert fit.reason is None and fit.impacts >= 20
        good, other = fit.readings[right], fit.readings[wrong]
        assert abs(good.e - 0.8) < 2e-5 and abs(good.load_gain - 1.0) < 1e-4 and abs(good.shift) < 0.01, (seed, good)
        assert abs(other.e - 0.8) < 5e-4 and abs(other.load_gain - 1.0) < 2e-3 and abs(other.shift - lag) < 0.01, (seed, other)
        lo, hi = fit.e_interval
        assert lo <= 0.8 <= hi
        for r in (good, other):
            assert lo <= r.e_interval[0] and r.e_interval[1] <= hi
        assert min(r.e_interval[0] for r in (good, other)) == lo and max(r.e_interval[1] for r in (good, other)) == hi
        assert fit.e == pytest.approx(math.sqrt(lo * hi), rel=1e-12)
        assert fit.reading_gap == pytest.approx(abs(math.log(good.e) - math.log(other.e)), rel=1e-9)


@pytest.mark.slow
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
    theta, base = tr.transient_with_base(0.9, 5, peak=1.6, noise=0.005, substeps=8, **SHORT)
    one = _fit(theta, base)
    assert _fit(-theta, -base).e == pytest.approx(one.e, abs=1e-9)
    assert _fit(theta, -base).e == pytest.approx(one.e, abs=1e-9)


def test_a_block_of_three_times_the_angle_gives_the_same_e_and_three_times_g():
    """The base over the uplift level unchanged, the angle three times: a block of three times
    ``g`` under three times the load."""
    theta, base = tr.transient_with_base(0.9, 6, peak=1.6, noise=0.005, substeps=8, **SHORT)
    one = _fit(theta, base)
    scaled = _fit(3.0 * theta, base)
    assert scaled.e == pytest.approx(one.e, abs=1e-9) and scaled.g == pytest.approx(3.0 * one.g, rel=1e-9)
    assert scaled.load_gain == pytest.approx(one.load_gain, rel=1e-9)


def test_a_base_in_the_wrong_units_is_refused_with_the_load_it_reads():
    theta, base = tr.transient_with_base(0.9, 7, peak=1.6, noise=0.005, substeps=8, **SHORT)
    fit = analyse_forced(theta, base / (2.0 * tr.G), DT)
    assert math.isnan(fit.e) and fit.load_gain == pytest.approx(2.0, rel=0.01)
    assert f"as {fit.load_gain:.3g} times what its units" in fit.reason


def test_pooled_records_read_their_impacts_together():
    """Each reading pooled over the records apart, the answer the union of the two pools."""
    fits = [_fit(*tr.transient_with_base(0.9, seed, peak=1.6, noise=0.01, substeps=8)) for seed in range(3)]
    pooled = pool_forced(fits)
    assert pooled.impacts <= sum(f.impacts for f in fits) and pooled.impacts >= max(f.impacts for f in fits)
    assert pooled.e_interval[0] <= 0.9 <= pooled.e_interval[1]
    assert pooled.e_interval[1] - pooled.e_interval[0] < np.median([f.e_interval[1] - f.e_interval[0] for f in fits])
    for name in READINGS:
        alone = pool_forced([f.readings[name] for f in fits])
        assert pooled.readings[name].e == pytest.approx(alone.e, rel=1e-12)
        assert pooled.e_interval[0] <= alone.e_interval[0] and alone.e_interval[1] <= pooled.e_interval[1]
    assert math.isfinite(pooled.reading_gap)


def test_a_reading_refused_leaves_no_e_and_names_it():
    """The union needs both readings: one refused (here by hand), the answer is refused with
    that reading's reason, the other's ``e`` kept in ``readings``."""
    theta, base = tr.transient_with_base(0.9, 8, peak=1.6, noise=0.01, substeps=8)
    fit = _fit(theta, base)
    held = ForcedFit.none("the record gives 3 impacts whose arcs fit either side, fewer than 5")
    one = forced._enveloped({"linear": fit.readings["linear"], "held": held})
    assert math.isnan(one.e) and one.reason.startswith("with the base read held between samples, the record gives 3")
    assert one.readings["linear"].e == fit.readings["linear"].e and math.isnan(one.reading_gap)
    pooled = pool_forced([fit, one])
    assert pooled.e == pytest.approx(fit.e, rel=1e-12) and pooled.e_interval == pytest.approx(fit.e_interval, rel=1e-12)


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


def test_base_integrals_held_match_a_staircase_integrated_numerically():
    """The base held over each sample: V and L against the staircase itself, integrated twice
    by the trapezoid rule on 2,000 points a sample (exact for V; L to the rule's error)."""
    a = np.random.default_rng(3).standard_normal(30)
    dt, fine = 0.005, 2000
    u = (np.arange(a.size * fine) + 0.5) / fine  # midpoints of the fine steps, in samples
    staircase = a[np.floor(u).astype(int)]
    v_fine = np.concatenate([[0.0], np.cumsum(staircase * dt / fine)])
    l_fine = np.concatenate([[0.0], np.cumsum(0.5 * (v_fine[:-1] + v_fine[1:]) * dt / fine)])
    v, l = base_integrals(a, dt, reading="held")
    np.testing.assert_allclose(v, v_fine[::fine][: a.size], rtol=0, atol=1e-13)
    np.testing.assert_allclose(l, l_fine[::fine][: a.size], rtol=0, atol=1e-12)
    assert np.max(np.abs(l - base_integrals(a, dt)[1])) > 1e-6  # the readings differ
    with pytest.raises(ValueError, match="not one of linear, held"):
        base_integrals(a, dt, reading="cubic")


def test_the_interval_is_never_narrower_than_its_floor():
    theta, base = tr.transient_with_base(0.95, 0, peak=1.6, noise=0.0, substeps=8, **SHORT)
    lo, hi = _fit(theta, base).e_interval
    assert math.log(hi) - math.log(lo) >= 2 * FLOOR * (1 - 1e-9)


def test_the_document_and_summary_show_both_readings_and_their_gap():
    """The shake-table document (schema-valid) carries each reading's ``e`` and interval, per
    record and pooled, and the gap between them; the summary names both (a base held over each
    sample: the held reading finds no lag)."""
    import json

    import jsonschema

    import rockdec
    from rockdec.report import result as result_mod

    theta, base = tr.transient_with_base(0.8, 3, peak=1.6, noise=0.01)
    res = rockdec.shake_table(theta, base, DT, base_units="rad/s2", g_block=tr.G)
    doc = json.loads(json.dumps(res.to_dict()))
    jsonschema.validate(doc, result_mod.schema())
    table = doc["shake_table"]["forced"]
    for entry in (table, *table["records"]):
        assert set(entry["readings"]) == set(READINGS)
        values = [entry["readings"][name]["e"] for name in READINGS]
        assert entry["reading_gap"] == pytest.approx(abs(math.log(values[0]) - math.log(values[1])), rel=1e-9)
        for name in READINGS:
            lo, hi = entry["readings"][name]["interval"]
            assert entry["interval"][0] <= lo and hi <= entry["interval"][1]
    assert table["readings"]["held"]["base_shift"] is None and abs(table["records"][0]["readings"]["held"]["base_shift"]) < 0.1
    assert doc["estimator"] == "forced" and doc["interval"] == table["interval"]
    assert f"linear: {table['readings']['linear']['e']:.4f}, held: {table['readings']['held']['e']:.4f}" in res.summary()

"""A low-pass filter after the block (issue 38): declared (:class:`SensorFilter`, applied by the
calibration to its simulated sets), measured (the roll-off of the second differences,
:func:`rockdec.record.record_measure.rolloff`), and declared parts of the model checked
against the record."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy import signal

from rockdec.api import estimate_options
from rockdec.calibrate import calibration
from rockdec import estimation
from rockdec.report.estimate_report import document
from stand_in_outcome import stand_in
from rockdec.cli import main
from rockdec.physics.record_model import Load, RecordModel, SensorFilter, SensorNoise, parse_sensor_filter
from rockdec.physics.simulate import simulate_block
from rockdec.rdd import measured
from rockdec.record import diagnostics, record_measure
from rockdec.record.records import Record
from rockdec.validate import InputError

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from rocking_reference import flight_reference  # noqa: E402

# As tests/calibrate/test_estimate_model.py: about 75 samples per cycle at e = 0.9, g = sigma_p = 1.
DT_WHITE, BURN_IN, E = 0.8043, 4362, 0.9
SMALL_GRID, SMALL_SETS = (0.6, 0.75, 0.85, 0.9, 0.95, 0.98), 6


def _record(seed, n=40_000):
    return simulate_block([seed], n, dt=DT_WHITE, g=1.0, e=E, sigma_p=1.0, burn_in=BURN_IN)[0][0]


def _reference(seed, n=30_000, burn=3000):
    """A record of the independent pure-Python simulator (tests/rocking_reference.py)."""
    pushes = np.random.default_rng(seed).standard_normal(n + burn)
    theta, omega, out = 0.0, 0.0, np.empty(n)
    for k in range(n + burn):
        theta, omega = flight_reference(theta, omega + pushes[k], DT_WHITE, 1.0, E)
        if k >= burn:
            out[k - burn] = theta
    return out


@pytest.mark.parametrize("text", ["butterworth:4:10:zero-phase", "butterworth:1:3.5:causal", "butterworth:8:20:causal",
                                  "rc:5:causal", "rc:12.5hz:zero-phase", "butterworth:2:40hz:causal"])
def test_a_filter_text_round_trips_through_the_model_key_and_attributes(text):
    found = parse_sensor_filter(text)
    assert parse_sensor_filter(found.text()) == found
    assert SensorFilter.from_dict(found.to_dict()) == found
    model = RecordModel(load=Load("lowpass", 3.0), sensor=SensorNoise(0.02), filter=found)
    assert RecordModel.from_key(model.key()) == model
    assert RecordModel.from_attrs(model.to_attrs()) == model


def test_no_filter_leaves_the_key_of_the_papers_model_unchanged():
    assert "sensor_filter" not in RecordModel().key() and RecordModel.from_key(RecordModel().key()).filter is None
    assert parse_sensor_filter("none") is None and parse_sensor_filter(" AUTO ") == "auto"


@pytest.mark.hostile("numbers", "refused")
@pytest.mark.parametrize("text, words", [
    ("butterworth:9:10:causal", "order 9"), ("butterworth:0:10:causal", "order 0"), ("butterworth:2.5:10:causal", "order 2.5"),
    ("butterworth:4:10", "not a filter"), ("rc:5", "not a filter"), ("rc:2:5:causal", "not a filter"),
    ("bessel:4:10:causal", "not a filter"), ("rc:5:sideways", "phase 'sideways'"), ("rc:0:causal", "corner 0"),
    ("rc:-3:causal", "corner -3"), ("rc:nan:causal", "corner nan"), ("rc:inf:causal", "corner inf"), ("rc:fast:causal", "numbers"),
])
def test_a_bad_filter_is_refused_in_one_sentence(text, words):
    with pytest.raises(InputError, match=words) as info:
        parse_sensor_filter(text)
    assert "\n" not in str(info.value)


@pytest.mark.hostile("numbers", "refused")
def test_a_corner_at_or_above_nyquist_and_a_filter_without_its_load_are_refused():
    with pytest.raises(InputError, match="Nyquist"):
        SensorFilter("rc", 1, 40.0).cycles_per_sample(75.0)
    with pytest.raises(InputError, match="`load` and `sensor_noise` beside it"):
        estimate_options(sensor_filter="rc:5:causal")
    assert estimate_options(sensor_filter="rc:5:causal", load="white", sensor_noise="0")[0]["sensor_filter"] == SensorFilter("rc", 1, 5.0)


@pytest.mark.parametrize("found", [SensorFilter("butterworth", 4, 10.0, True), SensorFilter("butterworth", 3, 5.0, False),
                                   SensorFilter("rc", 1, 5.0, True), SensorFilter("rc", 1, 3.0, False)])
def test_the_calibrations_filtered_set_is_scipys_filter_of_the_unfiltered_set(found):
    """Seam of the calibration: the block's angle through the filter (scipy.signal, written out
    here), then the sensor noise; with no noise, exactly scipy's filter of the unfiltered set."""
    ppc, lengths = 75.0, [3000, 5000]
    plain = calibration._simulate_set(7, lengths, DT_WHITE, E, 500, RecordModel())
    filtered = calibration._simulate_set(7, lengths, DT_WHITE, E, 500, RecordModel(filter=found), points_per_cycle=ppc)
    for y, z in zip(plain, filtered):
        if found.kind == "rc":
            a = math.exp(-2.0 * math.pi * found.corner / ppc)
            want = (signal.filtfilt if found.zero_phase else signal.lfilter)([1.0 - a], [1.0, -a], y)
        else:
            sos = signal.butter(found.order, 2.0 * found.corner / ppc, output="sos")
            want = (signal.sosfiltfilt if found.zero_phase else signal.sosfilt)(sos, y)
        np.testing.assert_allclose(z, want, rtol=1e-12, atol=1e-15 * np.abs(y).max())


def test_binned_filter_keeps_its_corner_per_sample_within_half_a_bin():
    rng = np.random.default_rng(4)
    for ppc, corner in zip(rng.uniform(30, 300, 40), rng.uniform(1.0, 12.0, 40)):
        model = RecordModel(filter=SensorFilter("butterworth", 4, corner, True))
        binned = RecordModel.from_key(calibration.calibration_settings([20_000], ppc, model=model)["record_model"])
        per_sample = binned.filter.corner / calibration.ppc_key(ppc)
        assert abs(math.log(per_sample / (corner / ppc))) <= calibration.FILTER_BIN / 2 + 1e-3


@pytest.mark.parametrize("make", [_reference, _record], ids=["reference simulator", "kernel"])
def test_the_rolloff_tells_a_filtered_record_from_the_same_record_unfiltered(make):
    """An unfiltered record keeps its steps and impacts (second differences falling no faster
    than f^-2); the same through a Butterworth of order 4 at 5 rocking frequencies falls far faster."""
    y = make(11)
    ppc = measured.analyse([y], DT_WHITE).points_per_cycle
    clean = record_measure.rolloff(y, ppc)
    assert not clean.filtered and clean.slope.value > record_measure.ROLLOFF_FLOOR
    for zero in (True, False):
        z = SensorFilter("butterworth", 4, 5.0, zero).apply(y, ppc)
        found = record_measure.rolloff(z, ppc)
        assert found.filtered and found.slope.value < 2 * record_measure.ROLLOFF_FLOOR


def test_rolloff_of_a_closed_form_spectrum_reads_its_slope():
    """White second differences through a known first-order filter applied twice (gain
    ``1/(1 + (f/f_c)^2)^2``, the sampled stage flattening it near Nyquist): far above its corner its slope, steeper than any
    unfiltered record's."""
    d = np.random.default_rng(5).standard_normal(400_000)
    y = np.cumsum(np.cumsum(SensorFilter("rc", 1, 2.0, True).apply(d, 75.0)))
    found = record_measure.rolloff(y, 75.0)
    a = math.exp(-2.0 * math.pi * 2.0 / 75.0)
    lo, hi = found.band
    f = np.linspace(lo, hi, 200) / 75.0  # cycles per sample
    gain = np.abs(signal.freqz([1.0 - a], [1.0, -a], worN=2 * np.pi * f)[1]) ** 4  # forward and back: the gain squared
    want = np.polyfit(np.log(f), np.log(gain), 1)[0]
    assert found.slope.value == pytest.approx(want, abs=0.1) and want < record_measure.ROLLOFF_FLOOR - 0.5 and found.filtered
    assert record_measure.rolloff(y[:200], 75.0) is None or not math.isnan(record_measure.rolloff(y[:200], 75.0).z)
    assert record_measure.rolloff(y, 10.0) is None  # no band below 0.4 of 10 samples per cycle


def _analysed(y):
    return estimation.analyse([Record(y, DT_WHITE, "record")])


@pytest.mark.hostile("wrong answers", "warned")
def test_a_declared_part_the_record_contradicts_is_noted_and_a_right_one_is_not():
    analysed = _analysed(_record(3, n=60_000))
    right = estimation.choose_model(analysed, load=Load(), sensor=SensorNoise())
    assert right.notes == ()
    noisy = estimation.choose_model(analysed, load=Load(), sensor=SensorNoise(0.2))
    assert [n.code for n in noisy.notes] == ["noise_contradicted"] and "0.2 sigma_Y" in noisy.notes[0].message
    coloured = estimation.choose_model(analysed, load=Load("lowpass", 3.0), sensor=SensorNoise())
    assert [n.code for n in coloured.notes] == ["load_contradicted"]
    assert set(estimation.NOTE_CODES) >= {"noise_contradicted", "load_contradicted"}


@pytest.fixture
def small_calibration(monkeypatch):
    monkeypatch.setattr(calibration, "E_GRID", SMALL_GRID)
    monkeypatch.setattr(calibration, "SETS_PER_E", SMALL_SETS)
    monkeypatch.setattr(calibration, "SETS_PER_E_CAPPED", SMALL_SETS)


@pytest.mark.hostile("wrong answers", "refused or answered")
@pytest.mark.slow
def test_a_filtered_record_is_declined_undeclared_and_covered_declared(tmp_path, small_calibration, capsys):
    y = _record(17, n=60_000)
    ppc = measured.analyse([y], DT_WHITE).points_per_cycle
    sos = signal.butter(4, 2.0 * 5.0 / ppc, output="sos")
    z = signal.sosfiltfilt(sos, y)
    path = tmp_path / "r.npy"
    np.save(path, z)
    hz = 5.0 / (DT_WHITE * ppc)
    common = ["estimate", str(path), "--dt", str(DT_WHITE), "--cache", str(tmp_path / "cache"), "--json"]
    assert main(common) == 0
    import json

    doc = json.loads(capsys.readouterr().out)
    assert doc["e"] is None and "`sensor_filter`" in doc["reason"] and doc["record_model"]["filter_rolloff"]["detected"]
    # as given: the checks' thresholds of this small calibration fire often, and a fired check starts the repair
    assert main([*common, "--sensor-filter", f"butterworth:4:{hz:.8g}hz:zero-phase", "--load", "white", "--sensor-noise", "0", "--no-repair"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["record_model"]["simulated"]["sensor_filter"]["order"] == 4
    assert doc["record_model"]["sources"]["sensor_filter"] == "declared"
    assert doc["interval"][0] <= E <= doc["interval"][1]


@pytest.mark.hostile("wrong answers", "refused")
@pytest.mark.parametrize("make", [_reference, _record], ids=["reference simulator", "kernel"])
def test_a_gentle_filter_blunts_the_impacts_where_the_spectrum_cannot_show_it(make):
    """A first-order RC stage (causal at 3, 5 and 10 rocking frequencies, zero-phase at 20)
    passes the roll-off floor, and the fit reads it as a low-pass load; but it spreads each
    impact's velocity jump over several samples, so the statistic of the check ``filtered``
    (the one-sample log ratio less the four-sample one: negative for a sharp jump) rises above
    the unfiltered record's by more than 0.01."""
    y = make(11)
    ppc = measured.analyse([y], DT_WHITE).points_per_cycle
    sharpness = (lambda x: diagnostics.impact_sharpness(diagnostics.sums([x]), None))
    clean = sharpness(y)
    assert clean < 0.0
    for found in (SensorFilter("rc", 1, 3.0, False), SensorFilter("rc", 1, 5.0, False), SensorFilter("rc", 1, 10.0, False),
                  SensorFilter("rc", 1, 20.0, True)):
        z = found.apply(y, ppc)
        choice = estimation.choose_model(_analysed(z))
        assert choice.declined is None and not choice.rolloff.filtered, found.text()
        assert sharpness(z) > clean + 0.01, found.text()


@pytest.mark.hostile("wrong answers", "refused")
@pytest.mark.slow
def test_a_gentle_filter_undeclared_is_declined_by_the_calibrated_check(tmp_path, small_calibration, monkeypatch):
    """A causal RC stage at 5 rocking frequencies, end to end: the calibration's unfiltered
    records hold sharper impacts, ``filtered`` fires, and ``e`` is declined naming the
    declaration that would help. Twice the small calibration's sets: the threshold pools
    every grid point the record's wide interval reaches, and a tail quantile of 6 sets a
    point rests on the few largest of them."""
    from rockdec.api import estimate as estimate_record

    monkeypatch.setattr(calibration, "SETS_PER_E", 2 * SMALL_SETS)
    y = _record(17, n=60_000)
    z = SensorFilter("rc", 1, 5.0, False).apply(y, measured.analyse([y], DT_WHITE).points_per_cycle)
    doc = estimate_record(z, DT_WHITE, cache=tmp_path).to_dict()
    assert doc["diagnostics"]["filtered"]["fired"] and doc["diagnostics"]["filtered"]["statistic"] > 0.0
    assert doc["e"] is None and "filtered" in doc["reason"] and "`sensor_filter`" in doc["reason"]


@pytest.mark.parametrize("source, declined", [("measured (none shown)", True), ("declared", False)])
def test_a_fired_filter_check_declines_unless_the_filter_was_declared(source, declined):
    verdict = estimation.Verdict(True, False, False, source == "declared", {"filtered": "the impacts' velocity jumps are spread"}, False)
    out = estimation.decline_unrepaired(stand_in(verdict))
    assert (out.declined is not None) == declined and (out.shown is None) == declined
    assert not declined or "filtered: the impacts' velocity jumps are spread" in out.declined


@pytest.mark.parametrize("source", ["measured (none shown)", "declared"])
def test_a_filter_shown_on_the_records_as_given_is_not_high_passed(monkeypatch, source):
    """A causal filter rings after each impact and can fire ``spikes`` beside ``filtered``;
    the high-pass that spikes would start cannot remove a filter and moves the zero crossings
    off the impacts, so an undeclared filter declines ``e`` on the records as given, its reason
    first. Declared, ``filtered`` only warns and the repair goes on."""
    calls = []

    def once(records, repaired, simulated_repair=None, **kwargs):
        calls.append(simulated_repair)
        fired = {"spikes": "a sample stands far off", "filtered": "the impacts' velocity jumps are spread"}
        return stand_in(estimation.Verdict(True, False, False, source == "declared", fired, bool(calls[1:])))

    monkeypatch.setattr(estimation.retry, "estimate_once", once)
    y = _record(5, n=20_000)
    out = estimation.estimate([Record(y, DT_WHITE, "record")], cache_dir=None)
    if source == "declared":
        assert len(calls) == 2 and out.declined.startswith("the records show a defect") and "filtered" not in out.declined
    else:
        assert len(calls) == 1 and out.shown is None and "(filtered: the impacts' velocity jumps are spread; spikes:" in out.declined


def test_a_drifting_record_that_shows_a_filter_is_high_passed_and_read_again(monkeypatch):
    """A drifting zero moves the zero crossings off the impacts and fires ``filtered`` on
    unfiltered records (benchmarks/repair_study.py: most drift records were declined for a
    filter): with ``drift`` fired beside it, the records are high-passed and estimated again,
    and ``e`` is declined only when a check still fires on the repaired records."""
    calls = []

    def once(records, repaired, simulated_repair=None, **kwargs):
        calls.append(simulated_repair)
        fired = {"filtered": "the impacts' velocity jumps are spread", "drift": "the zero drifts"} if len(calls) == 1 else {}
        return stand_in(estimation.Verdict(True, False, False, False, fired, len(calls) > 1))

    monkeypatch.setattr(estimation.retry, "estimate_once", once)
    y = _record(5, n=20_000)
    out = estimation.estimate([Record(y, DT_WHITE, "record")], cache_dir=None)
    assert len(calls) == 2 and calls[1] is not None and out.shown.e == 0.9 and out.verdict.repaired


@pytest.fixture(scope="module")
def white_record():
    y = _record(29, n=100_000)
    return y, measured.analyse([y], DT_WHITE).points_per_cycle


@pytest.mark.hostile("wrong answers", "refused")
@pytest.mark.parametrize("found", [
    SensorFilter(kind, order, corner, zero)
    for kind, order in (("butterworth", 2), ("butterworth", 3), ("butterworth", 4))
    for corner in (3.0, 5.0, 10.0) for zero in (True, False)
], ids=lambda f: f.text())
def test_an_undeclared_filter_declines_e_naming_the_declaration(white_record, found):
    """The matrix's steep filters (issue 38): a white-load record through a Butterworth filter
    of order 2 to 4 falls faster than f^-3 and is declined before any calibration, the reason
    naming `sensor_filter` (first-order stages: the calibrated check, tests above)."""
    y, ppc = white_record
    choice = estimation.choose_model(_analysed(found.apply(y, ppc)))
    assert choice.declined and "`sensor_filter`" in choice.declined


@pytest.mark.hostile("wrong answers", "warned")
@pytest.mark.parametrize("declared, code", [
    ({"load": Load(), "sensor": SensorNoise(0.05)}, "noise_contradicted"),
    ({"load": Load(), "sensor": SensorNoise(0.2)}, "noise_contradicted"),
    ({"load": Load("lowpass", 2.0), "sensor": SensorNoise()}, "load_contradicted"),
    ({"load": Load("lowpass", 5.0), "sensor": SensorNoise()}, "load_contradicted"),
], ids=["noise 5%", "noise 20%", "lowpass:2", "lowpass:5"])
def test_a_declaration_the_white_record_contradicts_is_warned(white_record, declared, code):
    choice = estimation.choose_model(_analysed(white_record[0]), **declared)
    assert code in [n.code for n in choice.notes]

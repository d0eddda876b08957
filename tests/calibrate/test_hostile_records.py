"""Records that once gave a confident wrong ``e`` with no warning: records pooled at
different scales (units), a logger's held samples, integer counts, a base record sampled
more coarsely than the rocking record. Each is refused, declined, warned or answered right
before any calibration is built (or with the fake calibration of ``tests/fake_calibration.py``)."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from rockdec.calibrate import calibration, consistency

from rockdec import estimation

from rockdec.physics.record_model import NO_NOISE
from rockdec.report.estimate_report import document
from rockdec.physics import simulate
from rockdec.rdd import measured
from rockdec.record.records import Record, RecordError

from conftest import calibrated_step
from test_hostile import hostile, marked, refused

E, G, SIGMA_P = 0.85, 1.0, 0.003


@pytest.fixture(scope="module")
def block():
    """Six records of one block (e = 0.85, g = 1 rad/s^2, 20,000 samples each, their own seeds)
    at one step, and that step; two more at twice the load."""
    cal = calibrated_step(E, G, SIGMA_P)
    dt, burn = cal["dt"], cal["burn_in"]
    theta = simulate.simulate_block(list(range(21, 27)), 20_000, dt=dt, g=G, e=E, sigma_p=SIGMA_P, burn_in=burn)[0]
    louder = simulate.simulate_block([31, 32], 20_000, dt=dt, g=G, e=E, sigma_p=2 * SIGMA_P, burn_in=burn)[0]
    return {"theta": theta, "louder": louder, "dt": dt}


@pytest.fixture
def fake_cal(monkeypatch, tmp_path):
    """A calibration without simulation (``tests/fake_calibration.py``)."""
    import fake_calibration

    monkeypatch.setattr(calibration, "_grid_point", fake_calibration.grid_point)
    return tmp_path / "calibration"


def _csv(path, theta, dt):
    np.savetxt(path, np.c_[np.arange(theta.size) * dt, theta], delimiter=",", header="time,theta", comments="", fmt="%.12g")
    return path


#: The scale of each record of a pair given together: one of them in other units.
UNITS = {
    "rad and degrees": (1.0, 180.0 / math.pi, "as degrees against rad give"),
    "degrees and rad": (180.0 / math.pi, 1.0, "as degrees against rad give"),
    "rad and mrad": (1.0, 1e3, "as mrad against rad"),
    "rad and µrad": (1.0, 1e6, "as µrad against rad give"),
    "degrees and mrad": (180.0 / math.pi, 1e3, "as mrad against degrees give"),
}


@pytest.mark.parametrize("first, second, named", marked(UNITS, "units"))
def test_records_pooled_in_different_units_are_refused_before_any_calibration(block, tmp_path, capsys, first, second, named):
    """Two records of one block, one of them in degrees (or mrad, µrad): the one in the larger
    unit alone set the trigger levels, and the pooled interval was calibrated for both
    records' samples (0.896 [0.873, 0.915] for 0.85). Their own g lie the units' factor apart."""
    a = _csv(tmp_path / "a.csv", first * block["theta"][0], block["dt"])
    b = _csv(tmp_path / "b.csv", second * block["theta"][1], block["dt"])
    out = tmp_path / "out"
    out.mkdir()
    refused(["estimate", str(a), str(b), "--cache", str(tmp_path / "cache"), "--plot", str(out / "e.png")], out, capsys,
            ["the records seem to be in different units", "give them in one unit (rad)", named, "sigma_Y"])
    assert not (tmp_path / "cache").exists()


@hostile("units", "refused")
def test_the_api_refuses_a_list_of_records_in_different_units(block, tmp_path):
    import rockdec

    with pytest.raises(RecordError, match="different units"):
        rockdec.estimate([block["theta"][0], np.degrees(block["theta"][1])], dt=block["dt"], cache=tmp_path)
    assert not any(tmp_path.iterdir())


@hostile("wrong answers", "refused")
def test_records_whose_own_g_lie_apart_beyond_one_blocks_are_declined_naming_each(block, fake_cal):
    """A record of a block whose g is 6 times the other's (the same motion at 6 times the
    angle): e is declined before any calibration, each record's own g named."""
    recs = [Record(block["theta"][0], block["dt"], "a.csv"), Record(6.0 * block["theta"][1], block["dt"], "b.csv")]
    doc = document(estimation.estimate(recs, cache_dir=fake_cal, load="white", sensor=NO_NOISE))
    assert doc["e"] is None and doc["calibration"]["file"] is None
    ratio, a, b = map(float, re.search(r"read g alone ([0-9.]+) times apart \(a\.csv ([0-9.]+), b\.csv ([0-9.]+) rad/s\^2\)",
                                       doc["reason"]).groups())
    assert 0.5 < a < 2.0 and b / a == pytest.approx(ratio, rel=0.01) and 4.0 < ratio < 10.0, doc["reason"]
    assert f"beyond the {consistency.G_FACTOR:g}" in doc["reason"]


@hostile("wrong answers", "answered")
def test_records_of_one_block_pass_the_scales_check_at_one_load_and_at_twice_the_load(block):
    """Six records at one load (15 pairs) and two at twice the load, whose sigma_Y lie several
    times apart: g is one block's constant, and no pair is declined or refused."""
    sigmas, gs = estimation.own_scales([Record(y, block["dt"], "r") for y in [*block["theta"], *block["louder"]]], block["dt"],
                                      dict(measured.DEFAULT_SETTINGS))
    assert np.all(np.isfinite(gs))
    assert max(sigmas[6:]) / min(sigmas[:6]) > 2.0  # the louder records' amplitude
    for i in range(len(gs)):
        for j in range(i + 1, len(gs)):
            assert consistency.scales_apart(["a", "b"], [sigmas[i], sigmas[j]], [gs[i], gs[j]]) is None, (i, j, gs)
    analysed = estimation.analyse([Record(block["theta"][0], block["dt"], "a"), Record(block["louder"][0], block["dt"], "b")])
    assert analysed.scales_apart is None


def test_the_scales_check_names_the_units_from_the_ratio_of_g():
    """Closed forms: a ratio within UNITS_NEAR of a units factor names it; beyond the factor
    of one block, under UNITS_RATIO, it is a decline; within it nothing; unread g is left out."""
    for factor, words in consistency.UNITS.items():
        out = consistency.scales_apart(["a", "b"], [1.0, factor], [2.0, 2.0 * factor * 1.2])
        assert out.kind == "units" and words in out.message
    assert consistency.scales_apart(["a", "b"], [1.0, 1.0], [1.0, 0.5 / consistency.UNITS_RATIO]).kind == "units"
    assert "as " not in consistency.scales_apart(["a", "b"], [1.0, 1.0], [1.0, 300.0]).message.split("times")[-1]
    assert consistency.scales_apart(["a", "b"], [1.0, 1.0], [1.0, consistency.G_FACTOR * 1.01]).kind == "blocks"
    assert consistency.scales_apart(["a", "b"], [1.0, 9.0], [1.0, consistency.G_FACTOR * 0.99]) is None
    assert consistency.scales_apart(["a", "b", "c"], [1.0, 1.0, 1.0], [1.0, math.nan, 100.0]).kind == "units"
    assert consistency.scales_apart(["a", "b"], [1.0, 1.0], [1.0, math.nan]) is None


def _hold(theta: np.ndarray, h: int) -> np.ndarray:
    """``theta`` as a logger that holds each value for ``h`` samples writes it."""
    out = theta.copy()
    for i in range(1, h):
        out[i::h] = theta[0::h][: out[i::h].size]
    return out


HOLDS = {f"hold of {h}": (h, nth) for h, nth in ((2, "2nd"), (3, "3rd"), (4, "4th"))}


@pytest.mark.parametrize("h, nth", marked(HOLDS, "wrong answers"))
def test_a_record_whose_logger_held_each_value_is_refused_naming_the_true_rate(block, tmp_path, capsys, h, nth):
    """y[1::2] = y[0::2] answered 0.772 [0.679, 0.843] for 0.85 (3 of 7 seeds answered, all
    low). The hold is named with the rate the record was truly sampled at."""
    path = _csv(tmp_path / "held.csv", _hold(block["theta"][0], h), block["dt"])
    out = tmp_path / "out"
    out.mkdir()
    refused(["estimate", str(path), "--cache", str(tmp_path / "cache"), "--plot", str(out / "e.png")], out, capsys,
            [f"the record repeats every {nth} sample", f"each value held for {h} samples", "a logger holding its value",
             f"every {nth} sample from sample 0", f"a step of {h * block['dt']:.6g} s"])


@hostile("wrong answers", "answered")
def test_records_quantised_to_counts_are_not_taken_for_held_ones(block):
    """Integer counts at a resolution of sigma_Y / 200 down to / 5 hold some values at the
    turning points, alike at every phase: six records, none refused; held, each is found."""
    from rockdec.record.records import held

    for y in block["theta"]:
        for lsb in (200, 20, 5):
            counts = np.round(y / (np.std(y) / lsb))
            assert held(Record(counts, block["dt"], "r")) is None, lsb
            assert "held for 2 samples" in held(Record(_hold(counts, 2), block["dt"], "r"))


def _base_csv(path, dt, n=20_000, seed=3):
    """A base-acceleration record, white noise at a step ``dt`` (s)."""
    accel = np.random.default_rng(seed).standard_normal(n)
    np.savetxt(path, np.c_[np.arange(n) * dt, accel], delimiter=",", header="time,acceleration", comments="", fmt="%.10g")
    return path


@pytest.fixture(scope="module")
def analysed_block(block):
    return estimation.analyse([Record(block["theta"][0], block["dt"], "rec.csv")])


@hostile("wrong answers", "warned")
@pytest.mark.parametrize("coarser", [2, 5.6])
def test_a_base_record_sampled_more_coarsely_than_the_rocking_record_is_warned(analysed_block, block, tmp_path, coarser):
    """A base record at 5.6 times the rocking record's step stops its spectrum at 6.7 rocking
    frequencies; the calibration drew no load above it, and the interval came out 2.4 times
    too narrow with no warning. The warning names where the spectrum stops (the base record's
    Nyquist frequency in rocking frequencies, N / (2 x coarser)) and the rocking record's."""
    base = _base_csv(tmp_path / "ground.csv", coarser * block["dt"])
    choice = estimation.choose_model(analysed_block, load=f"base:{base}", sensor=NO_NOISE)
    ppc = analysed_block.analysis.points_per_cycle
    notes = [n.message for n in choice.notes if n.code == "base_short"]
    assert len(notes) == 1 and choice.declined is None
    top = ppc / (2 * coarser)
    assert f"stops at its Nyquist frequency, {top:.3g} times the rocking frequency" in notes[0], (notes, top)
    assert f"below the rocking record's {ppc / 2:.3g}" in notes[0] and f"sampled {coarser:.3g} times as finely" in notes[0]
    assert "base_short" in estimation.NOTE_CODES
    assert choice.model.load.frequency[-1] == pytest.approx(top, rel=1e-9)  # the table's last row: where the calibration's load stops


@hostile("wrong answers", "answered")
@pytest.mark.parametrize("finer", [1, 2])
def test_a_base_record_sampled_as_finely_as_the_rocking_record_is_not_warned(analysed_block, block, tmp_path, finer):
    base = _base_csv(tmp_path / "ground.csv", block["dt"] / finer)
    choice = estimation.choose_model(analysed_block, load=f"base:{base}", sensor=NO_NOISE)
    assert not [n for n in choice.notes if n.code == "base_short"]
    assert choice.model.load.frequency[-1] >= analysed_block.analysis.points_per_cycle / 2 * (1 - 1e-9)


def test_the_calibrations_load_holds_no_power_above_the_tables_last_row():
    """What base_short warns of: spectral_gain sets S = 0 above the table's last frequency."""
    from rockdec.physics.loading import ImpulseSpectrum, spectral_gain

    gain = spectral_gain(ImpulseSpectrum((0.01, 0.1), (1.0, 1.0)), 1000)
    bins = np.arange(gain.size) / 1000
    assert np.all(gain[bins > 0.1] == 0.0) and np.all(gain[(bins >= 0.01) & (bins <= 0.1)] > 0.0)


@hostile("wrong answers", "warned")
def test_integer_counts_too_coarse_for_the_impacts_leave_the_filter_check_out_with_a_warning(block):
    """Counts of sigma_Y / 200 (an encoder's integers): the one-sample velocities at the
    impacts are a few tens of counts, their ratios snap the median of the check ``filtered``
    to a ratio of integers (0 at e near 1), and at e = 0.95 it fired on 4 of 12 clean records
    rounded so (1 of 12 unrounded): e declined for nothing. The check now leaves such records
    out, with a warning naming the resolution; finer counts keep it, at the unrounded value."""
    from rockdec.record import diagnostics

    def sharpness(y):
        return diagnostics.impact_sharpness(diagnostics.sums([y]), None)

    for i, y in enumerate(block["theta"]):
        sigma = np.std(y)
        coarse, fine = np.round(y / (sigma / 200)), np.round(y / (sigma / 20_000))
        assert diagnostics.resolution(coarse) == 1.0 and diagnostics.resolution(y) == 0.0
        assert diagnostics.impact_steps(coarse) < diagnostics.IMPACT_MIN_STEPS <= diagnostics.impact_steps(fine)
        assert math.isnan(sharpness(coarse)) and sharpness(fine) == pytest.approx(sharpness(y), abs=0.005)
        (note,) = estimation.unresolved_impacts([Record(coarse, block["dt"], f"r{i}.csv")])
        assert note.code == "filtered_unchecked" and note.message.startswith(f"r{i}.csv is quantised to steps of 1,")
        assert "was not checked for a low-pass filter" in note.message
        assert estimation.unresolved_impacts([Record(y, block["dt"], "r"), Record(fine, block["dt"], "f")]) == []
    assert "filtered_unchecked" in estimation.NOTE_CODES

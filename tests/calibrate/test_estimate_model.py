"""`rockdec estimate` under the record's own model: measured or declared, binned into the
calibration's key, simulated by the calibration, reported; the reported estimator is the
narrowest trusted candidate, and no value comes without a reason."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from rockdec.calibrate import belt, calibration

from rockdec import estimation
from rockdec.rdd import measured
from rockdec.record import record_measure
from rockdec.api import estimate_options
from rockdec.cli import main
from rockdec.physics.loading import series_rng
from rockdec.physics.record_model import PAPER, Load, RecordModel, SensorNoise
from rockdec.physics.simulate import secant_step, simulate_block

import fake_calibration

# Steps giving about 75 samples per cycle at sigma_Y (g = sigma_p = 1, e = 0.9), as in
# tests/record/test_record_measure.py: white load, and a low-pass load with its corner at the
# rocking frequency (Load("lowpass", 1).pole(75)).
DT_WHITE, DT_CORNER_1, BURN_IN = 0.8043, 2.513, 4362

#: A small calibration grid for the end-to-end tests (the belt needs 5 grid points).
SMALL_GRID, SMALL_SETS = (0.6, 0.75, 0.85, 0.9, 0.95, 0.98), 6


def _record(seed, n=40_000, pole=0.0, dt=DT_WHITE, noise=0.0):
    y = simulate_block([seed], n, dt=dt, g=1.0, e=0.9, sigma_p=1.0, burn_in=BURN_IN, pole=pole)[0][0]
    return y + noise * y.std() * series_rng(seed + 1000).standard_normal(y.size)


@pytest.fixture
def small_calibration(monkeypatch):
    monkeypatch.setattr(calibration, "E_GRID", SMALL_GRID)
    monkeypatch.setattr(calibration, "SETS_PER_E", SMALL_SETS)
    monkeypatch.setattr(calibration, "SETS_PER_E_CAPPED", SMALL_SETS)


def test_binned_model_keeps_noise_and_pole_per_sample_within_half_a_bin():
    """The calibration simulates the binned model: its noise and its pole per sample at the
    binned samples per cycle lie within half a bin (relative) of the record's."""
    rng = np.random.default_rng(3)
    for ppc, corner, noise in zip(rng.uniform(20, 300, 50), rng.uniform(0.2, 10, 50), rng.uniform(0.002, 0.1, 50)):
        model = RecordModel(load=Load("lowpass", corner), sensor=SensorNoise(noise))
        binned = RecordModel.from_key(calibration.calibration_settings([20_000], ppc, model=model)["record_model"])
        simulated_rate = -math.log(binned.load.pole(calibration.ppc_key(ppc)))
        assert abs(math.log(simulated_rate / (2 * math.pi * corner / ppc))) <= calibration.POLE_BIN / 2 + 1e-3
        assert abs(math.log(binned.sensor.std / noise)) <= calibration.NOISE_BIN / 2 + 1e-3
    near = [RecordModel(sensor=SensorNoise(s)) for s in (0.0300, 0.0302)]
    assert len({calibration.settings_hash(calibration.calibration_settings([20_000], 75.0, model=m)) for m in near}) == 1


def test_measured_noise_and_colour_reach_the_calibration_key():
    noisy = _record(21, noise=0.03)
    analysis = measured.analyse([noisy], DT_WHITE)
    m = record_measure.measure(noisy, DT_WHITE)
    model, sources = estimation.record_model(m, analysis)
    assert m.noisy and sources["sensor_noise"] == "measured" and model.load.kind == "white"
    key = calibration.calibration_settings([noisy.size], analysis.points_per_cycle, model=model)["record_model"]
    assert key["sensor_noise"]["std"] == pytest.approx(0.03, rel=0.1)
    coloured = _record(22, pole=Load("lowpass", 1.0).pole(75.0), dt=DT_CORNER_1, n=200_000)
    analysis = measured.analyse([coloured], DT_CORNER_1)
    m = record_measure.measure(coloured, DT_CORNER_1)
    model, _ = estimation.record_model(m, analysis)
    assert m.coloured and model.load.kind == "lowpass"
    assert model.load.pole(analysis.points_per_cycle) == pytest.approx(m.pole.value, rel=1e-9)  # the pole per sample measured
    declared, sources = estimation.record_model(m, analysis, load=Load(), sensor=SensorNoise(0.5 * analysis.sigma_y, "rad"))
    assert declared.load.kind == "white" and declared.sensor == SensorNoise(0.5, "sigma_y")
    assert sources["load"] == sources["sensor_noise"] == "declared"
    assert estimation.record_model(m, analysis, model=PAPER)[0] == PAPER


def test_a_declared_spectrum_file_is_placed_at_the_records_rocking_frequency(tmp_path):
    """--load spectrum:FILE with a table in Hz: read with the record's dt and samples per
    cycle, so its frequencies in rocking frequencies are Hz times dt N; the calibration's
    key carries the table."""
    y = _record(24)
    analysis = measured.analyse([y], DT_WHITE)
    table = tmp_path / "psd.csv"
    table.write_text("frequency_hz,psd\n0.0,1.0\n0.01,1.0\n0.02,0.1\n")
    model, sources = estimation.record_model(None, analysis, load=f"spectrum:{table}", sensor=SensorNoise())
    assert model.load.kind == "spectrum" and sources["load"] == "declared"
    f_rock = 1.0 / (DT_WHITE * analysis.points_per_cycle)
    np.testing.assert_allclose(model.load.frequency, np.array([0.0, 0.01, 0.02]) / f_rock)
    key = calibration.calibration_settings([y.size], analysis.points_per_cycle, model=model)["record_model"]
    assert key["load"]["kind"] == "spectrum" and key["load"]["psd"] == [1.0, 1.0, 0.1]


@pytest.mark.slow
def test_noisy_record_json_names_the_noise_and_its_calibration_simulates_it(tmp_path, capsys, small_calibration):
    y = _record(23, noise=0.03)
    path = tmp_path / "r.npy"
    np.save(path, y)
    cache = tmp_path / "cache"
    assert main(["estimate", str(path), "--dt", str(DT_WHITE), "--cache", str(cache), "--json", "--no-repair"]) == 0
    res = json.loads(capsys.readouterr().out)
    rm = res["record_model"]
    assert rm["measured"]["detected"]["sensor_noise"] is True
    assert rm["measured"]["sensor_noise_sigma_y"]["value"] == pytest.approx(0.03, rel=0.1)
    assert rm["measured"]["sensor_noise_sigma_y"]["se"] > 0
    assert rm["sources"]["sensor_noise"] == "measured"
    assert rm["simulated"]["sensor_noise"]["std"] == pytest.approx(0.03, rel=0.1)
    files = list(cache.glob("calibration-*.nc"))
    assert [f.name for f in files] == [res["calibration"]["file"]]
    import xarray as xr

    with xr.open_dataset(files[0]) as ds:
        assert json.loads(ds.attrs["settings"])["record_model"]["sensor_noise"] == rm["simulated"]["sensor_noise"]
    assert res["estimator"] in [row["estimator"] for row in res["selection"] if row["holds"]]
    widths = {row["estimator"]: row["width"] for row in res["selection"] if row["holds"]}
    assert widths[res["estimator"]] == min(widths.values())
    assert main(["estimate", str(path), "--dt", str(DT_WHITE), "--cache", str(cache), "--sensor-noise", "0"]) == 0
    text = capsys.readouterr().out
    assert "sensor noise declared" in text and "no sensor noise" in text


@pytest.mark.parametrize("text, expected", [("auto", None), ("0", SensorNoise(0.0, "rad")), ("3%", SensorNoise(0.03)),
                                            ("2e-4", SensorNoise(2e-4, "rad")), (" 0.5 % ", SensorNoise(0.005))])
def test_sensor_noise_option_reads_its_forms(text, expected):
    assert estimate_options(sensor_noise=text)[0]["sensor"] == expected


@pytest.mark.parametrize("args, names", [
    (["--sensor-noise", "-1"], "--sensor-noise '-1'"),
    (["--sensor-noise", "nan"], "--sensor-noise 'nan'"),
    (["--sensor-noise", "inf%"], "--sensor-noise 'inf%'"),
    (["--sensor-noise", "loud"], "--sensor-noise 'loud'"),
    (["--load", "pink"], "--load 'pink'"),
    (["--load", "lowpass:-2"], "corner"),
    (["--load", "spectrum:psd.csv"], "spectrum"),
    (["--load", "base:ground.csv"], "base"),
    (["--model", "housner"], "--theta-cr"),
    (["--model", "housner", "--theta-cr", "2"], "--theta-cr 2"),
    (["--theta-cr", "0.2"], "--model housner"),
    (["--model", "newton"], "--model"),
])
def test_bad_model_options_end_in_one_sentence_before_any_calibration(tmp_path, capsys, args, names):
    path = tmp_path / "r.npy"
    np.save(path, np.zeros(10))  # never read: the options are refused first
    cache = tmp_path / "cache"
    assert main(["estimate", str(path), "--dt", "0.1", "--cache", str(cache), *args]) == 2
    err = capsys.readouterr().err.strip()
    assert names in err and len(err.splitlines()) == 1 and "Traceback" not in err
    assert not cache.exists()


def _entry(e, low, high, coverage, beyond=None, notes=()):
    nan = math.nan
    return estimation.Reading(nan if e is None else e, nan if e is None else e, beyond, (0.4, 0.995), nan if low is None else low,
                              nan if high is None else high, nan if coverage is None else coverage, 100, tuple(notes))


def _unbiased_belts(**spreads):
    """Belts with mean ``e`` and a constant spread per candidate over ``[0.4, 0.995]``:
    away from the range's ends a raw value at the mean gets the interval ``e -+ Z95 spread``."""
    e = np.linspace(0.4, 0.995, 4001)
    return {name: belt.Belt(e, e.copy(), np.full_like(e, s), 0.0) for name, s in spreads.items()}


def test_the_narrowest_trusted_candidate_at_the_common_e_is_reported():
    floor = estimation.coverage_floor(600)
    assert floor == pytest.approx(0.95 - 1.959964 * math.sqrt(0.95 * 0.05 / 600), abs=1e-6)
    belts = _unbiased_belts(e_0=0.03, e4=0.005, e_v=0.01)
    per = {"e_0": _entry(0.9, 0.85, 0.95, 0.95), "e4": _entry(0.9, 0.88, 0.92, floor - 0.01), "e_v": _entry(0.9, 0.87, 0.94, 0.94)}
    name, rows, reason = estimation.select(per, 600, belts)
    assert name == "e_v" and reason is None  # e4 is narrower, but its calibrated coverage does not hold
    assert {row.estimator: row.holds for row in rows} == {"e_0": True, "e4": False, "e_v": True}
    assert "below" in next(row.why_not for row in rows if row.estimator == "e4")
    widths = {row.estimator: row.width_at_common_e for row in rows}
    assert widths["e_v"] == pytest.approx(2 * belt.Z95 * 0.01, abs=1e-3) and widths["e_0"] == pytest.approx(2 * belt.Z95 * 0.03, abs=1e-3)


def test_a_record_interval_cut_short_at_the_range_end_does_not_win_the_selection():
    """e_0's own interval is the shortest only because its scatter pushed it against the
    calibrated range's lower end; e_v's belt is the narrower one at the candidates' common e."""
    belts = _unbiased_belts(e_0=0.05, e4=0.05, e_v=0.02)
    per = {"e_0": _entry(0.41, 0.4, 0.43, 0.95), "e4": _entry(0.6, 0.5, 0.7, 0.95), "e_v": _entry(0.62, 0.58, 0.66, 0.95)}
    name, rows, _ = estimation.select(per, 600, belts)
    assert name == "e_v"
    assert next(row.width for row in rows if row.estimator == "e_0") < next(row.width for row in rows if row.estimator == "e_v")


def test_no_trusted_candidate_gives_null_with_a_one_sentence_reason():
    from rockdec.report.estimate_report import candidate_row
    from rockdec.report.summary import text as _estimate_text

    per = {"e_0": _entry(None, None, None, 0.95, beyond="above"), "e4": _entry(0.9, 0.8, 0.99, 0.5),
           "e_v": _entry(None, None, None, None, notes=["no raw estimate"])}
    belts = _unbiased_belts(e_0=0.03, e4=0.03, e_v=0.03)
    whole = estimation.select({**per, "e_v": _entry(0.41, 0.4, 0.995, 0.95)}, 600, belts)
    assert whole[0] is None and "spans the whole calibrated range" in whole[2]  # an interval that says nothing
    name, rows, reason = estimation.select(per, 600, belts)
    assert name is None and not any(row.holds for row in rows)
    assert reason.startswith("no estimator can be trusted") and all(n in reason for n in per) and "\n" not in reason
    res = {"records": ["r.csv"], "samples": 1000, "dt": 0.01, "nan_samples": 0, "sigma_y": 0.01, "points_per_cycle": 75.0,
           "g": None, "g_given": False, "g_raw": 1.0, "calibration": {"file": "c.nc", "cached": True, "seconds": 0.0},
           "estimators": {}, "estimator": None, "e": None, "interval": [None, None], "coverage": None, "warnings": [],
           "record_model": None, "selection": [candidate_row(row) for row in rows], "reason": reason}
    assert f"e: not estimated: {reason}" in _estimate_text(res)


def test_step_search_brackets_a_threshold_like_response():
    """Samples per cycle falling two decades over 15 % of the step (as at a corner at the
    rocking frequency, e = 0.98): the search reaches the target within 12 pilots from the
    white law's first step."""
    def read(dt):  # the white law at short steps, a drop to a few samples per cycle past dt = 2.6
        return 3000.0 / dt**2 / (1.0 + math.exp(min(40.0 * (dt - 2.6), 700.0))) + 2.0

    dt, history = 1.13, []
    for _ in range(12):
        dt = secant_step(history, dt, read(dt), 75.0)
    assert read(dt) == pytest.approx(75.0, rel=0.03)


def test_calibration_step_under_a_low_pass_load_reads_the_target(small_calibration):
    """At a corner of 1 rocking frequency the calibration's records read the target samples
    per cycle (median of 6 records within 25 %: their own spread is about 20 %)."""
    model = RecordModel(load=Load("lowpass", 1.0))
    dt, burn_in, _ = calibration.step_for(0.9, 75.0, [100_000], measured.DEFAULT_SETTINGS, 4321, model)
    read = [
        measured.analyse(calibration._simulate_set(777 + k, [100_000], dt, 0.9, burn_in, model, model.load.pole(75.0)), dt).points_per_cycle
        for k in range(6)
    ]
    assert float(np.median(read)) == pytest.approx(75.0, rel=0.25)


def test_housner_model_puts_sigma_y_over_theta_cr_in_the_calibration_key(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(calibration, "_grid_point", fake_calibration.grid_point)
    path = tmp_path / "r.npy"
    y = _record(25)
    np.save(path, 0.02 * y / y.std())  # sigma_Y = 0.02 rad
    args = ["estimate", str(path), "--dt", str(DT_WHITE), "--cache", str(tmp_path / "cache"), "--json", "--load", "white",
            "--sensor-noise", "0"]
    assert main([*args, "--model", "housner", "--theta-cr", "0.4"]) == 0
    res = json.loads(capsys.readouterr().out)
    ratio = res["sigma_y"] / 0.4
    simulated = res["record_model"]["simulated"]
    assert simulated["rocking"] == "housner" and res["record_model"]["sources"]["rocking"] == "declared"
    assert abs(math.log(simulated["sigma_y_over_theta_cr"] / ratio)) <= calibration.RATIO_BIN / 2 + 1e-3
    assert fake_calibration.grid_point.settings["sigma_y_over_theta_cr"] == simulated["sigma_y_over_theta_cr"]
    sources = res["record_model"]["sources"]
    assert sources["load"] == sources["sensor_noise"] == "declared"  # measured and reported, not used
    assert simulated["load"] == {"kind": "white"} and simulated["sensor_noise"]["std"] == 0.0
    assert main([*args, "--model", "housner", "--theta-cr", "0.8"]) == 0  # another ratio, another calibration
    assert json.loads(capsys.readouterr().out)["calibration"]["file"] != res["calibration"]["file"]


def test_a_measured_corner_below_the_floor_is_declined_with_its_corner_and_no_calibration(tmp_path, capsys):
    """A record under a low-pass load at half the rocking frequency: the colour is measured,
    its corner lies below COLOUR_CORNER_FLOOR, and `rockdec estimate` answers `e: null` with
    one sentence naming the measured corner and the declared load that would be calibrated,
    before building any calibration; the text report says so too."""
    y = _record(31, pole=Load("lowpass", 0.5).pole(75.0), dt=DT_CORNER_1, n=200_000)
    path = tmp_path / "r.npy"
    np.save(path, y)
    cache = tmp_path / "cache"
    assert main(["estimate", str(path), "--dt", str(DT_CORNER_1), "--cache", str(cache), "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    corner = res["record_model"]["measured"]["load_corner_rocking"]["value"]
    assert res["record_model"]["measured"]["detected"]["colour"] and corner < estimation.COLOUR_CORNER_FLOOR
    assert res["e"] is None and res["interval"] == [None, None] and res["estimator"] is None
    assert f"corner at {corner:.2f} +- " in res["reason"] and "`load`" in res["reason"] and res["reason"].count(". ") == 0
    assert not any(cache.glob("calibration-*.nc")) and res["calibration"]["file"] is None
    assert all(est["raw"] is not None or name not in ("e_0", "e_v") for name, est in res["estimators"].items())
    assert main(["-v", "estimate", str(path), "--dt", str(DT_CORNER_1), "--cache", str(cache)]) == 0
    text = capsys.readouterr().out
    assert "e: not estimated: the load measured on these records is low-pass" in text and "calibration: none" in text


def test_the_colour_decline_takes_only_a_measured_corner_below_the_floor():
    """A declared load is calibrated as declared, a white load or a corner at or above the
    floor is not declined; the sentence names the corner and the floor."""
    low = RecordModel(load=Load("lowpass", 0.7))
    assert estimation.colour_decline(low, {"load": "declared"}, None, 75.0) is None
    assert estimation.colour_decline(RecordModel(), {"load": "measured"}, None, 75.0) is None
    assert estimation.colour_decline(RecordModel(load=Load("lowpass", estimation.COLOUR_CORNER_FLOOR)), {"load": "measured"}, None, 75.0) is None
    reason = estimation.colour_decline(low, {"load": "measured"}, None, 75.0)
    assert "0.70 times the rocking frequency" in reason and f"below {estimation.COLOUR_CORNER_FLOOR:g}" in reason


@pytest.mark.parametrize("shape, se, declined", [(8.0, 0.3, False), (11.8, 0.3, True), (8.0, 1.5, True), (8.0, math.nan, True)])
def test_a_load_read_white_beneath_noise_is_declined_unless_its_shape_rules_out_a_low_corner(shape, se, declined):
    """Beneath sensor noise a load read white is calibrated only when its shape ratio, 2
    errors up, still means a corner above the floor (Q = 10.6 is a corner of 2 at 75 samples
    per cycle); the sentence names the lowest corner it allows."""
    from types import SimpleNamespace

    from rockdec.record.record_measure import MeasuredModel, Quantity

    measurement = SimpleNamespace(noisy=True, shape=Quantity(shape, se), side_g_share=lambda n: 1.0)
    measurement.shape_corner_low = lambda n, z: MeasuredModel.shape_corner_low(measurement, n, z)
    reason = estimation.colour_decline(RecordModel(), {"load": "measured"}, measurement, 75.0)
    assert (reason is not None) == declined
    if declined:
        assert "colour is not ruled out" in reason and f"below {estimation.COLOUR_CORNER_FLOOR:g}" in reason
    assert estimation.colour_decline(RecordModel(), {"load": "declared"}, measurement, 75.0) is None


@pytest.mark.parametrize("rate_se, declined", [(0.0, False), (0.02, False), (0.5, True)])
def test_a_measured_corner_above_the_floor_must_be_clear_of_it_by_its_errors(rate_se, declined):
    """A corner read at 3 with an error of a third of it is not shown to lie above the floor
    (declined, the sentence says so); with a small error it is calibrated."""
    from types import SimpleNamespace

    alpha = math.exp(-2 * math.pi * 3.0 / 75.0)
    measurement = SimpleNamespace(pole=SimpleNamespace(value=alpha, se=rate_se * alpha), side_g_share=lambda n: 1.0)  # se of -ln(alpha), relative
    reason = estimation.colour_decline(RecordModel(load=Load("lowpass", 3.0)), {"load": "measured"}, measurement, 75.0)
    assert (reason is not None) == declined
    if declined:
        se = 3.0 * rate_se / -math.log(alpha)
        assert f"3.00 +- {se:.2f}" in reason and f"not {estimation.COLOUR_CORNER_Z:g} errors above" in reason


@pytest.mark.parametrize("share, declined", [(1.0, False), (0.75, False), (0.5, True), (0.0, True)])
def test_a_measured_load_whose_side_means_hold_part_of_g_is_declined(share, declined):
    """Side means reading g below SIDE_G_SHARE of the signature's decline a measured load,
    white or low-pass, and the sentence names the share; a declared load is calibrated."""
    from types import SimpleNamespace

    alpha = math.exp(-2 * math.pi * 3.0 / 75.0)
    measurement = SimpleNamespace(pole=SimpleNamespace(value=alpha, se=0.0), noisy=False, side_g_share=lambda n: share)
    for load in (Load(), Load("lowpass", 3.0)):
        reason = estimation.colour_decline(RecordModel(load=load), {"load": "measured"}, measurement, 75.0)
        assert (reason is not None) == declined
        if declined:
            assert f"is {share:.2f} of the g their signature reads" in reason and "`load`" in reason and reason.count(". ") == 0
        assert estimation.colour_decline(RecordModel(load=load), {"load": "declared"}, measurement, 75.0) is None


def test_a_record_at_half_the_rocking_frequency_read_as_a_whiter_corner_gets_no_number(tmp_path, capsys):
    """Record 4 of the coverage study's cell kernel_corner0.5_e0.6 (its seed, step, pole and
    burn-in; 200,000 samples, e = 0.6, a low-pass load at 0.52 of its own rocking frequency):
    the block's side follows the load, the fit reads the corner at 2.7 +- 0.2, more than 2
    errors above the floor, so the corner alone lets it through (it was answered e = 0.79);
    the side means read g at 0.39 of the signature's, and `rockdec estimate` declines it."""
    dt, pole, burn_in, seed = 1.841449510947132, 0.9589772739360323, 1724, 1152921504806846976 + 4
    y = simulate_block([seed], 200_000, dt=dt, g=1.0, e=0.6, sigma_p=1.0, burn_in=burn_in, pole=pole)[0][0]
    path = tmp_path / "r.npy"
    np.save(path, y)
    cache = tmp_path / "cache"
    assert main(["estimate", str(path), "--dt", str(dt), "--cache", str(cache), "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    corner = res["record_model"]["measured"]["load_corner_rocking"]
    assert corner["value"] - estimation.COLOUR_CORNER_Z * corner["se"] > estimation.COLOUR_CORNER_FLOOR  # the corner alone passes
    assert res["e"] is None and res["interval"] == [None, None] and res["estimator"] is None
    assert "g read off the side means" in res["reason"] and "`load`" in res["reason"]
    assert res["record_model"]["measured"]["g_side_share"] < estimation.SIDE_G_SHARE
    assert f"is {res['record_model']['measured']['g_side_share']:.2f} of the g" in res["reason"]
    assert not any(cache.glob("calibration-*.nc"))
    assert main(["-v", "estimate", str(path), "--dt", str(dt), "--cache", str(cache)]) == 0
    text = capsys.readouterr().out
    assert "e: not estimated: g read off the side means" in text and "of the signature's" in text


def test_coloured_calibration_sets_are_moved_to_the_calibrations_samples_per_cycle(monkeypatch):
    """Under a low-pass load the sets of a grid point are simulated again at a corrected
    step until their median samples per cycle is within SET_PPC_TOLERANCE of the
    calibration's, or SET_STEP_TRIES corrections are spent, and the try nearest the target
    is kept; under a white load they are simulated once."""
    calls = []
    real = calibration._sets

    def spy(*args):
        out = real(*args)
        calls.append((float(np.nanmedian(out[2])), out[0]))
        return out

    monkeypatch.setattr(calibration, "_sets", spy)
    for load, n_max in ((Load("lowpass", 3.0), 1 + calibration.SET_STEP_TRIES), (Load(), 1)):
        calls.clear()
        settings = {**calibration.calibration_settings([20_000], 75.0, model=RecordModel(load=load)), "sets_per_e": 6}
        raw, _ = calibration._grid_point(0, 0.8, settings, 12345)
        assert 1 <= len(calls) <= n_max and np.isfinite(raw).any()
        misses = [abs(math.log(m / settings["points_per_cycle"])) for m, _ in calls]
        assert all(miss > calibration.SET_PPC_TOLERANCE for miss in misses[:-1])  # stops at the first within tolerance
        assert len(calls) == n_max or misses[-1] <= calibration.SET_PPC_TOLERANCE or load.kind == "white"
        np.testing.assert_array_equal(raw, calls[int(np.argmin(misses))][1])


def test_a_record_whose_model_cannot_be_measured_is_declined_unless_the_model_is_declared(tmp_path, capsys, monkeypatch):
    """Too few triples to measure the record's model (MIN_TRIPLES raised above what the record
    holds): `e` is null with one sentence that says why and names the options that would
    help, before any calibration; declaring the load and the sensor noise, which leaves
    nothing to measure, gives `e` under the declared model."""
    from rockdec.record import record_measure

    monkeypatch.setattr(record_measure, "MIN_TRIPLES", 10**9)
    monkeypatch.setattr(calibration, "_grid_point", fake_calibration.grid_point)
    path = tmp_path / "r.npy"
    np.save(path, _record(27))
    cache = tmp_path / "cache"
    args = ["estimate", str(path), "--dt", str(DT_WHITE), "--cache", str(cache), "--json"]
    assert main(args) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["e"] is None and res["estimator"] is None and res["calibration"]["file"] is None
    assert res["reason"].startswith("the record model could not be measured (the records hold ")
    assert "`load` white with `sensor_noise` 0" in res["reason"] and "\n" not in res["reason"]
    assert not any(cache.glob("calibration-*.nc"))
    assert main([*args, "--load", "white", "--sensor-noise", "0"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["e"] is not None and res["calibration"]["file"] is not None and res["reason"] is None

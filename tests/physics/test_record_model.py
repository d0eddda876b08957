"""The record model (:mod:`rockdec.physics.record_model`): the load's filter, the scene's load carried by
the run into every simulator and every product, and the white load unchanged."""

from __future__ import annotations

import functools
import json
import math

import numpy as np
import pytest

from rockdec.calibrate import calibration
from rockdec.pipeline import config, replicates
from rockdec.physics import run
from rockdec.physics.housner import housner_flight, integrate_housner
from rockdec.physics.loading import low_pass, series_rng
from rockdec.physics.record_model import PAPER, Load, RecordModel, SensorNoise
from rockdec.physics.simulate import integrate
from rockdec.validate import InputError

SMALL_PILOT = {"pilot_seeds": 32, "pilot_points": 20_000}


@pytest.mark.parametrize("pole", [0.3, 0.9, 0.99])
def test_low_pass_filter_has_the_closed_form_autocorrelation(pole):
    """A stationary AR(1) of pole ``c`` with unit variance has autocorrelation ``c^m`` at lag ``m``."""
    w = low_pass(np.random.default_rng(2).standard_normal(400_000), pole)
    assert w.std() == pytest.approx(1.0, abs=0.03 if pole < 0.99 else 0.08)
    for m in (1, 2, 5):
        rho = np.corrcoef(w[m:], w[:-m])[0, 1]
        assert rho == pytest.approx(pole**m, abs=0.01 if pole < 0.99 else 0.03)


def test_load_pole_places_the_corner_in_rocking_frequencies():
    assert Load().pole(75.0) == 0.0
    assert Load("lowpass", 2.0).pole(75.0) == pytest.approx(math.exp(-2.0 * math.pi * 2.0 / 75.0), rel=1e-15)


@pytest.mark.parametrize(
    "load, match",
    [({"kind": "lowpass"}, "needs its corner"), ({"kind": "white", "corner": 1.0}, "no corner"), ({"kind": "lowpass", "corner": -1}, "excitation.load")],
)
def test_scene_load_is_validated_with_one_sentence(load, match):
    with pytest.raises(config.ConfigError, match=match):
        config.validate_scene({"excitation": {"load": load}})


def test_unknown_load_kind_is_refused():
    with pytest.raises(config.ConfigError, match="white, lowpass"):
        config.validate_scene({"excitation": {"load": {"kind": "measured"}}})
    with pytest.raises(InputError, match="not a load model"):
        Load("measured")
    with pytest.raises(InputError, match="at least 2 rows"):
        Load("spectrum")


def test_record_model_round_trips_through_attributes_and_key():
    model = RecordModel("housner", Load("lowpass", 3.0), SensorNoise(0.05, "sigma_y"))
    assert RecordModel.from_attrs(model.to_attrs()) == model
    assert RecordModel.from_key(json.loads(json.dumps(model.key()))) == model


@functools.cache
def housner_lowpass_run():
    """The Housner scene under a low-pass load at corner 1, its step searched once for the module's tests."""
    scene = config.validate_scene({"model": "housner", "excitation": {"load": {"kind": "lowpass", "corner": 1.0}}})
    return run.from_scene(scene, pilot=SMALL_PILOT)


def impulses_of(theta, theta_dot, contract):
    """The impulses a Housner series received: the velocity after each step minus the velocity
    of the free flight (eq. 2) over that step."""
    nu = math.sqrt(contract.g / contract.theta_cr)
    free = np.array([housner_flight(theta[n], theta_dot[n], contract.dt, nu, contract.theta_cr, contract.e)[1] for n in range(theta.size - 1)])
    return theta_dot[1:] - free


def test_housner_scene_with_lowpass_load_simulates_coloured_impulses():
    contract = housner_lowpass_run()
    assert contract.model == "housner" and contract.load == Load("lowpass", 1.0)
    assert 0.9 < contract.pole < 0.95  # exp(-2 pi / 75)
    ds = contract.dataset([3], 20_000).load()
    p = impulses_of(ds["theta"].values[0], ds["theta_dot"].values[0], contract)
    assert p.std() == pytest.approx(contract.sigma_p, rel=0.1)
    assert np.corrcoef(p[1:], p[:-1])[0, 1] == pytest.approx(contract.pole, abs=0.02)
    white = run.with_model(run.from_scene(config.validate_scene({"model": "simplified"}), pilot=SMALL_PILOT), "housner", SMALL_PILOT)
    ds = white.dataset([3], 20_000).load()
    p = impulses_of(ds["theta"].values[0], ds["theta_dot"].values[0], white)
    assert abs(np.corrcoef(p[1:], p[:-1])[0, 1]) < 0.03


@pytest.mark.filterwarnings("ignore::rockdec.rdd.signatures.NoTriggerWarning")
def test_run_json_and_every_product_name_the_load(tmp_path):
    contract = housner_lowpass_run()
    assert contract.record_model == RecordModel("housner", Load("lowpass", 1.0))
    stored = json.loads(contract.write(tmp_path / "run.json").read_text())
    assert stored["load"] == "lowpass" and stored["load_corner"] == 1.0 and stored["load_pole"] == pytest.approx(contract.pole)
    assert run.Run.read(tmp_path / "run.json") == contract
    scene = config.validate_scene(
        {"records": {"replicates": 2, "series_per_replicate": 2, "n_points": 4000, "chunk_seeds": 2}, "estimates": {"compare_readings": False}}
    )
    reading = scene["estimates"]["reading"]
    cube = replicates.scene_cubes(contract, scene["records"], scene["signatures"], [reading])[reading]
    est, _ = replicates.scene_estimates(cube, scene["estimates"])
    curves = replicates.reading_curves({reading: cube}, scene["estimates"]["fit_points"])
    combined, _ = replicates.readings_estimates(curves, "window")
    products = {"series": contract.dataset([0], 100), "signatures": cube, "estimates": est, "readings": curves, "estimates_readings": combined}
    for name, ds in products.items():
        assert ds.attrs["load"] == "lowpass" and ds.attrs["load_corner"] == 1.0, name


def test_white_load_series_are_plain_normal_impulses_through_the_kernel():
    """White: the series of a run are its seed's standard normal draws times sigma_p through
    the integrator, bit for bit (seed-stable, whatever the record model machinery)."""
    contract = run.from_scene(config.validate_scene({"model": "simplified"}), pilot=SMALL_PILOT)
    n, seed = 3000, 11
    impulses = contract.sigma_p * series_rng(seed).standard_normal(contract.burn_in + n - 1)
    theta, omega = np.empty(n), np.empty(n)
    integrate(impulses, contract.dt, contract.g, contract.e, 0.0, 0.0, contract.burn_in, theta, omega)
    np.testing.assert_array_equal(contract.dataset([seed], n)["theta"].values[0], theta)
    housner = run.with_model(contract, "housner", SMALL_PILOT)
    h_theta, h_omega = np.empty(n), np.empty(n)
    nu = math.sqrt(contract.g / contract.theta_cr)
    integrate_housner(impulses, contract.dt, nu, contract.theta_cr, contract.e, 0.0, 0.0, contract.burn_in, h_theta, h_omega)
    np.testing.assert_array_equal(housner.dataset([seed], n)["theta"].values[0], h_theta)


def test_sensor_noise_is_added_to_the_angle_from_its_own_stream():
    scene = config.validate_scene({"model": "simplified", "excitation": {"sensor_noise": {"std": 0.1}}})
    noisy = run.from_scene(scene, pilot=SMALL_PILOT)
    clean = run.from_scene(config.validate_scene({"model": "simplified"}), pilot=SMALL_PILOT)
    assert noisy.dt == clean.dt and noisy.sensor_std == pytest.approx(0.1 * noisy.sigma_y)
    a, b = noisy.dataset([5], 50_000).load(), clean.dataset([5], 50_000).load()
    np.testing.assert_array_equal(a["theta_dot"].values, b["theta_dot"].values)
    diff = (a["theta"] - b["theta"]).values[0]
    assert diff.std() == pytest.approx(noisy.sensor_std, rel=0.03)
    assert abs(np.corrcoef(diff[1:], diff[:-1])[0, 1]) < 0.02


def test_calibration_key_names_the_record_model():
    white = calibration.calibration_settings([20_000], 75.0)
    assert white["record_model"] == PAPER.key()
    others = [RecordModel(load=Load("lowpass", 3.0)), RecordModel(sensor=SensorNoise(0.1))]
    hashes = {calibration.settings_hash(calibration.calibration_settings([20_000], 75.0, model=m)) for m in [PAPER, *others]}
    assert len(hashes) == 3
    with pytest.raises(ValueError, match="simplified model"):
        calibration.calibration_settings([20_000], 75.0, model=RecordModel("housner"))


def test_calibration_records_follow_the_record_model():
    """The calibration's records carry the model's load and its sensor noise (relative to their rms)."""
    args = (5, [30_000], 0.36, 0.95, 1000)
    white = calibration._simulate_set(*args, PAPER, 0.0)[0]
    coloured = RecordModel(load=Load("lowpass", 3.0))
    assert not np.array_equal(calibration._simulate_set(*args, coloured, coloured.load.pole(75.0))[0], white)
    noisy = calibration._simulate_set(*args, RecordModel(sensor=SensorNoise(0.1)), 0.0)[0]
    assert (noisy - white).std() == pytest.approx(0.1 * np.sqrt(np.mean(white**2)), rel=0.03)


def test_parse_load_reads_the_command_line_forms_and_refuses_others():
    from rockdec.physics.record_model import parse_load

    assert parse_load("white") == Load()
    assert parse_load("lowpass:2.5") == Load("lowpass", 2.5)
    for text in ("pink", "white:3", "lowpass:", "lowpass:x", "lowpass:-1", ""):
        with pytest.raises(InputError):
            parse_load(text)


# --------------------------------------------------------------------------- issue 38: corners whose pole degenerates

from rockdec.physics.record_model import POLE_RATE_RANGE, parse_load  # noqa: E402


@pytest.mark.hostile("numbers", "refused")
@pytest.mark.parametrize("corner, words", [
    ("1e5", ["is white", "give `load` white"]), ("1e8", ["is white"]), ("1e300", ["is white"]),
    ("1e-300", ["never becomes stationary", "above"]), ("1e-17", ["never becomes stationary"]),
])
@pytest.mark.parametrize("points_per_cycle", [35.0, 75.0, 2000.0])
def test_a_corner_whose_pole_rounds_to_0_or_1_is_refused_naming_load(corner, words, points_per_cycle):
    load = parse_load(f"lowpass:{corner}")
    if POLE_RATE_RANGE[0] <= 2 * math.pi * float(corner) / points_per_cycle < POLE_RATE_RANGE[1]:
        assert 0.0 < load.pole(points_per_cycle) < 1.0  # coloured at this finer sampling
        return
    with pytest.raises(InputError) as info:
        load.pole(points_per_cycle)
    text = str(info.value)
    assert text.startswith(f"`load` lowpass:{float(corner):g} at ") and "\n" not in text and text.count(". ") == 0
    for word in words:
        assert word in text
    with pytest.raises(InputError):  # the calibration's model key takes -log(pole): refused, not a math domain error
        calibration.binned_model(RecordModel("simplified", load, SensorNoise()), points_per_cycle)


@pytest.mark.hostile("numbers", "answered")
@pytest.mark.parametrize("points_per_cycle", [35.0, 75.0, 2000.0])
def test_corners_inside_the_range_give_a_pole_whose_log_returns_the_corner(points_per_cycle):
    """At the range's edges (just inside) the pole is a float in (0, 1) and ``-log(pole) N / 2 pi`` is the corner."""
    for rate in (POLE_RATE_RANGE[0] * 1.01, 1.0, POLE_RATE_RANGE[1] * 0.999):
        corner = rate * points_per_cycle / (2 * math.pi)
        pole = Load("lowpass", corner).pole(points_per_cycle)
        assert 0.0 < pole < 1.0
        assert -math.log(pole) * points_per_cycle / (2 * math.pi) == pytest.approx(corner, rel=0.02)

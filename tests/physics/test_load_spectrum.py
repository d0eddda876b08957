"""Spectrum loads (:class:`rockdec.physics.record_model.Load` of kind ``spectrum``, a base-excitation
record read into one): the impulses' autocorrelation is the inverse transform of the table
(closed forms: the low-pass spectrum gives ``c^m``, a flat one white noise), every simulator
draws them, the step search converges under them, and scenes, the command line, ``run.json``
and every product state them; the ``pole`` path keeps its series bit for bit."""

from __future__ import annotations

import functools
import json
import math

import numpy as np
import pytest
import xarray as xr
from hypothesis import given, settings
from hypothesis import strategies as st

from rockdec.pipeline import config, replicates
from rockdec.physics import run, simulate
from rockdec.physics.loading import WRAP_TOLERANCE, ImpulseSpectrum, draw_impulses, embedding_size, low_pass, series_rng, spectral_gain
from rockdec.physics.record_model import Load, RecordModel, carried_attrs, load_attrs, load_from_attrs, parse_load, read_base_record
from rockdec.validate import InputError

SMALL_PILOT = {"pilot_seeds": 32, "pilot_points": 20_000}
N_CYCLE = 75.0


def lowpass_psd(c: float, f_per_step):
    """One-sided PSD of the stationary AR(1) of pole ``c`` (unit variance), at ``f`` cycles per
    step: ``(1 - c^2)/(1 - 2 c cos w + c^2)``, ``w = 2 pi f``; its autocorrelation is ``c^m``."""
    w = 2.0 * np.pi * np.asarray(f_per_step)
    return (1.0 - c * c) / (1.0 - 2.0 * c * np.cos(w) + c * c)


def lowpass_table(c: float, points_per_cycle: float = N_CYCLE, rows: int = 600) -> Load:
    """The low-pass spectrum of pole ``c`` at ``points_per_cycle`` as a spectrum load's table
    (rocking frequencies: cycles per step times samples per cycle), from 0 to Nyquist."""
    f = np.concatenate([[0.0], np.geomspace(1e-6, 0.5, rows)])
    return Load("spectrum", frequency=tuple(f * points_per_cycle), psd=tuple(lowpass_psd(c, f)))


@pytest.mark.parametrize("c", [0.5, 0.9, 0.99])
def test_lowpass_spectrum_table_gives_the_closed_form_autocorrelation(c):
    """The circulant autocorrelation ``sum_k S_k cos(2 pi k m/M)/M`` of the gains is ``c^m``
    (deterministic, up to the table's interpolation), and drawn impulses follow it."""
    spectrum = lowpass_table(c).draw_options(N_CYCLE)["spectrum"]
    size = 2**18
    gain = spectral_gain(spectrum, size)
    power = np.concatenate([gain, gain[-2:0:-1]]) ** 2  # the whole circle
    acf = np.fft.irfft(gain**2, n=size)  # (1/M) sum_k S_k cos(2 pi k m / M)
    assert power.mean() == pytest.approx(1.0, rel=1e-12)
    for m in (1, 2, 5, 20):
        assert acf[m] == pytest.approx(c**m, abs=2e-3)
    # the embedding wraps no more than WRAP_TOLERANCE of correlation (c^L < 1e-4) and costs little more than n
    n = 48_086
    assert n + math.log(WRAP_TOLERANCE) / math.log(c) <= embedding_size(spectrum, n) <= 1.1 * n
    p = draw_impulses(series_rng(4), np.empty(400_000), 2.0, spectrum=spectrum)
    assert p.std() == pytest.approx(2.0, rel=0.03 if c < 0.99 else 0.08)
    for m in (1, 2, 5):
        assert np.corrcoef(p[m:], p[:-m])[0, 1] == pytest.approx(c**m, abs=0.01 if c < 0.99 else 0.03)


def test_flat_spectrum_is_white_noise_of_the_stream():
    """A flat table has unit gains, so the impulses are the stream's first standard normals
    times sigma_p (the transform there and back is exact to rounding)."""
    flat = Load("spectrum", frequency=(0.0, N_CYCLE / 2), psd=(3.0, 3.0))
    spectrum = flat.draw_options(N_CYCLE)["spectrum"]
    p = draw_impulses(series_rng(9), np.empty(50_001), 0.7, spectrum=spectrum)
    w = series_rng(9).standard_normal(p.size)
    np.testing.assert_allclose(p, 0.7 * w, rtol=0, atol=1e-12)
    assert abs(np.corrcoef(p[1:], p[:-1])[0, 1]) < 0.015


def test_table_outside_the_band_and_a_band_without_power_are_handled():
    """Rows above Nyquist are not drawn; no power below Nyquist is refused in one sentence."""
    band = ImpulseSpectrum((0.1, 0.2, 0.9), (1.0, 1.0, 1.0))
    gain = spectral_gain(band, 1000)
    f = np.arange(gain.size) / 1000
    assert np.all(gain[(f < 0.1)] == 0.0) and np.all(gain[(f >= 0.1)] > 0.0)
    with pytest.raises(InputError, match="no power"):
        spectral_gain(ImpulseSpectrum((0.6, 0.9), (1.0, 1.0)), 1000)


@pytest.mark.filterwarnings("ignore:the simplified model is outside its validity region")
def test_pole_path_keeps_its_series_bit_for_bit():
    """``pole=`` (calibration.py, coverage.py) draws the seed's normals through the AR(1)
    filter, as before: the series equals that reference through the kernel, bit for bit,
    for the simplified, fixed-step and Housner simulators, and a Run of a lowpass load too."""
    c, n, burn, seed = 0.9, 2000, 500, 17
    kw = dict(dt=0.36, g=1.0, e=0.9, sigma_p=1.0, burn_in=burn)
    impulses = low_pass(series_rng(seed).standard_normal(burn + n - 1), c)
    for grid in (False, True):
        theta, omega = np.empty(n), np.empty(n)
        simulate.integrate(impulses, 0.36, 1.0, 0.9, 0.0, 0.0, burn, theta, omega, grid)
        np.testing.assert_array_equal(simulate.simulate_block([seed], n, grid_impacts=grid, pole=c, **kw)[0][0], theta)
    scene = {"model": "simplified", "excitation": {"dt": 0.01, "burn_in": 500, "load": {"kind": "lowpass", "corner": 2.0}}}
    contract = run.from_scene(config.validate_scene(scene), pilot=SMALL_PILOT)
    ref = simulate.simulate_block([seed], n, dt=contract.dt, g=contract.g, e=contract.e, sigma_p=contract.sigma_p,
                                  burn_in=contract.burn_in, pole=contract.pole)[0][0]
    np.testing.assert_array_equal(contract.dataset([seed], n)["theta"].values[0], ref)
    housner = simulate.simulate_model("housner", [seed], n, theta_cr=0.25, pole=c, **kw)[0]
    same = simulate.simulate_model("housner", [seed], n, theta_cr=0.25, **kw, **Load("lowpass", -math.log(c) * N_CYCLE / (2 * math.pi))
                                   .draw_options(N_CYCLE))[0]
    np.testing.assert_array_equal(housner, same)


def test_step_search_converges_under_a_spectrum_load():
    """The step search reaches its samples per cycle under a spectrum load (a band around the
    rocking frequency, and the low-pass shape at corner 3, where it matches the lowpass
    load's step)."""
    band = Load("spectrum", frequency=(0.3, 1.0, 3.0), psd=(0.0, 1.0, 0.0))
    lowpass = Load("lowpass", 3.0)
    steps = {}
    for name, load in {"band": band, "table": lowpass_table(lowpass.pole(N_CYCLE)), "lowpass": lowpass}.items():
        cal = simulate.calibrate_dt(e=0.9, g=1.0, sigma_p=1.0, points_per_cycle=N_CYCLE, iterations=simulate.STEP_ITERATIONS[load.kind],
                                    **SMALL_PILOT, **load.draw_options(N_CYCLE))
        assert cal["points_per_cycle"] == pytest.approx(N_CYCLE, rel=0.1), name
        steps[name] = cal["dt"]
    assert steps["table"] == pytest.approx(steps["lowpass"], rel=0.05)


def test_secant_step_exponent_is_a_fit_over_recent_pilots():
    """Exact power law ``N = 300 dt^-4``: the fitted exponent is 4, so one update lands on the target."""
    history: list = []
    dt = 1.0
    for _ in range(3):
        dt = simulate.secant_step(history, dt, 300.0 * dt**-4, 75.0)
    assert 300.0 * dt**-4 == pytest.approx(75.0, rel=1e-9)


@functools.cache
def housner_spectrum_run():
    table = lowpass_table(Load("lowpass", 1.0).pole(N_CYCLE), rows=200).to_dict()
    scene = config.validate_scene({"model": "housner", "excitation": {"load": table}})
    return run.from_scene(scene, pilot=SMALL_PILOT)


def test_housner_honours_a_spectrum_load():
    """The impulses a Housner series received (velocity after each step minus the free
    flight's, eq. 2) have ``sigma_p`` and the table's lag-m autocorrelation ``c^m``, read
    over four seeds, each series up to the step before its overturn (if it falls): which
    series fall, and when, is not the same on every machine (the spectrum load's gains go
    through NumPy's SIMD logarithm), but the claim holds on any stretch of any series."""
    from rockdec.physics.housner import housner_flight

    contract = housner_spectrum_run()
    assert contract.model == "housner" and contract.load.kind == "spectrum" and math.isnan(contract.pole)
    c = Load("lowpass", 1.0).pole(N_CYCLE)
    ds = contract.dataset([0, 1, 2, 3], 20_000)
    nu = math.sqrt(contract.g / contract.theta_cr)
    received = []
    for theta, theta_dot in zip(ds["theta"].values, ds["theta_dot"].values):
        standing = np.flatnonzero(~(np.abs(theta) < contract.theta_cr))
        end = (standing[0] if standing.size else theta.size) - 1  # the last step that starts and ends standing
        free = np.array([housner_flight(theta[n], theta_dot[n], contract.dt, nu, contract.theta_cr, contract.e)[1] for n in range(end)])
        received.append(theta_dot[1 : end + 1] - free)
    lengths = [p.size for p in received]
    assert sum(lengths) >= 40_000, lengths  # most of the four series stand
    p = np.concatenate(received)
    assert np.isfinite(p).all()
    assert p.std() == pytest.approx(contract.sigma_p, rel=0.1)
    for m in (1, 5):
        lagged = np.concatenate([q[m:] * q[:-m] for q in received]).mean() / np.concatenate([q * q for q in received]).mean()
        assert lagged == pytest.approx(c**m, abs=0.03)


@pytest.mark.filterwarnings("ignore::rockdec.rdd.signatures.NoTriggerWarning")
def test_run_json_and_files_name_a_spectrum_load(tmp_path):
    contract = housner_spectrum_run()
    stored = json.loads(contract.write(tmp_path / "run.json").read_text())
    assert stored["load"] == "spectrum" and stored["load_frequency"] == list(contract.load.frequency)
    assert stored["load_psd"] == list(contract.load.psd) and math.isnan(stored["load_pole"])
    assert run.Run.read(tmp_path / "run.json") == contract
    ds = contract.dataset([0, 1], 200)
    ds.to_netcdf(tmp_path / "series.nc")
    with xr.open_dataset(tmp_path / "series.nc") as back:
        assert run.Run.from_attrs(back.attrs) == contract
        assert load_from_attrs(carried_attrs(back.attrs)) == contract.load
    assert contract.record_model == RecordModel("housner", contract.load)
    scene = config.validate_scene(
        {"records": {"replicates": 2, "series_per_replicate": 2, "n_points": 4000, "chunk_seeds": 2}, "estimates": {"compare_readings": False}}
    )
    reading = scene["estimates"]["reading"]
    cube = replicates.scene_cubes(contract, scene["records"], scene["signatures"], [reading])[reading]
    est, _ = replicates.scene_estimates(cube, scene["estimates"])
    for name, product in {"signatures": cube, "estimates": est}.items():
        assert load_from_attrs(product.attrs) == contract.load, name


def write(path, text):
    path.write_text(text)
    return path


def test_parse_load_reads_spectrum_tables_and_base_records(tmp_path):
    rows = "frequency_rocking,psd\n0,1\n0.5,2\n1,4\n10,0\n"
    load = parse_load(f"spectrum:{write(tmp_path / 's.csv', rows)}")
    assert load.frequency == (0.0, 0.5, 1.0, 10.0) and load.psd == (1.0, 2.0, 4.0, 0.0)
    assert "s.csv" in load.source and "sha256" in load.source
    assert Load.from_dict(json.loads(json.dumps(load.to_dict()))) == load
    assert load_from_attrs(load_attrs(load)) == load
    hz = write(tmp_path / "hz.csv", "# from the rig\nfrequency_hz;psd\n0.5;1\n2;1\n")
    # f/f_rock = f dt N: at dt = 0.01 s and 50 samples per cycle the rocking frequency is 2 Hz
    assert parse_load(f"spectrum:{hz}", dt=0.01, points_per_cycle=50).frequency == pytest.approx((0.25, 1.0))
    # a base record: a 3 Hz sine in noise, the rocking frequency 1.5 Hz -> a peak at 2 rocking frequencies
    t = np.arange(8192) / 100.0
    a = np.sin(2 * np.pi * 3.0 * t) + 0.1 * np.random.default_rng(0).standard_normal(t.size)
    csv = tmp_path / "base.csv"
    np.savetxt(csv, np.column_stack([t, a]), delimiter=",", header="time,acceleration", comments="")
    base = parse_load(f"base:{csv}", dt=1 / 150, points_per_cycle=100)
    assert base.kind == "spectrum" and base.frequency[int(np.argmax(base.psd))] == pytest.approx(2.0, abs=0.02)
    nc = tmp_path / "base.nc"
    xr.Dataset({"acceleration": ("time", a)}, coords={"time": ("time", t * 1000, {"units": "ms"})}).to_netcdf(nc)
    from_nc = read_base_record(nc, 1.5)
    assert from_nc.psd == pytest.approx(base.psd, rel=1e-9) and from_nc.frequency == pytest.approx(base.frequency, rel=1e-9)


@pytest.mark.parametrize(
    "text, match",
    [
        ("frequency_rocking,psd\n0,1\n", "at least 2 rows"),
        ("frequency_rocking,psd\n0,1\n1,x\n", "'x', not a number"),
        ("frequency_rocking,psd\n0,1\n1,-2\n", "psd -2 < 0"),
        ("frequency_rocking,psd\n1,1\n1,2\n", "does not increase"),
        ("frequency_rocking,psd\n0,1\n1,nan\n", "not a finite number"),
        ("frequency_rocking,psd\n0,0\n1,0\n", "no power"),
        ("f,psd\n0,1\n1,1\n", "the header"),
        ("frequency_hz,psd\n0,1\n1,1\n", "rocking frequency"),
        ("", "empty"),
    ],
)
def test_bad_spectrum_files_are_refused_in_one_sentence(tmp_path, text, match):
    path = write(tmp_path / "bad.csv", text)
    with pytest.raises(InputError, match=match) as err:
        parse_load(f"spectrum:{path}")
    assert "\n" not in str(err.value)


def test_bad_load_strings_and_base_records_are_refused(tmp_path):
    with pytest.raises(InputError, match="no such"):
        parse_load(f"spectrum:{tmp_path / 'missing.csv'}")
    one = write(tmp_path / "b.csv", "time,acceleration\n0,1\n")
    with pytest.raises(InputError, match="rocking frequency"):
        parse_load(f"base:{one}")
    short = write(tmp_path / "short.csv", "time,acceleration\n" + "".join(f"{i * 0.01},{i % 3}\n" for i in range(100)))
    with pytest.raises(InputError, match="at least 256"):
        read_base_record(short, 1.0)
    gap = write(tmp_path / "gap.csv", "time,acceleration\n" + "".join(f"{i * 0.01},{'nan' if i == 7 else i % 3}\n" for i in range(300)))
    with pytest.raises(InputError, match="sample 7"):
        read_base_record(gap, 1.0)
    with pytest.raises(InputError, match="not a load"):
        parse_load("spectrum")


def test_scene_spectrum_load_validates_and_bad_ones_are_refused(tmp_path):
    inline = {"kind": "spectrum", "frequency": [0.0, 1.0, 5.0], "psd": [1.0, 2.0, 0.5]}
    scene = config.validate_scene({"excitation": {"load": dict(inline)}})
    assert Load.from_dict(scene["excitation"]["load"]) == Load("spectrum", frequency=(0.0, 1.0, 5.0), psd=(1.0, 2.0, 0.5))
    table = write(tmp_path / "t.csv", "frequency_hz,psd\n1,1\n4,3\n")
    scene = config.validate_scene({"excitation": {"load": {"kind": "spectrum", "file": str(table), "rocking_frequency": 2.0}}})
    assert scene["excitation"]["load"]["frequency"] == [0.5, 2.0] and "t.csv" in scene["excitation"]["load"]["source"]
    assert config.validate_scene(scene)["excitation"]["load"] == scene["excitation"]["load"]  # validated twice: the same
    bad = [
        ({"kind": "spectrum", "frequency": [0.0, 1.0], "psd": [1.0, -1.0]}, "excitation.load"),
        ({"kind": "spectrum", "frequency": [1.0, 0.5], "psd": [1.0, 1.0]}, "does not increase"),
        ({"kind": "spectrum"}, "at least 2 rows"),
        ({"kind": "base", "file": str(tmp_path / "none.csv"), "rocking_frequency": 1.0}, "no such"),
        ({"kind": "white", "psd": [1.0, 1.0]}, "no spectrum table"),
        ({"kind": "spectrum", "frequency": [0.0, 1.0], "psd": [1.0, 1.0], "corner": 2.0}, "no corner"),
    ]
    for load, match in bad:
        with pytest.raises(config.ConfigError, match=match) as err:
            config.validate_scene({"excitation": {"load": load}})
        assert "\n" not in str(err.value)


def test_spectrum_series_are_seed_stable_whatever_the_chunks_and_a_nan_pole_is_refused():
    spectrum = lowpass_table(0.9, rows=100).draw_options(N_CYCLE)["spectrum"]
    kw = dict(dt=0.36, g=1.0, e=0.9, sigma_p=1.0, burn_in=300, spectrum=spectrum)
    alone = simulate.simulation_dataset([3, 7], 1500, chunk_seeds=1, **kw).theta.values
    many = simulate.simulation_dataset(np.arange(10), 1500, chunk_seeds=3, **kw)
    np.testing.assert_array_equal(many.theta.sel(seed=[3, 7]).values, alone)
    assert math.isnan(many.attrs["load_pole"])
    assert math.isnan(Load("spectrum", frequency=(0.0, 1.0), psd=(1.0, 1.0)).pole(N_CYCLE))
    with pytest.raises(InputError, match="pole nan"):
        simulate.simulate_block([0], 10, dt=0.36, g=1.0, e=0.9, sigma_p=1.0, pole=math.nan)


@settings(max_examples=60, deadline=None)
@given(
    frequency=st.lists(st.floats(allow_nan=True, allow_infinity=True), min_size=0, max_size=5),
    psd=st.lists(st.floats(allow_nan=True, allow_infinity=True), min_size=0, max_size=5),
    points_per_cycle=st.floats(1e-300, 1e300),
)
def test_any_table_is_refused_in_one_sentence_or_draws_finite_impulses_of_unit_shape(frequency, psd, points_per_cycle):
    try:
        load = Load("spectrum", frequency=tuple(frequency), psd=tuple(psd))
        p = draw_impulses(series_rng(1), np.empty(2000), 1.5, **load.draw_options(points_per_cycle))
    except InputError as exc:
        assert "\n" not in str(exc)
        return
    assert np.all(np.isfinite(p))
    gain = spectral_gain(load.draw_options(points_per_cycle)["spectrum"], 4000)  # the variance over the circle: exactly 1
    assert np.concatenate([gain, gain[-2:0:-1]]) ** 2 @ np.ones(4000) / 4000 == pytest.approx(1.0, rel=1e-9)

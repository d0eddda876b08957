"""The record's own model read off its second differences (rockdec.record.record_measure)."""

import math

import numpy as np
import pytest
from scipy.signal import lfilter

from rockdec.record import record_measure as rm
from rockdec.physics.loading import series_rng
from rockdec.physics.record_model import Load
from rockdec.physics.simulate import simulate_block
from rockdec.validate import InputError

from rocking_reference import flight_reference

# Steps giving about 75 samples per cycle at sigma_Y for g = 1, sigma_p = 1, e = 0.9
# (rockdec.physics.simulate.calibrate_dt): white load, and a low-pass load with its corner at the
# rocking frequency (Load("lowpass", 1).pole(75)).
DT_WHITE, DT_CORNER_1 = 0.8043, 2.513
BURN_IN = 4362


def _sample_r(d, lags):
    d = d - d.mean()
    return np.array([np.mean(d[:-m] * d[m:]) for m in lags]) / np.mean(d * d)


def _one_side_record(d, segment=500, lift=1e3):
    """A record whose second differences are ``d`` within segments of ``segment`` samples
    that never cross zero, alternately far above and far below it (like rocking, with no
    drift): the double sum of ``d``, lifted."""
    x = np.cumsum(np.cumsum(d))
    x -= np.linspace(x[0], x[-1], x.size)
    lift = 10.0 * np.abs(x).max() + lift
    sign = np.where((np.arange(x.size) // segment) % 2 == 0, 1.0, -1.0)
    return sign * lift + x


def test_mixed_autocorrelation_matches_long_simulation():
    rng = np.random.default_rng(1)
    n, alpha, sigma_p, sigma_n = 400_000, 0.7, 1.0, 0.6
    p = lfilter([math.sqrt(1 - alpha**2)], [1.0, -alpha], rng.standard_normal(n)) * sigma_p
    noise = rng.standard_normal(n + 2) * sigma_n
    d = p + noise[2:] - 2.0 * noise[1:-1] + noise[:-2]
    q = sigma_n**2 / sigma_p**2
    lags = np.arange(1, 7)
    expected = (alpha**lags + q * np.array([-4.0, 1.0, 0, 0, 0, 0])) / (1.0 + 6.0 * q)  # r(m) of the docstring
    gamma = rm.mixed_autocovariance(np.arange(7), sigma_p**2, sigma_n**2, alpha)
    np.testing.assert_allclose(gamma[1:] / gamma[0], expected, rtol=1e-12)
    np.testing.assert_allclose(_sample_r(d, lags), expected, atol=0.006)


def test_structure_function_is_the_variance_of_span_differences():
    """S(L) from the autocovariance of one-step differences equals the variance of
    y[k+L] - 2 y[k] + y[k-L] measured directly, and the white, noise-only closed forms."""
    rng = np.random.default_rng(4)
    alpha, sigma_n = 0.8, 0.7
    p = lfilter([1.0], [1.0, -alpha], rng.standard_normal(300_000))
    y = np.cumsum(np.cumsum(p)) + sigma_n * rng.standard_normal(p.size)
    direct = np.array([np.var(y[2 * L :] - 2 * y[L:-L] + y[: -2 * L]) for L in rm.SPANS])
    model = rm.structure_model(1.0 / (1 - alpha**2), sigma_n**2, alpha)
    np.testing.assert_allclose(direct, model, rtol=0.03)
    spans = np.array(rm.SPANS)
    np.testing.assert_allclose(rm.structure_model(1.0, 0.0, 0.0), spans * (2 * spans**2 + 1) / 3, rtol=1e-12)
    np.testing.assert_allclose(rm.structure_model(0.0, 1.0, 0.5), 6.0, rtol=1e-12)


def test_fit_structure_inverts_the_model():
    for a, s2, alpha in ((1.0, 0.0, 0.9), (1.0, 3.0, 0.8), (0.01, 1.0, 0.95), (1.0, 0.5, 0.0), (1.0, 0.0, 0.0)):
        got = rm.fit_structure(rm.mixed_autocovariance(np.arange(rm.MAX_LAG + 1), a, s2, alpha))
        np.testing.assert_allclose(got, (a, s2, alpha), atol=1e-5)


def test_pure_noise_second_differences_are_ma2():
    rng = np.random.default_rng(2)
    sigma_n = 0.5
    y = _one_side_record(np.zeros(200_000), lift=50.0) + sigma_n * rng.standard_normal(200_000)
    m = rm.measure(y, 1.0)
    assert m.r[0] == pytest.approx(-2.0 / 3.0, abs=0.01)
    assert m.r[1] == pytest.approx(1.0 / 6.0, abs=0.01)
    assert m.noise_sd.value == pytest.approx(sigma_n, rel=0.01)
    assert m.noisy and m.impulse_var.value == pytest.approx(0.0, abs=0.01 * sigma_n**2)


def test_low_pass_second_differences_are_ar1():
    rng = np.random.default_rng(3)
    alpha = 0.85
    d = lfilter([1.0], [1.0, -alpha], rng.standard_normal(100_000))
    m = rm.measure(_one_side_record(d), 1.0)
    np.testing.assert_allclose(m.r[:4], alpha ** np.arange(1, 5), atol=0.02)
    assert m.pole.value == pytest.approx(alpha, abs=3 * m.pole.se + 0.005)
    assert m.coloured and not m.noisy


def _simulated(seed, n=200_000, pole=0.0, dt=DT_WHITE):
    theta, _ = simulate_block([seed], n, dt=dt, g=1.0, e=0.9, sigma_p=1.0, burn_in=BURN_IN, pole=pole)
    return theta[0]


def test_white_load_record_reads_white_with_its_g():
    m = rm.measure(_simulated(11), DT_WHITE)
    assert m.kind == "white"
    assert abs(m.g.value - 1.0) < 0.04  # the selection of triples biases g by about -2 %
    assert m.impulse_sd.value == pytest.approx(1.0, rel=0.1)  # biased about +7 % (docs/method.md)
    assert m.noise_ratio.value < 0.002


def test_side_g_share_is_one_at_the_side_means_own_samples_per_cycle():
    """At the samples per cycle eq. 5 gives for the side means' own ``g`` the share is 1; it
    scales as the square of the samples per cycle; no positive ``g`` gives 0."""
    import dataclasses

    from rockdec.physics.models import period_from_g

    m = rm.measure(_simulated(11), DT_WHITE)
    n = period_from_g(m.sigma_y, m.g.value) / DT_WHITE
    assert m.side_g_share(n) == pytest.approx(1.0, rel=1e-12)
    assert m.side_g_share(2.0 * n) == pytest.approx(4.0, rel=1e-12)
    assert dataclasses.replace(m, g=rm.Quantity(-0.1, 0.01)).side_g_share(n) == 0.0


@pytest.mark.parametrize("share", [0.01, 0.05])
def test_sensor_noise_is_measured_in_units_of_sigma_y(share):
    y = _simulated(12)
    noisy = y + share * y.std() * series_rng(99).standard_normal(y.size)
    m = rm.measure(noisy, DT_WHITE)
    assert m.kind == "noisy"
    assert m.noise_ratio.value == pytest.approx(share, rel=0.1)
    assert abs(m.noise_ratio.value - share) < 4 * m.noise_ratio.se
    assert abs(m.g.value - 1.0) < 0.06


@pytest.mark.parametrize("noise, kind", [(0.0, "coloured"), (0.02, "both")])
def test_low_pass_load_corner_is_recovered_under_sensor_noise(noise, kind):
    pole = Load("lowpass", 1.0).pole(75.0)
    y = _simulated(13, pole=pole, dt=DT_CORNER_1)
    m = rm.measure(y + noise * y.std() * series_rng(98).standard_normal(y.size), DT_CORNER_1)
    assert m.kind == kind
    if noise:  # seen through the structure function only, whose tail pulls the pole up
        assert m.noise_ratio.value == pytest.approx(noise, rel=0.1)
        assert pole - 0.02 < m.pole.value < 1.0
    else:
        assert m.pole.value == pytest.approx(pole, abs=0.01)
        true_hz = -math.log(pole) / (2 * math.pi * DT_CORNER_1)
        assert m.corner_hz.value == pytest.approx(true_hz, rel=0.15)


def test_reference_flight_record_with_sensor_noise():
    """An independent simulator (one impact at a time, pure Python) and added noise."""
    rng = np.random.default_rng(21)
    n, dt, e = 60_000, DT_WHITE, 0.9
    impulses = rng.standard_normal(n + BURN_IN)
    theta, omega = 0.0, 0.0
    y = np.empty(n)
    for i in range(n + BURN_IN):
        theta, omega = flight_reference(theta, omega, dt, 1.0, e)
        omega += impulses[i]
        if i >= BURN_IN:
            y[i - BURN_IN] = theta
    clean = rm.measure(y, dt)
    assert clean.kind == "white"
    assert clean.g.value == pytest.approx(1.0, abs=0.05)
    noisy = rm.measure(y + 0.03 * y.std() * rng.standard_normal(n), dt)
    assert noisy.kind == "noisy"
    assert noisy.noise_ratio.value == pytest.approx(0.03, rel=0.08)


@pytest.mark.parametrize("pole, dt, noise", [(0.0, DT_WHITE, 0.01), (Load("lowpass", 1.0).pole(75.0), DT_CORNER_1, 0.0)])
def test_scale_invariance(pole, dt, noise):
    y = _simulated(14, n=100_000, pole=pole, dt=dt)
    y = y + noise * y.std() * series_rng(5).standard_normal(y.size)
    a = rm.measure(y, dt)
    b = rm.measure(y * 3e-3, dt * 0.05)
    assert a.kind == b.kind
    for name in ("noise_ratio", "corner_ratio", "pole"):
        assert getattr(b, name).value == pytest.approx(getattr(a, name).value, rel=1e-9)
        assert getattr(b, name).se == pytest.approx(getattr(a, name).se, rel=1e-6, nan_ok=True)
    assert b.g.value == pytest.approx(a.g.value * 3e-3 / 0.05**2, rel=1e-9)
    assert b.corner_hz.value == pytest.approx(a.corner_hz.value / 0.05, rel=1e-9)


def test_split_record_and_gaps_agree_with_whole():
    y = _simulated(15)
    whole = rm.measure(y, DT_WHITE)
    parts = rm.measure([y[:80_000], y[80_000:]], DT_WHITE)
    gappy = y.copy()
    gappy[np.arange(1000, y.size, 20_000)] = np.nan
    holed = rm.measure(gappy, DT_WHITE)
    for other in (parts, holed):
        assert other.g.value == pytest.approx(whole.g.value, abs=whole.g.se)
        assert other.impulse_var.value == pytest.approx(whole.impulse_var.value, abs=whole.impulse_var.se)
        assert other.kind == whole.kind


def test_drift_is_flagged_and_clean_is_not():
    y = _simulated(16)
    clean = rm.measure(y, DT_WHITE)
    assert not clean.drifting
    trend = np.linspace(-0.3, 0.3, y.size) * y.std()
    drifted = rm.measure(y + trend, DT_WHITE)
    assert drifted.drifting and drifted.drift_z > clean.drift_z


def test_bad_input_is_refused_in_one_sentence():
    with pytest.raises(InputError, match="dt"):
        rm.measure(np.ones(10_000), float("nan"))
    with pytest.raises(InputError, match="longer record"):
        rm.measure(np.full(10_000, np.nan), 1.0)
    with pytest.raises(InputError, match="longer record"):
        rm.measure(np.arange(100.0), 1.0)


def test_a_structure_function_without_spread_is_refused_in_one_sentence_not_an_internal_error():
    """All-zero second differences (a block at rest) leave every residual of the fit NaN: the
    fit says so (InputError, which rockdec estimate turns into 'model not measured')."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        with pytest.raises(InputError, match="no usable spread"):
            rm.fit_structure(np.zeros(rm.MAX_LAG + 1))


def test_a_fit_that_gives_every_variance_to_noise_has_no_noise_ratio():
    """Second differences of pure white noise (``sigma_n^2 (6, -4, 1, 0, ...)``) larger than
    the record's variance leave no rocking ``sigma_Y``: the noise ratio is NaN, not a
    division by zero (a jackknife block of a coloured, noisy record at e = 0.95 met it)."""
    gamma = np.zeros(rm.MAX_LAG + 1)
    gamma[:3] = [6.0, -4.0, 1.0]
    out = rm._quantities(np.array([1000.0]), np.array([0.0]), np.array([1.0]), np.array([[500.0, 500.0]]), np.array([[-1.0, 1.0]]),
                         gamma[None, :] * 1000.0, np.full((1, rm.MAX_LAG + 1), 1000.0),
                         *(np.full((1, len(rm.SHAPE_SPANS), 2), v) for v in (500.0, 0.0, 3000.0)), 0.1)
    assert out["sigma_y"][0] == 0.0 and out["noise_var"][0] == pytest.approx(1.0) and math.isnan(out["noise_ratio"][0])


def test_shape_ratio_closed_forms_and_its_inverse():
    """White impulses: V_L = L (2 L^2 + 1) / 3, so Q = (V_16 - V_8) / (V_8 - V_4) = 2392 / 300;
    a pole near 1 (V_L ~ L^4): Q -> (16^4 - 8^4) / (8^4 - 4^4) = 16; noise adds the same to
    every span and cancels; pole_of_shape inverts shape_of_pole."""
    assert rm.WHITE_SHAPE == pytest.approx(2392.0 / 300.0, rel=1e-12)
    assert float(rm.shape_of_pole(rm.MAX_POLE)) == pytest.approx(16.0, abs=0.01)
    s = rm._triangle_products(rm.SHAPE_SPANS) @ (0.9 ** np.arange(2 * max(rm.SHAPE_SPANS) - 1))
    assert float(rm.shape_ratio(s + 6.0 * 123.0)) == pytest.approx(float(rm.shape_of_pole(0.9)), rel=1e-12)
    poles = np.array([-0.5, 0.3, 0.78, 0.92, 0.99])
    np.testing.assert_allclose(rm.pole_of_shape(rm.shape_of_pole(poles)), poles, atol=2e-3)


def test_span_differences_sum_kept_second_differences_only():
    """A span difference is the triangle-weighted sum of the one-step second differences
    it spans, and is left out (NaN) when any of them is."""
    y = series_rng(3).standard_normal(200).cumsum().cumsum() + 1e4
    d, _ = rm.second_differences(y)
    x = rm.span_differences(y, d, 4)
    k = 50
    assert x[k] == pytest.approx(np.dot([1, 2, 3, 4, 3, 2, 1], d[k - 3 : k + 4]), rel=1e-9)
    d[k + 3] = np.nan
    assert np.isnan(rm.span_differences(y, d, 4)[k]) and np.isfinite(rm.span_differences(y, d, 3)[k])


@pytest.mark.parametrize("pole, dt, n, noise, coloured", [
    (Load("lowpass", 1.0).pole(75.0), DT_CORNER_1, 200_000, 0.02, True),
    (0.0, DT_WHITE, 100_000, 0.05, False),
])
def test_colour_beneath_sensor_noise_is_read_off_the_shape(pole, dt, n, noise, coloured):
    """Beneath 2 % noise a load with its corner at the rocking frequency is coloured, its
    shape near Q(alpha) and its corner below the floor even 2 errors up; noise alone over a
    white load is not coloured and rules out a corner below 2 (benchmarks/colour_detection.py
    measures the rates)."""
    y = _simulated(16, n=n, pole=pole, dt=dt)
    m = rm.measure(y + noise * y.std() * series_rng(17).standard_normal(y.size), dt)
    assert m.noisy and m.coloured == coloured
    if coloured:
        assert m.shape.value == pytest.approx(float(rm.shape_of_pole(pole)), abs=1.5)
        assert m.shape_corner_low(75.0, 2.0) < 2.0
    else:
        assert abs(m.shape.value - rm.WHITE_SHAPE) < 4 * m.shape.se
        assert m.shape_corner_low(75.0, 2.0) > 2.0


@pytest.mark.parametrize("pole", [0.0, 0.78])
def test_the_asymmetry_reads_a_lean_about_the_impact_level(pole):
    """A push of ``b g`` towards the positive side (impulses of mean ``b g dt``) leaves the
    block ``g (1 - b)`` there and ``g (1 + b)`` on the other (eq. 4): the reported asymmetry
    ``(g+ - g-)/(g+ + g-)`` is ``-b`` within 3 of its standard errors for b = 0.03 and 0.3
    (and within 0.02 for 0.3), under a white and a low-pass load (pole 0.78 per sample,
    where a lean moves the record's mean off the impact level); a mirrored record reads
    ``+b``, and the reading is the asymmetry check's (rockdec.record.diagnostics) within 0.001
    (its blocks leave out the triples across their ends)."""
    from rockdec.physics.loading import draw_impulses
    from conftest import calibrated_step
    from rockdec.physics.simulate import integrate
    from rockdec.record import diagnostics

    step = calibrated_step(0.9, 1.0, 1.0, 75.0)
    n = 60_000
    for b in (0.03, 0.3):
        for seed in (31, 32, 33):
            impulses = np.empty(step["burn_in"] + n - 1)
            draw_impulses(series_rng(seed), impulses, 1.0, pole)
            impulses += b * step["dt"]
            theta, omega = np.empty(n), np.empty(n)
            integrate(impulses, step["dt"], 1.0, 0.9, 0.0, 0.0, step["burn_in"], theta, omega)
            got = rm.measure(theta, step["dt"]).asymmetry
            assert abs(got.value + b) < 3.0 * got.se and got.se < 0.02
            assert b < 0.1 or got.value == pytest.approx(-b, abs=0.02)
            assert rm.measure(-theta, step["dt"]).asymmetry.value == pytest.approx(-got.value, rel=1e-6)
            assert abs(got.value) == pytest.approx(diagnostics.asymmetry(diagnostics.sums([theta]), None), abs=0.001)


@pytest.mark.parametrize("n, gaps", [(300, 0), (5_000, 7), (40_000, 30), (40_000, 0)])
def test_second_difference_spectra_are_scipys_spectrogram_to_the_bit(n, gaps):
    """The roll-off's periodograms are scipy.signal.spectrogram's (its default periodic Tukey
    window of 0.25, each segment less its mean, half overlap) to the last bit, and a segment
    is left out exactly when scipy's spectrogram of the NaN mask has power in it; two records
    of one step, one with gaps, pooled (segments of an eighth of the longer up to 1024)."""
    from scipy import signal

    rng = np.random.default_rng(n + gaps)
    records = [np.cumsum(np.cumsum(rng.standard_normal(size))) for size in (n, n // 2 + 3)]
    records[0][rng.choice(n, gaps, replace=False)] = np.nan
    frequency, spectra = rm.second_difference_spectra(records)
    size = (frequency.size - 1) * 2
    assert np.array_equal(rm.periodic_tukey(size), signal.windows.tukey(size, 0.25, sym=False))
    expected = []
    for y in records:
        d = np.diff(y, 2)
        f, _, s = signal.spectrogram(np.nan_to_num(d), nperseg=size, noverlap=size // 2, detrend="constant")
        bad = signal.spectrogram(np.isnan(d).astype(float), nperseg=size, noverlap=size // 2, detrend=False)[2].any(axis=0)
        expected.append(s[:, ~bad].T)
    expected = np.concatenate(expected)
    assert np.array_equal(frequency, f) and spectra.shape == expected.shape
    assert np.array_equal(spectra.view(np.uint64), expected.view(np.uint64))
    assert gaps == 0 or spectra.shape[0] < sum(1 + (y.size - 2 - size) // (size - size // 2) for y in records)

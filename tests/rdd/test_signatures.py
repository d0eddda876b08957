"""Properties of the Random Decrement signatures (paper §3, eqs. 8-20; docs/method.md §4)."""

from __future__ import annotations

import dask
import numpy as np
import pytest
import xarray as xr
from reference_signatures import reference_per_window
from scipy.signal import find_peaks, lfilter

from rockdec.rdd.signatures import (
    NoTriggerWarning,
    crossing_sums,
    extremum_sums,
    free_response,
    lag_samples,
    mean_signature,
    pool,
    signature_cube,
)

# --------------------------------------------------------------------------- helpers


def modulated_sine(n, period=37.3, mod_period=1234.5, depth=0.3, phase=0.1):
    """A sine whose amplitude drifts slowly: sampled extrema of many different heights."""
    t = np.arange(n)
    return (1.0 + depth * np.sin(2 * np.pi * t / mod_period)) * np.sin(2 * np.pi * t / period + phase)


def ar2(n, seed, zeta=0.05, per_period=40, burn=5000):
    """Linear oscillator under white noise as an AR(2) process (poles of a damped oscillator)."""
    w = 2 * np.pi / per_period
    r = np.exp(-zeta * w)
    phi1, phi2 = 2 * r * np.cos(w * np.sqrt(1 - zeta**2)), -r * r
    eps = np.random.default_rng(seed).standard_normal(n + burn)
    return lfilter([1.0], [1.0, -phi1, -phi2], eps)[burn:]


def peak_segments(y, a, da, n_lag, both_signs=True):
    """Independent D_a reference: extrema from scipy's find_peaks, segments gathered by slicing."""
    segments = []
    for sign in (1.0, -1.0) if both_signs else (1.0,):
        peaks, _ = find_peaks(sign * y)
        for p in peaks:
            if n_lag <= p < y.size - n_lag and abs(sign * y[p] - a) <= da:
                segments.append(sign * y[p - n_lag : p + n_lag + 1])
    return np.array(segments).reshape(-1, 2 * n_lag + 1)


def rocking_free_response(e, n_crossings, samples_per_cycle, g=1.0, amplitude=1.0, offset=0.37):
    """Analytic free rocking of the simplified model (eq. 4) through impacts (eq. 6).

    Released at rest from ``amplitude``: parabolic arcs under ``-g sign(theta)``, the
    velocity multiplied by ``e`` at each zero crossing. Returns ``(theta, dt, v_in)`` with
    the pre-impact speeds ``v_in`` of the crossings.
    """
    v0 = np.sqrt(2 * g * amplitude)
    dt = 4 * np.sqrt(2 * amplitude / g) / samples_per_cycle
    v_in = v0 * e ** np.arange(n_crossings)
    t_cross = np.sqrt(2 * amplitude / g) + np.concatenate([[0.0], np.cumsum(2 * e * v_in[:-1] / g)])
    t = (np.arange(int(t_cross[-1] / dt)) + offset) * dt
    arc = np.searchsorted(t_cross, t)  # 0: first fall, k: after crossing k-1
    theta = np.empty_like(t)
    first = arc == 0
    theta[first] = amplitude - 0.5 * g * t[first] ** 2
    k = arc[~first] - 1
    s = t[~first] - t_cross[k]
    side = np.where(k % 2 == 0, -1.0, 1.0)  # sign of theta after crossing k
    theta[~first] = side * (e * v_in[k] * s - 0.5 * g * s**2)
    return theta, dt, v_in


def slope_at_zero(values):
    """Slope at lag 0 of the quadratic through ``values`` at lags 1, 2, ... (unit spacing)."""
    return np.polyfit(np.arange(1, values.size + 1), values, 2)[1]


def cube_kwargs(**over):
    kw = dict(sigma_y=0.5, sigma_ydot=0.35, level=2.0, windows=(0.25, 0.5, 1.0), n_lag=12)
    kw.update(over)
    return kw


def seeds_block(n_seed=6, n=3000):
    rng = np.random.default_rng(7)
    y = np.stack([modulated_sine(n, period=37.3 + 3 * s, phase=s) for s in range(n_seed)])
    y += 0.02 * rng.standard_normal(y.shape)
    y[2, 400:410] = np.nan
    return xr.DataArray(y, dims=("seed", "time"), coords={"seed": np.arange(n_seed) + 100}, attrs={"dt": 0.5, "units": "rad"})


def _no_compute(*args, **kwargs):
    raise AssertionError("building the signature graph computed something")


# --------------------------------------------------------------------------- linear system


def gaussian_peak_signature(R, a, n_lag):
    """Exact ``E[Y(tau) | Y(0) = a, Y(-1) < Y(0) >= Y(1)]`` of a zero-mean Gaussian sequence.

    Built from the autocovariance ``R[k]`` alone. The first term is eq. 9, ``a R(tau)/R(0)``;
    the second is what a *sampled* extremum adds: the trigger selects the increments
    ``Y(0) - Y(-1) > 0 >= Y(1) - Y(0)`` (a discrete ``Y' = 0`` with negative curvature),
    and their truncated mean differs from their mean given ``Y(0) = a`` alone.
    """
    tau = np.arange(-n_lag, n_lag + 1)
    r = lambda k: R[np.abs(k)]  # noqa: E731
    c_yd = np.array([R[0] - R[1], R[1] - R[0]])  # Cov(Y0, (dY-, dY+))
    c_dd = np.array([[2 * (R[0] - R[1]), 2 * R[1] - R[0] - R[2]], [2 * R[1] - R[0] - R[2], 2 * (R[0] - R[1])]])
    mean = c_yd * a / R[0]
    cov = c_dd - np.outer(c_yd, c_yd) / R[0]
    inv = np.linalg.inv(cov)
    grid = np.linspace(-9.0, 9.0, 1201)
    u1, u2 = mean[0] + np.sqrt(cov[0, 0]) * grid, mean[1] + np.sqrt(cov[1, 1]) * grid
    x1, x2 = np.meshgrid(u1[u1 > 0], u2[u2 <= 0], indexing="ij")  # the trigger's quadrant: the grid's other points weigh 0
    d1, d2 = x1 - mean[0], x2 - mean[1]
    weight = np.exp(-0.5 * (inv[0, 0] * d1**2 + 2 * inv[0, 1] * d1 * d2 + inv[1, 1] * d2**2))
    truncated = np.array([(weight * x1).sum(), (weight * x2).sum()]) / weight.sum()
    c_td = np.stack([r(tau) - r(tau + 1), r(tau - 1) - r(tau)], axis=-1) - np.outer(r(tau), c_yd) / R[0]
    eq9 = a * r(tau) / R[0]
    return eq9 + c_td @ inv @ (truncated - mean), eq9


def autocovariance(y, n):
    """Biased autocovariance ``R[0..n]`` by FFT (zero-padded, no wrap-around)."""
    y = y - y.mean()
    spectrum = np.fft.rfft(y, 2 * y.size)
    return np.fft.irfft(np.abs(spectrum) ** 2)[: n + 1] / y.size


def test_extremum_signature_of_linear_oscillator_matches_correlation_function():
    """Eqs. 9-11: for a Gaussian (linear, white-noise driven) response, D_a = a R(tau)/sigma^2,
    up to the known effect of taking ``y' = 0`` as a sampled extremum.

    Tolerance: the record is cut into 20 batches; the spread of the batch differences
    ``D - prediction`` gives a standard error that accounts for the correlation of
    neighbouring triggers (peaks above 1.5 sigma come in clusters over the ~3-period
    envelope correlation time) and for the error of the FFT estimate of ``R``. Five
    standard errors, on every lag, fails by chance with negligible probability.
    """
    n_lag, batches = 80, 20
    y = ar2(1_000_000, seed=1)
    sigma = y.std()
    a, da = 1.5 * sigma, 0.05 * sigma

    def difference(record):
        res = extremum_sums(record, a, [da], n_lag)
        d = res.sum[..., 0, :] / res.count[..., 0, None]
        exact, eq9 = gaussian_peak_signature(autocovariance(record, n_lag + 2), d[n_lag], n_lag)
        return d, exact, eq9

    d, exact, eq9 = difference(y)
    batch_diffs = [np.subtract(*difference(part)[:2]) for part in y.reshape(batches, -1)]
    se = np.std(batch_diffs, axis=0, ddof=1) / np.sqrt(batches)
    se[n_lag] = 1e-12  # lag 0: the trigger value itself, no sampling error in the difference
    assert np.all(np.abs(d - exact) <= 5 * se + 1e-12)
    # the sampled-extremum correction is a few per cent of a: eq. 9 holds to 5 %
    assert np.max(np.abs(exact - eq9)) < 0.05 * a
    assert np.max(np.abs(d - eq9)) < 0.05 * a + 5 * se.max()


# --------------------------------------------------------------------------- exactness


def test_periodic_record_gives_its_segment_back():
    """An integer-period sine: every extremum sees the same samples, so D_a is the segment."""
    n_lag, period = 25, 40
    y = np.sin(2 * np.pi * np.arange(4000) / period + 0.3)
    peak = int(np.argmax(y[:period])) + period  # a sampled maximum with a full segment
    res = extremum_sums(y, y[peak], [1e-9], n_lag)
    expected = peak_segments(y, y[peak], 1e-9, n_lag)
    assert res.count[0] == expected.shape[0] > 190
    np.testing.assert_allclose(res.sum[0] / res.count[0], y[peak - n_lag : peak + n_lag + 1], rtol=0, atol=1e-13)


def test_counts_and_sums_equal_independently_found_extrema():
    n_lag = 30
    y = modulated_sine(20_000)
    half_widths = np.array([0.02, 0.05, 0.1, 0.2])
    res = extremum_sums(y, 1.0, half_widths, n_lag)
    for w, da in enumerate(half_widths):
        segs = peak_segments(y, 1.0, da, n_lag)
        assert res.count[w] == segs.shape[0] > 0
        np.testing.assert_allclose(res.sum[w], segs.sum(axis=0), rtol=1e-12, atol=1e-12)
    one_sided = extremum_sums(y, 1.0, half_widths, n_lag, both_signs=False)
    assert np.array_equal(one_sided.count, [peak_segments(y, 1.0, da, n_lag, both_signs=False).shape[0] for da in half_widths])


def test_mirrored_record_gives_the_same_signatures():
    """The minimum rule mirrors the maximum rule (ties included), so -y triggers like y."""
    y = np.round(modulated_sine(5000), 2)  # rounding creates flat tops and bottoms
    for kernel, args in ((extremum_sums, (1.0, [0.05, 0.1], 20)), (crossing_sums, (0.15, [0.05, 0.1], 20, 1.0))):
        up, down = kernel(y, *args), kernel(-y, *args)
        assert np.array_equal(up.count, down.count)
        np.testing.assert_allclose(up.sum, down.sum, rtol=1e-13, atol=1e-13)


def test_flat_top_triggers_once_at_its_first_sample():
    y = np.array([0.0, 0.5, 1.0, 1.0, 0.5, 0.0, 0.5, 1.0, 1.0, 0.5, 0.0])
    res = extremum_sums(y, 1.0, [0.0], 2, both_signs=False)
    assert res.count[0] == 2
    np.testing.assert_array_equal(res.sum[0], y[0:5] + y[5:10])


def test_zero_crossing_signature_of_rocking_free_response_kinks_by_e():
    """D_v on the analytic free response (eqs. 4, 6): 0 at lag 0, one-sided slopes in ratio e.

    The chord root places the crossing within ``(1 - e) dt / (4 e)`` of the true one; that
    shift changes each one-sided slope by at most ``g`` times it, so the ratio is within
    ``(1 + e) g (1 - e) dt / (4 e^2 v_min)`` of ``e`` (``v_min`` the slowest crossing used).
    The interpolation error is a constant along each arc and does not move the slopes.
    """
    e, g = 0.9, 1.0
    theta, dt, v_in = rocking_free_response(e, n_crossings=10, samples_per_cycle=400, g=g)
    n_lag, fit = 20, 8
    res = crossing_sums(theta, 0.5 * v_in[0], [0.75 * v_in[0]], n_lag, dt)
    assert res.count[0] == 9  # all crossings but the last, whose segment runs off the record
    d = res.sum[0] / res.count[0]
    assert d[n_lag] == 0.0
    ratio = slope_at_zero(d[n_lag + 1 : n_lag + 1 + fit]) / -slope_at_zero(d[n_lag - 1 :: -1][:fit])
    tolerance = (1 + e) * g * (1 - e) * dt / (4 * e**2 * v_in[8])
    assert abs(ratio - e) <= tolerance
    left_slope = -slope_at_zero(d[n_lag - 1 :: -1][:fit]) / dt
    np.testing.assert_allclose(left_slope, v_in[:9].mean(), rtol=tolerance)


def test_crossing_velocity_is_the_incoming_one():
    """A crossing triggers on its pre-impact speed, not on the outgoing or an averaged one."""
    e = 0.5
    theta, dt, v_in = rocking_free_response(e, n_crossings=4, samples_per_cycle=400)
    narrow = 0.02 * v_in[1]
    assert crossing_sums(theta, v_in[1], [narrow], 10, dt).count[0] == 1
    assert crossing_sums(theta, e * v_in[1], [narrow], 10, dt).count[0] == 1  # that is v_in[2]
    assert crossing_sums(theta, 0.75 * v_in[1], [narrow], 10, dt).count[0] == 0


# --------------------------------------------------------------------------- one pass, chunks, pooling


def test_one_pass_equals_per_window_reference():
    y = np.stack([ar2(20_000, seed=s) for s in range(3)])
    y[1, 500::300] = np.nan  # isolated gaps: some segments reach one
    sigma, sigma_v = y[0].std(), np.diff(y[0]).std()
    widths = np.linspace(0.1, 1.0, 10) * 0.28
    fast_a = extremum_sums(y, 1.5 * sigma, widths * 1.5 * sigma, 30)
    ref_a = reference_per_window(y, "a", 1.5 * sigma, widths * 1.5 * sigma, 30)
    fast_v = crossing_sums(y, sigma_v, widths * sigma_v, 30, 1.0)
    ref_v = reference_per_window(y, "v", sigma_v, widths * sigma_v, 30, dt=1.0)
    for fast, ref in ((fast_a, ref_a), (fast_v, ref_v)):
        assert fast.count[:, 0].min() > 0 and fast.skipped[1, -1] > 0
        assert np.array_equal(fast.count, ref.count) and np.array_equal(fast.skipped, ref.skipped)
        np.testing.assert_allclose(fast.sum, ref.sum, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("time_chunk", [5, 17, 137, 1000])
def test_time_chunked_record_equals_whole_record(time_chunk):
    theta = seeds_block(n=1200)  # chunks of 1000 still cut it; a gap at 400-409 in seed 102
    whole = signature_cube(theta, **cube_kwargs())
    chunked = signature_cube(theta.chunk({"seed": 4, "time": time_chunk}), **cube_kwargs())
    assert chunked["count"].chunks is not None
    chunked = chunked.compute()
    assert np.array_equal(whole["count"].values, chunked["count"].values)
    assert np.array_equal(whole["skipped"].values, chunked["skipped"].values)
    assert whole["skipped"].sel(seed=102).max() > 0
    np.testing.assert_allclose(whole.signature_sum, chunked.signature_sum, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("use_dask", [True, False])
def test_cube_equals_kernels(use_dask):
    theta = seeds_block()
    kw = cube_kwargs()
    cube = signature_cube(theta.chunk({"seed": 4}) if use_dask else theta, **kw).compute()
    a, v = kw["level"] * kw["sigma_y"], kw["sigma_ydot"]
    windows = np.asarray(kw["windows"])
    sa = extremum_sums(theta.values, a, windows * 0.28 * a, kw["n_lag"])
    sv = crossing_sums(theta.values, v, windows * 0.28 * v, kw["n_lag"], theta.attrs["dt"])
    assert np.array_equal(cube["count"].sel(trigger="a").values, sa.count)
    assert np.array_equal(cube["count"].sel(trigger="v").values, sv.count)
    np.testing.assert_array_equal(cube.signature_sum.sel(trigger="a").values, sa.sum)
    np.testing.assert_array_equal(cube.signature_sum.sel(trigger="v").values, sv.sum)
    with np.errstate(invalid="ignore"):
        np.testing.assert_array_equal(cube.signature.sel(trigger="a").values, sa.sum / sa.count[..., None])
    np.testing.assert_array_equal(cube.free_response.values, free_response(cube.signature.sel(trigger="a").values))


def test_dask_over_seeds_equals_numpy():
    theta = seeds_block()
    eager = signature_cube(theta, **cube_kwargs())
    lazy = signature_cube(theta.chunk({"seed": 2}), **cube_kwargs())
    xr.testing.assert_identical(eager, lazy.compute())


@pytest.mark.parametrize("chunks", [{"seed": 2}, {"seed": 2, "time": 500}])
def test_building_the_graph_computes_nothing(chunks):
    theta = seeds_block().chunk(chunks)
    group = xr.DataArray([0, 0, 1, 1, 1, 2], dims="seed", coords={"seed": theta.seed})
    with dask.config.set(scheduler=_no_compute):
        cube = signature_cube(theta, **cube_kwargs(), group=group)
        pooled = pool(cube, "group")
    assert cube.signature.chunks is not None and pooled.signature.chunks is not None


def test_pooled_signature_is_the_mean_over_the_union_of_triggers():
    theta = seeds_block()
    kw = cube_kwargs(n_lag=30)
    pooled = pool(signature_cube(theta, **kw), "seed")
    a = kw["level"] * kw["sigma_y"]
    for w, rel in enumerate(kw["windows"]):
        segments = [peak_segments(row, a, rel * 0.28 * a, 30) for row in theta.values]
        union = np.concatenate([s[~np.isnan(s).any(axis=1)] for s in segments])
        assert pooled["count"].sel(trigger="a").values[w] == union.shape[0]
        np.testing.assert_allclose(pooled.signature.sel(trigger="a").values[w], union.mean(axis=0), rtol=1e-12, atol=1e-12)
    assert set(pooled.dims) == {"trigger", "window", "lag", "lag_pos"}



@pytest.mark.parametrize(
    "by",
    [
        [0, 0, 0, 1, 1, 2, -1, -1, 3],  # runs in label order
        [-1, 3, 3, 1, 0, 0, 2, 2, 2],  # one run a label, out of order (a pass's groups_of_10 units)
        [1, 0, 1, -1, 0, 2, 2, 0, 1],  # labels split over several runs
        [2, 0, -1, 1, 3, 4, 5, 6, 7],  # one entry a label
    ],
)
def test_pooling_by_labels_adds_each_labels_entries_in_their_order(by):
    """``pool(..., by=)`` sums each label's entries in their order along the dimension,
    whichever way the labels lie: bit for bit the sum of the label's entries gathered
    together (so a pass's pooled cube does not depend on how its units are laid out)."""
    rng = np.random.default_rng(7)
    by = np.array(by)
    n = by.size
    cube = xr.Dataset(
        {
            "signature_sum": (("unit", "trigger", "window", "lag"), rng.standard_normal((n, 2, 3, 9)) * 10.0 ** rng.integers(-8, 8, (n, 1, 1, 1))),
            "count": (("unit", "trigger", "window"), rng.integers(1, 50, (n, 2, 3))),
            "skipped": (("unit", "trigger", "window"), rng.integers(0, 3, (n, 2, 3))),
        },
        coords={"trigger": ["a", "v"], "window": [0.5, 0.75, 1.0], "lag": np.arange(-4, 5) * 0.1},
    )
    pooled = pool(cube, "unit", by=by)
    labels = sorted(set(by[by >= 0]))
    assert list(pooled.group.values) == labels
    for name in ("signature_sum", "count", "skipped"):
        for label in labels:
            gathered = cube[name].values[by == label]
            got = pooled[name].sel(group=label).values
            assert np.array_equal(got, np.add.reduceat(gathered, [0], axis=0)[0]), (name, label)
            np.testing.assert_allclose(got, sum(gathered[1:], gathered[0]), rtol=1e-12, atol=0)

def test_kernels_sum_series_into_their_output_rows():
    """``rows_to`` adds each series into its row inside the kernel: the per-series sums added."""
    y = np.stack([ar2(8000, seed=s) for s in range(7)])
    y[4, 900::400] = np.nan  # some segments reach a gap: skipped
    rows_to = np.array([3, 0, 3, 1, 0, 3, 1])  # unsorted; row 2 gets no series
    sigma, sigma_v = y[0].std(), np.diff(y[0]).std()
    widths = np.array([0.1, 0.2, 0.28])
    for kernel, args in (
        (extremum_sums, (1.5 * sigma, widths * 1.5 * sigma, 20)),
        (crossing_sums, (sigma_v, widths * sigma_v, 20, 1.0)),
    ):
        per_series, grouped = kernel(y, *args), kernel(y, *args, rows_to=rows_to)
        assert grouped.sum.shape == (4, 3, 41) and grouped.count.shape == (4, 3)
        for row in range(4):
            members = rows_to == row
            assert np.array_equal(grouped.count[row], per_series.count[members].sum(axis=0))
            assert np.array_equal(grouped.skipped[row], per_series.skipped[members].sum(axis=0))
            np.testing.assert_allclose(grouped.sum[row], per_series.sum[members].sum(axis=0), rtol=1e-12, atol=1e-12)
        assert grouped.count[2].sum() == 0 and grouped.sum[2].max() == 0  # no series: zeros
        assert grouped.skipped[0, -1] > 0 and grouped.count[[0, 1, 3], 0].min() > 0
        with pytest.raises(ValueError, match="rows_to"):
            kernel(y, *args, rows_to=rows_to[:-1])
        with pytest.raises(ValueError, match="rows_to"):
            kernel(y, *args, rows_to=rows_to - 1)


def sums_by_label(per_seed, labels, dim="seed"):
    """Group sums the old way: per-series sums, added with NumPy label by label."""
    out = {}
    for label in np.unique(labels):
        members = per_seed.isel({dim: np.flatnonzero(labels == label)})
        out[label] = {name: members[name].sum(dim).values for name in ("signature_sum", "count", "skipped")}
    return out


GROUPINGS = {
    "aligned with chunks": [3, 3, 5, 5, 9, 9],
    "straddling chunks": [3, 3, 5, 5, 5, 9],
    "unsorted": [9, 3, 5, 3, 9, 5],
    "one group": [7, 7, 7, 7, 7, 7],
}


@pytest.mark.parametrize("labels", GROUPINGS.values(), ids=GROUPINGS.keys())
@pytest.mark.parametrize("chunks", [None, {"seed": 2}, {"seed": 4}, {"seed": 2, "time": 500}], ids=str)
def test_group_sums_equal_sums_of_their_seeds(labels, chunks):
    theta = seeds_block()
    labels = np.array(labels)
    group = xr.DataArray(labels, dims="seed", coords={"seed": theta.seed}, attrs={"description": "scene groups"})
    per_seed = signature_cube(theta, **cube_kwargs())
    data = theta if chunks is None else theta.chunk(chunks)
    cube = signature_cube(data, **cube_kwargs(), group=group)
    assert (cube["count"].chunks is None) == (chunks is None)
    grouped = cube.compute()
    assert list(grouped.group.values) == sorted(set(labels))  # xarray's groupby order: sorted labels
    assert grouped.group.attrs == {"description": "scene groups", "long_name": "group of series pooled into one signature"}
    assert grouped.signature_sum.dims == ("group", "trigger", "window", "lag") and grouped["count"].dtype == np.int64
    expected = sums_by_label(per_seed, labels)
    assert grouped.skipped.sel(group=labels[2]).max() > 0  # seed 102 has a gap
    for label, sums in expected.items():
        assert np.array_equal(grouped["count"].sel(group=label).values, sums["count"])
        assert np.array_equal(grouped["skipped"].sel(group=label).values, sums["skipped"])
        np.testing.assert_allclose(grouped.signature_sum.sel(group=label), sums["signature_sum"], rtol=1e-12, atol=1e-12)
    for name in ("window", "lag", "lag_pos", "da", "dv", "trigger"):
        xr.testing.assert_identical(grouped[name], per_seed[name])
    assert grouped.attrs == per_seed.attrs
    xr.testing.assert_allclose(pool(grouped, "group").signature, pool(per_seed, "seed").signature, rtol=1e-12)


def test_dask_group_sums_equal_numpy_ones_with_more_dimensions():
    """Groups along ``seed`` of a ``(replicate, seed, time)`` record: the other dimension and
    its coordinate stay, ``group`` comes first (as with xarray's groupby), Dask equals NumPy."""
    one = seeds_block()
    theta = xr.concat([one, 0.9 * one], dim="replicate").assign_coords(replicate=[10, 20], run=("seed", np.arange(6)))
    group = xr.DataArray([5, 3, 3, 9, 5, 5], dims="seed", coords={"seed": theta.seed})
    whole = signature_cube(theta, **cube_kwargs(), group=group)
    lazy = signature_cube(theta.chunk({"seed": 4, "replicate": 1}), **cube_kwargs(), group=group).compute()
    assert whole.signature_sum.dims == ("group", "replicate", "trigger", "window", "lag")
    assert "run" not in whole.coords and list(whole.replicate.values) == [10, 20]
    xr.testing.assert_allclose(whole, lazy, rtol=1e-12, atol=1e-12)
    assert np.array_equal(whole["count"].values, lazy["count"].values)
    per_seed = signature_cube(theta, **cube_kwargs())
    for replicate in (10, 20):
        expected = sums_by_label(per_seed.sel(replicate=replicate), group.values)
        for label, sums in expected.items():
            got = lazy.sel(group=label, replicate=replicate)
            assert np.array_equal(got["count"].values, sums["count"])
            np.testing.assert_allclose(got.signature_sum, sums["signature_sum"], rtol=1e-12, atol=1e-12)


def test_cube_is_labelled_with_units_and_settings():
    cube = signature_cube(seeds_block(), **cube_kwargs())
    for name in list(cube.data_vars) + ["window", "lag", "lag_pos", "da", "dv"]:
        assert {"units", "long_name"} <= set(cube[name].attrs), name
    assert list(cube.trigger.values) == ["a", "v"]
    assert cube["count"].dtype == np.int64 and cube.signature_sum.dtype == np.float64
    assert cube.sizes["lag"] == 25 and cube.sizes["lag_pos"] == 13
    np.testing.assert_allclose(cube.lag.values[[0, -1]], [-6.0, 6.0])
    assert cube.attrs["a"] == 1.0 and cube.attrs["da_max"] == pytest.approx(0.28)
    assert {"level", "sigma_y", "sigma_ydot", "dv_max", "both_signs", "n_lag", "dt"} <= set(cube.attrs)
    assert "dt" not in cube.signature_sum.attrs  # the record's attributes stay with the record
    sized = signature_cube(seeds_block(), **cube_kwargs(n_lag=None, g=2.0, n_periods=1.0))
    assert sized.attrs["n_lag"] == lag_samples(1.0, 1.0, 2.0, 0.5) == 8 and sized.attrs["g"] == 2.0


def test_sampling_interval_from_time_coordinate():
    theta = seeds_block()
    del theta.attrs["dt"]
    theta = theta.assign_coords(time=np.arange(theta.sizes["time"]) * 0.5)
    assert signature_cube(theta, **cube_kwargs()).attrs["dt"] == 0.5


# --------------------------------------------------------------------------- degenerate inputs


@pytest.mark.parametrize("value", [0.0, 0.3])
def test_constant_record_has_no_trigger(value):
    theta = xr.DataArray(np.full((2, 500), value), dims=("seed", "time"), attrs={"dt": 1.0})
    with pytest.warns(NoTriggerWarning, match="lower the trigger level"):
        cube = signature_cube(theta, **cube_kwargs())
    assert cube["count"].sum() == 0 and cube.signature.isnull().all()


def test_nan_gaps_skip_their_triggers_and_count_them():
    n_lag, a, da = 30, 1.0, 0.1
    clean = modulated_sine(20_000)
    y = clean.copy()
    gaps = [(1000, 1003), (5000, 5040), (12345, 12346)]
    for lo, hi in gaps:
        y[lo:hi] = np.nan
    res = extremum_sums(y, a, [da], n_lag)
    counted, skipped, total = 0, 0, np.zeros(2 * n_lag + 1)
    for seg_sign, peaks in ((1.0, find_peaks(clean)[0]), (-1.0, find_peaks(-clean)[0])):
        for p in peaks:
            if not (n_lag <= p < y.size - n_lag and abs(seg_sign * y[p] - a) <= da) or np.isnan(y[p - 1 : p + 2]).any():
                continue  # not a trigger, or next to a gap: cannot be classified
            if np.isnan(y[p - n_lag : p + n_lag + 1]).any():
                skipped += 1
            else:
                counted += 1
                total += seg_sign * y[p - n_lag : p + n_lag + 1]
    assert skipped > 0 and (res.count[0], res.skipped[0]) == (counted, skipped)
    np.testing.assert_allclose(res.sum[0], total, rtol=1e-12, atol=1e-12)


def test_level_above_every_peak_gives_nan_and_a_warning():
    theta = xr.DataArray(seeds_block().values, dims=("seed", "time"), attrs={"dt": 0.5})
    with pytest.warns(NoTriggerWarning) as record:
        cube = signature_cube(theta, **cube_kwargs(level=10.0))
    messages = [str(w.message) for w in record]
    assert [m.split(":")[0] for m in messages] == [f"no D_a (extremum) trigger in window {w}" for w in ("0.25", "0.5", "1")]
    assert (cube["count"].sel(trigger="a") == 0).all()
    assert cube.signature.sel(trigger="a").isnull().all() and cube.free_response.isnull().all()
    assert (cube["count"].sel(trigger="v") > 0).any()


def test_float32_record_equals_its_float64_cast():
    y32 = modulated_sine(10_000).astype(np.float32)
    y32[300:305] = np.nan
    for kernel, args in ((extremum_sums, (1.0, [0.05, 0.2], 25)), (crossing_sums, (0.3, [0.02, 0.1], 25, 0.5))):
        single, double = kernel(y32, *args), kernel(y32.astype(np.float64), *args)
        assert single.sum.dtype == np.float64
        for got, want in zip(single, double):
            np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("n", [0, 1, 3, 24, 25])
def test_record_shorter_than_the_lag_window_gives_zero_count(n):
    y = modulated_sine(n, period=8.3)
    for res in (extremum_sums(y, 1.0, [0.5], 12), crossing_sums(y, 0.5, [0.5], 12, 1.0)):
        assert res.count.shape == (1,) and res.count[0] == 0 and res.sum.shape == (1, 25)
    with pytest.warns(NoTriggerWarning):
        assert np.isnan(mean_signature(res.sum[None, None], res.count[None, None])).all()
    theta = xr.DataArray(y[None], dims=("seed", "time"), attrs={"dt": 1.0})
    for data in (theta, theta.chunk({"time": 2})) if n else ():
        with pytest.warns(NoTriggerWarning):
            assert signature_cube(data, **cube_kwargs()).compute()["count"].sum() == 0


# --------------------------------------------------------------------------- helpers


def test_lag_samples_uses_the_simplified_period():
    # T(a) = 4 sqrt(2 a / g) = 4 s for a = 1 rad, g = 2 rad/s^2 (eq. 5)
    assert lag_samples(2.5, 1.0, 2.0, 0.01) == 1000
    assert lag_samples(1.0, 1.0, 2.0, 0.3) == 13


def test_free_response_is_the_even_part():
    d = np.array([[5.0, 1.0, 2.0, 3.0, 9.0]])
    np.testing.assert_array_equal(free_response(d), [[2.0, 2.0, 7.0]])

"""The random streams drawn inside numba are NumPy's, bit for bit (rockdec.physics.loading).

The reference is NumPy itself: ``Generator(PCG64(SeedSequence(seed)))`` and its sensor
spawn, and the series-by-series loop through them that every simulator ran before a block
was drawn in one kernel (``draw_impulses`` then ``integrate``).
"""

import numpy as np
import pytest

from rockdec.physics import loading, simulate
from rockdec.validate import InputError

#: Seeds of one and two 32-bit words, the pilots' (from 2**62) and the largest int64.
SEEDS = [0, 1, 7, 2**31, 2**32 - 1, 2**32, 12_345_678_901, 2**62, 2**62 + 5, 2**63 - 1]


def bits(x):
    return np.ascontiguousarray(x).view(np.uint64)


@pytest.mark.parametrize("spawn", [-1, loading.SENSOR_STREAM])
def test_stream_words_are_seedsequences(spawn):
    """Every seed width, both streams, a few seeds (hashed one by one) and a block of them
    (hashed as arrays): NumPy's own ``SeedSequence(seed[, spawn_key]).generate_state(4, uint64)``."""
    spawn_key = () if spawn < 0 else (spawn,)
    block = SEEDS + [seed + 1 for seed in SEEDS[:-1]]
    assert len(SEEDS) <= loading._SEEDS_ONE_BY_ONE < len(block)
    for seeds in (SEEDS, block):
        expected = [np.random.SeedSequence(seed, spawn_key=spawn_key).generate_state(4, np.uint64) for seed in seeds]
        np.testing.assert_array_equal(loading.stream_words(seeds, spawn), expected)


@pytest.mark.parametrize("spawn", [-1, loading.SENSOR_STREAM])
def test_drawn_normals_are_numpys(spawn):
    """Every seed width, both streams: the same 20,000 numbers as NumPy's standard_normal
    (some 400 of them pass the ziggurat's wedges or tail, which draw further outputs)."""
    for seed in SEEDS:
        ours = loading.draw_series(loading.stream_words([seed], spawn)[0], np.empty(20_000), 1.0, None)
        rng = loading.series_rng(seed) if spawn < 0 else loading.sensor_rng(seed)
        np.testing.assert_array_equal(bits(ours), bits(rng.standard_normal(20_000)), err_msg=f"seed {seed}")


def _series_by_series(seeds, n_points, *, pole=0.0, grid_impacts=False, theta0=0.0, **run):
    """The simulators' loop on NumPy's generators: one ``series_rng`` and one ``integrate`` a seed."""
    theta, theta_dot = np.empty((2, len(seeds), n_points))
    impulses = np.empty(run["burn_in"] + n_points - 1)
    for row, seed in enumerate(seeds):
        loading.draw_impulses(loading.series_rng(seed), impulses, run["sigma_p"], pole)
        simulate.integrate(impulses, run["dt"], run["g"], run["e"], theta0, 0.0, run["burn_in"], theta[row], theta_dot[row], grid_impacts)
    return theta, theta_dot


@pytest.mark.parametrize(
    "options", [{}, {"pole": 0.8}, {"grid_impacts": True}, {"sigma_p": 0.0, "theta0": 0.01}], ids=["white", "lowpass", "grid", "free"]
)
def test_block_kernel_is_the_series_loop(options):
    """simulate_block's one-kernel block gives the series-by-series loop's numbers bit for bit."""
    run = {"dt": 0.0035, "g": 1.0, "e": 0.95, "sigma_p": 0.003, "burn_in": 500, **options}
    seeds = [3, 4, 2**40 + 1, 2**62]
    ours = simulate.simulate_block(seeds, 1500, **run)
    for a, b in zip(ours, _series_by_series(seeds, 1500, **run)):
        np.testing.assert_array_equal(bits(a), bits(b))


def test_block_writes_into_out():
    """``out`` receives theta and theta_dot, and the halves returned are views of it."""
    out = np.full((2, 3, 200), np.nan)
    theta, theta_dot = simulate.simulate_block([1, 2, 3], 200, dt=0.0035, g=1.0, e=0.95, sigma_p=0.003, out=out)
    assert np.shares_memory(theta, out) and np.shares_memory(theta_dot, out)
    np.testing.assert_array_equal(out, simulate.simulate_block([1, 2, 3], 200, dt=0.0035, g=1.0, e=0.95, sigma_p=0.003))


def test_sensor_noise_is_the_sensor_stream():
    theta = np.zeros((3, 500))
    loading.add_sensor_noise(theta, [5, 6, 2**33], 0.25)
    for row, seed in zip(theta, [5, 6, 2**33]):
        np.testing.assert_array_equal(bits(row), bits(0.0 + 0.25 * loading.sensor_rng(seed).standard_normal(500)))


def test_negative_seed_refused():
    with pytest.raises(InputError, match="seed -1 is negative"):
        simulate.simulate_block([3, -1], 100, dt=0.0035, g=1.0, e=0.95, sigma_p=0.003)


def test_sensor_noise_negative_seed_refused():
    with pytest.raises(InputError, match="seed -3 is negative"):
        loading.add_sensor_noise(np.zeros((2, 10)), [4, -3], 0.1)

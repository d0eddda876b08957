"""The shake-table tests of the demonstration campaign (rockdec.physics.base_motion)."""

import numpy as np
import pytest

from rockdec.physics.base_motion import GROUND, ground_gain, ground_motion, shake_test
from rockdec.validate import InputError


def test_the_ground_filter_is_kanai_tajimis_at_its_frequency_and_cuts_the_slowest_motion():
    at = float(ground_gain(GROUND["f_g"], **GROUND))
    kanai = 1.0 + 1.0 / (4.0 * GROUND["zeta_g"] ** 2)  # (1 + 4 zeta^2) / (4 zeta^2) at f = f_g
    s = GROUND["f_g"] / GROUND["f_f"]
    high = s**4 / ((1.0 - s * s) ** 2 + (2.0 * GROUND["zeta_f"] * s) ** 2)
    assert at == pytest.approx(np.sqrt(kanai * high), rel=1e-12)
    assert ground_gain(0.0, **GROUND) == 0.0 and ground_gain(0.01, **GROUND) < 1e-3


def test_the_base_shakes_with_its_strength_over_the_first_part_and_then_rests():
    n, dt = 8_000, 0.005
    bases = np.array([ground_motion(n, dt, seed, peak=1.5, g=2.0) for seed in range(8)])
    strong = bases[:, int(0.2 * n / 2) + 1 : int(0.7 * n / 2)]
    assert np.all(bases[:, n // 2 :] == 0.0)
    assert np.std(strong) == pytest.approx(1.5 * 2.0, rel=0.1)
    power = (np.abs(np.fft.rfft(bases[:, : n // 2], axis=1)) ** 2).mean(axis=0)
    f = np.fft.rfftfreq(n // 2, dt)
    assert 2.0 < f[np.argmax(power)] < 8.0  # about the ground's frequency (5 Hz), not the slow end


def test_a_shake_test_scales_with_the_blocks_g():
    """Under the simplified model (eq. 4) theta'' = -g sign(theta) + p: g and the load doubled
    double the angle (every operation of the kernel scales exactly by a power of two)."""
    one, base_one = shake_test(0.9, 4_000, 0.005, 3, peak=2.0, g=1.0, noise=0.01)
    two, base_two = shake_test(0.9, 4_000, 0.005, 3, peak=2.0, g=2.0, noise=0.01)
    np.testing.assert_allclose(base_two, 2.0 * base_one, rtol=1e-12)
    np.testing.assert_allclose(two, 2.0 * one, rtol=1e-9, atol=1e-15)
    assert np.abs(one[: 2_000]).max() > 0.0


@pytest.mark.parametrize("kwargs, words", [
    ({"peak": 0.0}, "peak"),
    ({"peak": 1.0, "shaking": 0.0}, "shaking"),
    ({"peak": 1.0, "g": -1.0}, "g"),
])
def test_a_shake_test_outside_its_model_is_refused(kwargs, words):
    with pytest.raises(InputError, match=words):
        shake_test(0.9, 2_000, 0.005, 0, **kwargs)

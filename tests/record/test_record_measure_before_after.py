"""One-off check: the vectorised rockdec.record.record_measure against its loop version
(tests/record/record_measure_before.py) on records made here."""

import math

import numpy as np
import pytest

import record_measure_before as before
from rockdec.record import record_measure as rm
from rockdec.physics.loading import series_rng
from rockdec.physics.record_model import Load
from rockdec.physics.simulate import simulate_block

DT_WHITE, DT_CORNER_1, BURN_IN = 0.8043, 2.513, 4362


def _records():
    def sim(seed, n=200_000, pole=0.0, dt=DT_WHITE):
        return simulate_block([seed], n, dt=dt, g=1.0, e=0.9, sigma_p=1.0, burn_in=BURN_IN, pole=pole)[0][0]

    pole = Load("lowpass", 1.0).pole(75.0)
    white = sim(11)
    noisy = white + 0.03 * white.std() * series_rng(99).standard_normal(white.size)
    coloured = sim(13, pole=pole, dt=DT_CORNER_1)
    both = coloured + 0.02 * coloured.std() * series_rng(98).standard_normal(coloured.size)
    gappy = sim(15)
    gappy[np.arange(1000, gappy.size, 20_000)] = np.nan
    drifted = sim(16) + np.linspace(-0.3, 0.3, 200_000) * white.std()
    return {
        "white": (white, DT_WHITE), "noisy": (noisy, DT_WHITE), "coloured": (coloured, DT_CORNER_1), "both": (both, DT_CORNER_1),
        "gappy split": ([gappy[:80_000], gappy[80_000:]], DT_WHITE), "drifted": (drifted, DT_WHITE),
        "short": (sim(17, n=30_000), DT_WHITE),
    }


RECORDS = _records()


@pytest.mark.parametrize("name", list(RECORDS))
def test_vectorised_measure_agrees_with_the_loops(name):
    y, dt = RECORDS[name]
    old, new = before.measure(y, dt), rm.measure(y, dt)
    assert (new.kind, new.noisy, new.coloured, new.drifting, new.triples) == (old.kind, old.noisy, old.coloured, old.drifting, old.triples)
    assert new.sigma_y == pytest.approx(old.sigma_y, rel=1e-9)
    assert (new.drift_rms, new.drift_z) == pytest.approx((old.drift_rms, old.drift_z), rel=1e-12)
    worst = 0.0
    for field in ("g", "asymmetry", "impulse_var", "noise_var", "pole", "impulse_sd", "noise_sd", "noise_ratio", "corner_hz", "corner_ratio"):
        a, b = getattr(old, field), getattr(new, field)
        if math.isinf(a.value):
            assert b.value == a.value
            continue
        if math.isnan(a.se):  # a block left out gave no finite value
            assert math.isnan(b.se) and b.value == pytest.approx(a.value, rel=1e-6), (field, a, b)
            continue
        # the pole is searched to 1e-8 (golden section) where scipy's bounded Brent stopped at about 1e-7
        assert abs(b.value - a.value) <= 1e-3 * a.se, (field, a, b)
        assert b.se == pytest.approx(a.se, rel=1e-3), (field, a, b)
        worst = max(worst, abs(b.value - a.value) / a.se if a.se else 0.0)
    np.testing.assert_allclose(new.r, old.r, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(new.r_se, old.r_se, rtol=1e-4)
    print(name, "largest difference in standard errors:", worst)

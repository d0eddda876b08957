"""Records that are not free-rocking records are refused, and valid records that give no
``e`` are declined, each in one sentence that names the problem and the fix."""

import numpy as np
import pytest

from rockdec.free.analysis import analyse_free_rocking
from rockdec.physics.simulate import simulate_model
from rockdec.studies.free_coverage import free_record
from rockdec.timeaxis import RecordError
from rockdec.validate import InputError

THETA, DT, _ = free_record(0.9, noise=0.01, samples_per_cycle=50, seed=0)


def one_sentence(message: str) -> bool:
    return message.endswith(".") and ". " not in message


def refused(theta, dt=DT, **kw) -> str:
    with pytest.raises(RecordError) as err:
        analyse_free_rocking(theta, dt, **kw)
    assert one_sentence(str(err.value)), str(err.value)
    return str(err.value)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_nan_and_infinite_samples(bad):
    theta = THETA.copy()
    theta[77] = bad
    assert "sample 77" in refused(theta)


def test_too_short():
    assert "too short" in refused(THETA[:5])


def test_constant_record():
    assert "constant" in refused(np.full(500, 0.02))


def test_non_uniform_time_stamps():
    t = DT * np.arange(THETA.size)
    t[150:] += 0.5 * DT
    assert "not uniformly sampled" in refused(THETA, t)


def test_no_release():
    held = 0.02 + 1e-4 * np.random.default_rng(0).normal(size=800)  # tilted and held, never let go
    assert "no release found" in refused(held)


def test_random_response():
    theta = simulate_model("simplified", [1], 20000, dt=0.01, g=1.0, e=0.9, sigma_p=0.003)[0][0]
    assert "forced (random) response" in refused(theta, 0.01)


def test_never_comes_to_rest():
    assert "never comes to rest" in refused(THETA[:80])


def test_overturns_past_theta_cr():
    theta, dt, theta_cr = free_record(0.9, model="housner", samples_per_cycle=50)
    tipped = np.concatenate([theta[:200], np.linspace(0.0, 1.5 * theta_cr, 100)])
    assert "overturns" in refused(tipped, dt, model="housner", theta_cr=theta_cr)


def test_overturns_without_theta_cr():
    cut = int(np.flatnonzero(np.diff(np.sign(THETA)) != 0)[5]) + 1  # just after the 6th impact
    fall = np.sign(THETA[cut]) * np.linspace(0.0, 1.2, 150)
    assert "overturns" in refused(np.concatenate([THETA[:cut], fall, np.full(100, fall[-1])]))


def test_clipped_sensor():
    assert "clipped" in refused(np.clip(THETA, -0.012, 0.012))


def test_two_dimensional_array():
    assert "1-D" in refused(np.stack([THETA, THETA]))


def test_one_step_per_record():
    with pytest.raises(RecordError, match="one step"):
        analyse_free_rocking([THETA, THETA], [DT, DT, DT])


def test_too_few_impacts_is_declined_in_one_sentence():
    theta, dt, _ = free_record(0.5, samples_per_cycle=12)
    fit = analyse_free_rocking(theta, dt)
    assert np.isnan(fit.e) and np.isnan(fit.e_interval[0]) and one_sentence(fit.reason)
    assert "samples per cycle" in fit.reason and "min_arc_samples" in fit.stop_reason[0]


@pytest.mark.parametrize(
    "kw, words",
    [
        (dict(model="newton"), "not a rocking model"),
        (dict(model="housner"), "needs `theta_cr`"),
        (dict(theta_cr=-1.0), "theta_cr"),
        (dict(min_arc_samples=2), "min_arc_samples"),
        (dict(min_arc_samples=4.0), "min_arc_samples"),
    ],
)
def test_bad_parameters(kw, words):
    with pytest.raises(InputError, match=words):
        analyse_free_rocking(THETA, DT, **kw)


@pytest.mark.parametrize("dt", [0.0, -0.01, np.nan])
def test_bad_step(dt):
    with pytest.raises(InputError, match="dt"):
        analyse_free_rocking(THETA, dt)

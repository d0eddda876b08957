"""A record whose load is a transient (an earthquake or a shake-table test) is declined before any calibration.

The transients and their stationary twins come from ``tests/transient_reference.py``, a generator
apart from the project's simulator; the stationary records also from the project's simulator at
white and low-pass loads. The check (:mod:`rockdec.record.transient`) fires on every transient
and on no more stationary records than its tolerance allows.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from rockdec import estimation

from rockdec.physics.record_model import NO_NOISE
from rockdec.report.estimate_report import document
from rockdec.physics.simulate import simulate_block
from rockdec.record import transient
from rockdec.record.records import Record

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import transient_reference as reference  # noqa: E402
from conftest import calibrated_step  # noqa: E402
from test_hostile import hostile  # noqa: E402

#: Transients: (e, seed, seconds of shaking, sensor noise).
TRANSIENTS = [(e, seed, strong, noise) for e in (0.8, 0.9, 0.95) for seed, strong, noise in ((1, 16.0, 0.0), (2, 24.0, 0.03), (3, 31.0, 0.01))]


@pytest.fixture(scope="module")
def transients() -> dict:
    """The transient records of :data:`TRANSIENTS`, by case."""
    return {case: reference.transient(case[0], case[1], strong=case[2], noise=case[3]) for case in TRANSIENTS}


@pytest.mark.parametrize("case", TRANSIENTS, ids=lambda c: f"e{c[0]}-seed{c[1]}-{c[2]:g}s-noise{c[3]:g}")
def test_check_fires_on_transients(transients, case):
    found = transient.envelope(transients[case], 1.0 / reference.FS)
    assert found.transient and found.decades > transient.DECADES
    assert 0.0 < found.share <= 1.0 and found.seconds > 0.0


@hostile("wrong answers", "refused")
@pytest.mark.parametrize("case", TRANSIENTS[::2], ids=lambda c: f"e{c[0]}-seed{c[1]}-{c[2]:g}s-noise{c[3]:g}")
def test_transient_declined_before_any_calibration(transients, case, tmp_path):
    cache = tmp_path / "cache"
    cache.mkdir()
    doc = document(estimation.estimate([Record(transients[case], 1.0 / reference.FS, "quake")], cache_dir=cache))
    assert doc["e"] is None and doc["interval"] == [None, None]
    assert doc["reason"].startswith("the record's amplitude builds up and dies away (quake: its strongest")
    assert "the load is a transient, an earthquake or a shake-table test" in doc["reason"] and "`--test shake --base FILE`" in doc["reason"]
    assert "transient_load" in doc["warning_codes"]
    assert doc["calibration"]["file"] is None and list(cache.iterdir()) == []  # no calibration was built


@hostile("wrong answers", "refused")
def test_transient_declined_with_the_load_declared(transients, tmp_path):
    """A declared record model does not let a transient through: the load is not the one declared."""
    cache = tmp_path / "cache"
    cache.mkdir()
    doc = document(estimation.estimate([Record(transients[TRANSIENTS[0]], 1.0 / reference.FS, "quake")], cache_dir=cache,
                             load="white", sensor=NO_NOISE))
    assert doc["e"] is None and "the load is a transient" in doc["reason"] and list(cache.iterdir()) == []


def _project_records() -> list[np.ndarray]:
    """Stationary records of the project's simulator: e 0.6-0.98 at the step that gives e 0.8
    75 samples per cycle (so the samples per cycle vary with e), white and low-pass (corner at
    three rocking frequencies) loads, 20,000 samples, sensor noise 0 and 3 %."""
    rng = np.random.default_rng(7)
    g, sigma_p = 1.0, 0.003
    step = calibrated_step(0.8, g, sigma_p)
    out = []
    for e in (0.6, 0.8, 0.9, 0.98):
        for pole, seeds in ((0.0, [11, 12, 13]), (math.exp(-2.0 * math.pi * 3.0 / 75.0), [14, 15, 16])):
            theta, _ = simulate_block(seeds, 20_000, dt=step["dt"], g=g, e=e, sigma_p=sigma_p, pole=pole, burn_in=20_000)
            for k, row in enumerate(theta):
                out.append(row + (0.03 * (k % 2)) * row.std() * rng.standard_normal(row.size))
    return out


@pytest.mark.slow
def test_check_quiet_on_the_project_simulator():
    """24 stationary records of the project's simulator (:func:`_project_records`). Tolerance:
    at most one fires (a false-alarm rate of 1 % gives two or more of 24 with probability 2.4 %)."""
    records = _project_records()
    fired = sum(transient.envelope(r, 1.0).transient for r in records)
    assert len(records) == 24 and fired <= 1


def test_check_quiet_on_the_generator_stationary():
    """12 stationary records of the independent generator, e 0.6-0.98, sensor noise 0 and 3 %.
    Tolerance: at most one fires (a false-alarm rate of 1 % gives two or more of 12 with
    probability 0.6 %)."""
    records = [reference.stationary(e, seed, seconds=40.0, strength=1.0, noise=0.03 * (seed % 2))
               for e in (0.6, 0.8, 0.9, 0.95, 0.98, 0.9) for seed in (21, 22)]
    fired = sum(transient.envelope(r, 1.0 / reference.FS).transient for r in records)
    assert fired <= 1

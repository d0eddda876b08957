"""Records given together that are the same data in disguise (issue 38): offset, sign, scale,
rad against degrees, overlapping pieces, gaps and noise; independent records of one block
are never flagged, and a pair of 200,000 samples takes well under a second or two."""

from __future__ import annotations

import itertools
import time

import numpy as np
import pytest

from rockdec.physics import simulate
from rockdec.record import sameness
from rockdec.record.records import Record

from conftest import calibrated_step

hostile = pytest.mark.hostile


@pytest.fixture(scope="module")
def block():
    """Twelve independent records of one block (e = 0.85, 20,000 samples each)."""
    cal = calibrated_step(0.85, 1.0, 0.003)
    theta, _ = simulate.simulate_block(np.arange(40, 52), 20_000, dt=cal["dt"], g=1.0, e=0.85, sigma_p=0.003, burn_in=cal["burn_in"])
    return theta


def _gaps(x, rng, fraction=0.05):
    x = x.copy()
    x[rng.choice(x.size, int(fraction * x.size), replace=False)] = np.nan
    return x


DISGUISES = {
    "offset 1e-4 rad": (lambda a, rng: (a, a + 1e-4), ["shifted by +0.0001", "over 20000 shared samples"]),
    "negated": (lambda a, rng: (a, -a), ["negated"]),
    "scaled": (lambda a, rng: (a, 3.7 * a), ["scaled by 3.7"]),
    "rad and degrees": (lambda a, rng: (a, np.degrees(a)), ["in degrees where the other is in rad"]),
    "degrees and rad": (lambda a, rng: (np.degrees(a), a), ["in rad where the other is in degrees"]),
    "halves overlapping by half": (lambda a, rng: (a[:13_333], a[6_667:]), ["over 6666 shared samples", "from sample 6667"]),
    "second half first": (lambda a, rng: (a[6_667:], a[:13_333]), ["from sample 6667 of record 1"]),
    "piece, negated, in degrees, shifted": (lambda a, rng: (a, 0.3 - np.degrees(a[5_000:9_000])),
                                            ["negated", "in degrees", "shifted by +0.3", "over 4000 shared samples"]),
    "printed to 4 digits": (lambda a, rng: (a, np.array([float(f"{v:.4g}") for v in a])), ["(a copy, over"]),
    "float32": (lambda a, rng: (a, a.astype(np.float32).astype(np.float64)), ["correlation 1"]),
    "copy with gaps": (lambda a, rng: (a, _gaps(a, rng)), ["over 19000 shared samples"]),
    "both with gaps": (lambda a, rng: (_gaps(a, rng), -_gaps(a, rng)), ["negated"]),
    "copy with 5 % noise": (lambda a, rng: (a, a + 0.05 * np.std(a) * rng.standard_normal(a.size)), ["correlation 0.99"]),
}


@hostile("wrong answers", "refused")
@pytest.mark.parametrize("make, words", DISGUISES.values(), ids=DISGUISES.keys())
def test_the_same_data_in_disguise_is_named_in_one_sentence(block, make, words):
    rng = np.random.default_rng(1)
    a, b = make(block[0], rng)
    reason = sameness.same_data([block[3], a, block[5], b], ["other", "record 0", "third", "record 1"])
    assert reason is not None and reason.startswith("record 1 holds the same data as record 0"), reason
    assert "\n" not in reason and reason.endswith("for nothing).") and reason.count(". ") == 0
    for word in words:
        assert word in reason, (word, reason)


@hostile("wrong answers", "answered")
def test_independent_records_of_one_block_are_not_flagged(block):
    assert sameness.same_data(list(block)) is None
    size = 2**16
    spectra = [sameness._prepared(x, size)[0] for x in block]
    worst = max(sameness._best(spectra[i], spectra[j], size, 20_000, 20_000, sameness.MIN_OVERLAP)[0]
                for i, j in itertools.combinations(range(len(block)), 2))
    assert worst < 0.9 * sameness.SAME_CORRELATION  # a margin below the threshold


def test_the_best_correlation_is_pearsons_over_the_shared_samples_at_the_best_lag(block):
    """Against a brute force over every lag (:func:`numpy.corrcoef` on each overlap): the same
    largest ``|r|``, at the same lag, with the same overlap."""
    a = block[0][:1500]
    b = np.degrees(block[0][400:1600]) + 0.3 * np.degrees(block[1][:1200])  # related, not a copy: |r| < 1
    size, least = 4096, 200
    best, r, lag, overlap, _, _ = sameness._best(sameness._prepared(a, size)[0], sameness._prepared(b, size)[0], size, a.size, b.size, least)
    brute = {}
    for k in range(-(b.size - least), a.size - least + 1):
        x, y = (a[k:], b) if k >= 0 else (a, b[-k:])
        m = min(x.size, y.size)
        brute[k] = (np.corrcoef(x[:m], y[:m])[0, 1], m)
    k_best = max(brute, key=lambda k: abs(brute[k][0]))
    assert lag == k_best == 400 and overlap == brute[k_best][1] == 1100
    assert r == pytest.approx(brute[k_best][0], abs=1e-9) and 0.5 < best < sameness.SAME_CORRELATION


@hostile("wrong answers", "answered")
def test_records_shorter_than_the_overlap_and_single_records_are_not_compared(block):
    assert sameness.same_data([block[0][:500], block[0][:500]]) is None
    assert sameness.same_data([block[0]]) is None
    named = [Record(block[0], 0.01, "a.csv"), Record(-block[0], 0.01, "b.csv")]
    assert sameness.same_data(named).startswith("b.csv holds the same data as a.csv (negated")


@hostile("sizes", "answered")
def test_a_pair_of_200000_samples_takes_well_under_two_seconds(block):
    long = np.concatenate(list(block[:10]))  # 200,000 samples
    other = np.concatenate(list(block[2:12]))[::-1].copy()
    start = time.perf_counter()
    assert sameness.same_data([long, other]) is None
    assert sameness.same_data([long, long[50_000:] * -1.0]) is not None
    assert time.perf_counter() - start < 4.0  # two pairs

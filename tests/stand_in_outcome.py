"""A stand-in for one estimate's typed outcome (:class:`rockdec.estimation.Outcome`): an
estimator reported at a given ``e`` with a narrow interval, and the verdict the
repair-and-retry reads; no records, no calibration. For tests of the retry's decisions."""

from __future__ import annotations

from types import SimpleNamespace

from rockdec import estimation


def stand_in(verdict: estimation.Verdict, e: float = 0.9, estimator: str = "e_0", points_per_cycle: float = 75.0) -> estimation.Outcome:
    """An outcome reporting ``estimator`` at ``e`` +- 0.02 (coverage 0.95), with ``verdict``
    and an analysis that reads ``points_per_cycle`` samples per cycle."""
    reading = estimation.Reading(e, e, None, (0.5, 0.99), e - 0.02, e + 0.02, 0.95, 100, ())
    analysed = SimpleNamespace(analysis=SimpleNamespace(points_per_cycle=points_per_cycle))
    return estimation.Outcome(analysed, None, None, {estimator: reading}, estimation.Selection(estimator, (), None),
                              estimation.uncalibrated_g(None), (), {},
                              estimation.Repaired(None, True), verdict)

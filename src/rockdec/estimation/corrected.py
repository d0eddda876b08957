"""Stage 4 of the estimate: every estimator's raw value corrected for its bias, with its 95 %
interval and calibrated coverage (:class:`Reading`), by inverting its belt.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from rockdec.calibrate import belt
from rockdec.estimation.analysed import Analysed
from rockdec.estimation.calibrated import Calibrated
from rockdec.rdd import registry

__all__ = ["Reading", "beyond", "correct", "gains_speed", "uncalibrated"]


class Reading(NamedTuple):
    """One estimator corrected (:func:`correct`): its ``raw`` value, its corrected ``e``
    (NaN when it gives none; ``beyond``: why, :func:`beyond`), the ``calibrated_range``
    of ``e`` (``(first, last)``, ``None`` for an empty belt), its 95 % interval ``low`` to
    ``high``, its calibrated ``coverage``
    (:func:`rockdec.calibrate.belt.calibration_coverage`), the ``triggers`` it was read
    from and its ``notes`` (sentences of :func:`rockdec.calibrate.belt.correct`)."""

    raw: float
    e: float
    beyond: str | None
    calibrated_range: tuple | None
    low: float
    high: float
    coverage: float
    triggers: int
    notes: tuple

    @property
    def has_value(self) -> bool:
        """Whether the estimator gives a corrected ``e``."""
        return math.isfinite(self.e)


def correct(analysed: Analysed, calibrated: Calibrated) -> dict[str, Reading]:
    """Every estimator's raw value corrected for its bias and its 95 % interval, by
    inverting its belt (:func:`rockdec.calibrate.belt.correct`), with its calibrated
    coverage; a raw value beyond the belt's mean curve gives no value (:func:`beyond`).
    Returns ``{estimator: Reading}``."""
    analysis, belts = analysed.analysis, calibrated.belts
    per = {}
    for name in registry.ESTIMATORS:
        c = belt.correct(belts[name], analysis.raw[name])
        side = beyond(belts[name], analysis.raw[name], c)
        per[name] = Reading(
            float(analysis.raw[name]), math.nan if side else float(c.value), side,
            (float(belts[name].e[0]), float(belts[name].e[-1])) if belts[name].e.size else None,
            float(c.low), float(c.high), float(belt.calibration_coverage(calibrated.cal, name, calibrated.simulated_belts[name])),
            int(analysis.count[registry.trigger(name)][-1]),
            tuple(note for note in c.notes if not (side and "nearest point" in note)),  # no value is shown
        )
    return per


def uncalibrated(analysed: Analysed) -> dict[str, Reading]:
    """The :class:`Reading` of every estimator of records declined before any calibration:
    its raw value, no corrected value or interval."""
    analysis = analysed.analysis
    return {name: Reading(float(analysis.raw[name]), math.nan, None, None, math.nan, math.nan, math.nan,
                          int(analysis.count[registry.trigger(name)][-1]), ())
            for name in registry.ESTIMATORS}


def beyond(b: belt.Belt, raw: float, c: belt.Corrected) -> str | None:
    """Why the corrected value ``c`` of the raw value ``raw`` is no estimate, or ``None``.

    When ``raw`` lies outside every value the belt's mean curve takes, :func:`belt.correct`
    returns the nearest point of the curve, which estimates nothing: ``"below"`` or
    ``"above"`` when that point is an end of the calibrated range of ``e`` (which then
    bounds ``e``), ``"unreached"`` when it is inside the range.
    """
    if b.e.size == 0 or not (np.isfinite(raw) and np.isfinite(c.value)) or b.mean.min() <= raw <= b.mean.max():
        return None
    if c.value == b.e[0]:
        return "below"
    return "above" if c.value == b.e[-1] else "unreached"


def gains_speed(analysed: Analysed, calibrated: Calibrated) -> str | None:
    """Why the records cannot be a rocking block's, when their impacts gain speed: ``e_v``
    (the slope of ``D_v`` after the impact over the slope before, eq. 6) read above 1 by more
    than the upper end of its belt's 95 % band at the top of the calibrated range, which
    no block that loses energy at impacts gives (a record that runs backwards in time, or a
    system that is not a rocking block); else ``None``."""
    b = calibrated.belts["e_v"]
    raw = analysed.analysis.raw["e_v"]
    if b.e.size == 0 or not np.isfinite(raw):
        return None
    top = float(b.mean[-1] + np.max(np.atleast_1d(b.q_high)) * b.spread[-1])
    if not (raw > 1.0 and raw > top):
        return None
    return (
        f"the impacts of these records gain speed (e_v reads {raw:.3f}, above the {top:.3f} that a block losing energy at "
        "impacts gives at most): the record runs backwards in time, or the system is not a rocking block; e is not estimated"
    )

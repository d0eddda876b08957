"""Stage 7 of the estimate: the block's ``g`` corrected at the reported ``e`` with its 95 %
interval (or as given, checked against the records' own), and the note on records far
longer than the calibration's.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from rockdec.calibrate import belt
from rockdec.estimation.analysed import G_FACTOR, Analysed
from rockdec.estimation.calibrated import Calibrated
from rockdec.estimation.model_choice import ModelChoice
from rockdec.estimation.notes import Note
from rockdec.rdd import measured
from rockdec.rdd.registry import DEFAULT_ESTIMATOR

__all__ = ["GReading", "LONG_RATIO", "g_note", "long_record_note", "read_g", "uncalibrated_g"]

#: Records more than this many times as long as the calibration's simulated records are warned
#: that their interval's coverage was not measured at their length (evidence:
#: docs/explanation/constants.md, from ``benchmarks/long_coverage.py``).
LONG_RATIO = 20.0


class GReading(NamedTuple):
    """``g`` as the estimate gives it (:func:`read_g`): its value (rad/s^2, as given or
    corrected; NaN when none), its 95 % interval ``(low, high)`` and the interval's
    calibrated coverage (``None`` and NaN when there is none), the note on how it was found
    (:func:`g_note`), and :class:`~rockdec.estimation.notes.Note` s on a given ``g``."""

    value: float
    interval: tuple | None
    coverage: float
    note: str
    notes: tuple


def read_g(analysed: Analysed, choice: ModelChoice, calibrated: Calibrated, chosen: str | None, e_chosen: float) -> GReading:
    """``g`` corrected at the reported ``e`` with its 95 %
    interval (:func:`rockdec.calibrate.belt.g_interval`), or as given, checked against the
    records' own."""
    g, own, analysis = analysed.g, analysed.own, analysed.analysis
    g_belt = calibrated.simulated_belts[measured.G_NAME]
    e_name = chosen or DEFAULT_ESTIMATOR  # the estimator whose corrected e corrects g
    e_belt = calibrated.simulated_belts[e_name]
    g_band = belt.g_band(calibrated.cal, e_name, e_belt, g_belt)
    value = g if g is not None else belt.correct_g(g_belt, analysis.raw[measured.G_NAME], e_chosen)
    no_interval = g is not None or chosen is None
    low, high = (math.nan, math.nan) if no_interval else belt.g_interval(g_band, e_belt, g_belt, analysis.raw[e_name], analysis.raw[measured.G_NAME])
    notes = []
    if g is not None and own is not None:
        own_low, own_high = belt.g_interval(g_band, e_belt, g_belt, own.raw[e_name], own.raw[measured.G_NAME])
        if np.isfinite(own_low) and not own_low <= g <= own_high:
            notes.append(Note("g_outside", (
                f"the given `g` {g:g} lies outside the records' own g, {own_low:.4g}-{own_high:.4g} rad/s^2 (calibrated 95 % "
                "interval): the estimate rests on the given g"
            )))
        elif not np.isfinite(own_low):
            notes.append(Note("g_unchecked", (
                f"the given `g` {g:g} was checked against the records' own g only to within a factor {G_FACTOR:g} "
                f"({own.raw[measured.G_NAME]:.4g} rad/s^2 read off them, not corrected): this calibration gives their g no "
                "interval; the estimate rests on the given g"
            )))
    return GReading(
        float(value),
        None if g is not None or not np.isfinite(low) else (float(low), float(high)),
        math.nan if no_interval else float(belt.g_calibration_coverage(calibrated.cal, e_name, e_belt, g_belt, g_band)),
        g_note(g is not None, bool(np.isfinite(low)), chosen is not None, calibrated.scale, sum(choice.cal_settings["lengths"])),
        tuple(notes),
    )


def uncalibrated_g(g: float | None) -> GReading:
    """``g`` of records declined before any calibration: as given (NaN when not), no interval."""
    return GReading(math.nan if g is None else float(g), None, math.nan, g_note(g is not None, False, False, 1.0, 0), ())


def g_note(given: bool, has_interval: bool, has_e: bool, scale: float, simulated: int) -> str:
    """How the report's ``g`` was found (the JSON's ``g_interval_note``)."""
    if given:
        return "as given"
    if has_interval:
        return (
            "95 % interval: the corrected g over the scatter of the corrected g about the true g on the calibration's "
            "simulated records (the error of the corrected e included)"
            + (f", as long as those records ({simulated} samples): wider than the records' own" if scale != 1.0 else "")
        )
    if not has_e:
        return "no interval: no e was estimated, and g is corrected at the corrected e"
    return "no interval: g's interval needs a corrected e whose interval lies inside the calibrated range"


def long_record_note(analysed: Analysed, choice: ModelChoice) -> tuple:
    """A :class:`~rockdec.estimation.notes.Note` when the records are more than :data:`LONG_RATIO` times as long as
    the calibration's simulated records (an empty tuple otherwise)."""
    simulated = sum(choice.cal_settings["lengths"])
    if analysed.samples <= LONG_RATIO * simulated:
        return ()
    return (Note("long_record", (
        f"{analysed.samples} samples are {analysed.samples / simulated:.0f} times the calibration's simulated records, beyond the "
        f"{LONG_RATIO:.0f} times at which the interval's coverage was measured: the narrower the interval, the more "
        "the calibration's own error of the bias counts"
    )),)

"""Stage 3 of the estimate: the calibration of the records, read from the cache or built and
stored (:func:`rockdec.calibrate.calibration.load_or_build`), and its belts.
"""

from __future__ import annotations

import logging
import time
from typing import NamedTuple

from rockdec import console
from rockdec.calibrate import belt, calibration
from rockdec.estimation.analysed import Analysed
from rockdec.estimation.cost_model import stage_seconds
from rockdec.estimation.model_choice import ModelChoice
from rockdec.estimation.notes import Note

__all__ = ["Calibrated", "CalibrationNeeded", "get_calibration"]

log = logging.getLogger(__name__)


class CalibrationNeeded(Exception):
    """The estimate asks for a calibration outside those it may read (``available`` of
    :func:`rockdec.estimation.estimate`); ``settings`` are that calibration's. What a planner catches to learn
    which calibrations an estimate reads, its repair's decisions included, before any is built
    (:func:`rockdec.pipeline.campaign.plan`)."""

    def __init__(self, settings: dict):
        super().__init__(f"calibration-{calibration.settings_hash(settings)}.nc")
        self.settings = settings


class Calibrated(NamedTuple):
    """The calibration of the records (stage 3 of :func:`rockdec.estimation.estimate`): ``cal`` (the stored
    simulated sets), whether it came from the cache, the seconds it took, the factor on
    its spread (:func:`rockdec.calibrate.calibration.spread_scale`), ``belts`` at the
    records' length and ``simulated_belts`` at the simulated one, ``notes`` (:class:`~rockdec.estimation.notes.Note`)."""

    cal: object
    cached: bool
    seconds: float
    scale: float
    belts: dict
    simulated_belts: dict
    notes: tuple

    @property
    def n_sets(self) -> int:
        """Simulated record sets in the calibration."""
        return int(self.cal["raw"].sizes["e_true"] * self.cal["raw"].sizes["set"])


def get_calibration(analysed: Analysed, choice: ModelChoice, cache_dir, available=None) -> Calibrated:
    """Get the calibration of ``choice`` from ``cache_dir``
    or build and store it (:func:`rockdec.calibrate.calibration.load_or_build`), and its
    belts. ``available``: the settings hashes of the calibrations it may read (``None``: any);
    one outside them raises :class:`CalibrationNeeded`, before the cache is read."""
    cal_settings = choice.cal_settings
    if available is not None and calibration.settings_hash(cal_settings) not in available:
        raise CalibrationNeeded(cal_settings)
    scale = calibration.spread_scale(cal_settings, analysed.samples)
    simulated = sum(cal_settings["lengths"])
    shortened = (
        f"; the records' {analysed.samples} samples are calibrated on simulated records of {simulated} samples, "
        f"the spread scaled by sqrt({simulated} / {analysed.samples}) = {scale:.3g}" if scale != 1.0 else ""
    )
    stages = stage_seconds(analysed.samples, False, analysed.g is not None, records=len(analysed.records),
                           length_grid="length_grid" in cal_settings)
    log.info(
        f"calibration {calibration.settings_hash(cal_settings)}: {console.about(stages['calibrating'])} to build when it is not stored"
        f"{shortened}"
    )
    started = time.perf_counter()
    messages: list[str] = []
    cal, cached = calibration.load_or_build(cal_settings, cache_dir, messages)
    seconds = time.perf_counter() - started
    belts = belt.belts(cal, scale)  # e's belts at the records' length
    simulated_belts = belts if scale == 1.0 else belt.belts(cal)  # at the simulated length: coverage on the sets, g's interval
    return Calibrated(cal, cached, seconds, scale, belts, simulated_belts, tuple(Note("calibration", m) for m in messages))

"""From measured records to a calibrated ``e``, in typed stages: what ``rockdec estimate``
computes.

:func:`estimate` (:mod:`~rockdec.estimation.retry`) repairs the records and runs
:func:`~rockdec.estimation.stages.estimate_once`, whose stages each take and give typed
values: :mod:`~rockdec.estimation.analysed` (the records checked and analysed) →
:mod:`~rockdec.estimation.model_choice` (the record model the calibration simulates) →
:mod:`~rockdec.estimation.calibrated` (the calibration and its belts) →
:mod:`~rockdec.estimation.corrected` (every estimator corrected, with its interval) →
:mod:`~rockdec.estimation.selected` (the reported estimator) →
:mod:`~rockdec.estimation.pooled` (records given together agree on one ``e``) →
:mod:`~rockdec.estimation.g_read` (the block's ``g``) →
:mod:`~rockdec.estimation.diagnosed` (the checks of the records). The result is an
:class:`~rockdec.estimation.stages.Outcome`; its report is made once, at the end, by
:mod:`rockdec.report.estimate_report`. :mod:`~rockdec.estimation.cost_model` says what an
estimate costs before it runs.

The package re-exports the ``__all__`` of its modules, each imported on first use.

Explanation: docs/explanation/estimate.md, docs/explanation/method/measured-record.md.
"""

from rockdec.lazy import lazy_names

#: The names each module of the package exports (its ``__all__``), by the module that defines them.
_MODULES = {
    "analysed": ("Analysed", "G_FACTOR", "SPIKE_SIGMAS", "analyse", "own_scales", "refuse_held", "transient_decline"),
    "calibrated": ("Calibrated", "CalibrationNeeded", "get_calibration"),
    "corrected": ("Reading", "beyond", "correct", "gains_speed", "uncalibrated"),
    "cost_model": ("ANALYSIS_SECONDS", "BYTES_PER_SAMPLE", "CALIBRATION_SECONDS", "CSV_SECONDS", "PAIR_SECONDS", "RECORD_SECONDS", "calibration_sets", "cost", "stage_seconds"),
    "diagnosed": ("checks_place", "diagnose", "unresolved_impacts"),
    "g_read": ("GReading", "LONG_RATIO", "g_note", "long_record_note", "read_g", "uncalibrated_g"),
    "model_choice": ("BASE_NYQUIST_TOLERANCE", "BASE_SOURCE", "COLOUR_CORNER_FLOOR", "COLOUR_CORNER_Z", "DECLARED_FACTOR", "DECLARED_Z", "ModelChoice", "SIDE_G_SHARE", "base_short", "choose_model", "colour_decline", "declared_contradictions", "filter_decline", "measure_model", "record_model"),
    "notes": ("NOTE_CODES", "Note"),
    "pooled": ("Pooled", "check_pooled"),
    "retry": ("DECLINING_CHECKS", "REPAIRING_CHECKS", "blunted_cause", "decline_unrepaired", "declining_fired", "estimate"),
    "selected": ("Candidate", "Selection", "coverage_floor", "declined_rows", "select"),
    "stages": ("Outcome", "Repaired", "Verdict", "estimate_once"),
}

#: Where each exported name lives.
_HOMES = {name: f"{__name__}.{module}" for module, names in _MODULES.items() for name in names}

__all__ = sorted(_HOMES)

__getattr__, __dir__ = lazy_names(__name__, _HOMES)

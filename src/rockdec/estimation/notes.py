"""The warnings an estimate gives: :class:`Note` (a stable code and its sentence) and
the codes of those that no check of :mod:`rockdec.record.diagnostics` names.
"""

from __future__ import annotations

from typing import NamedTuple

__all__ = ["NOTE_CODES", "Note"]


class Note(NamedTuple):
    """A warning of :func:`rockdec.estimation.estimate`: a stable ``code`` (the name of a check of
    :mod:`rockdec.record.diagnostics`, or one of :data:`NOTE_CODES`) and its sentence."""

    code: str
    message: str

#: Codes of the warnings :func:`rockdec.estimation.estimate` gives besides the checks of
#: :mod:`rockdec.record.diagnostics`, with what each says.
NOTE_CODES = {
    "g_unreadable": "g cannot be read off the records, so a given g is not checked against them",
    "g_outside": "a given g lies outside the calibrated interval of the records' own g",
    "g_unchecked": "a given g is checked against the records' own only to within a factor",
    "long_record": "the records are far longer than the calibration's, beyond the lengths whose coverage was measured",
    "calibration": "the stored calibration was rebuilt, or a stopped run's lock was taken over",
    "pooled_disagree": "records given together disagree on one e; e is declined",
    "pooled_unchecked": "a record given with others could not be analysed alone, so it was not checked against them",
    "noise_contradicted": "the declared sensor noise is not what the records show, beyond the measurement's error",
    "load_contradicted": "the declared load is not what the records show, beyond the measurement's error",
    "base_short": "a declared base record's spectrum stops below the rocking record's Nyquist frequency",
    "filtered_unchecked": "a record is quantised too coarsely for the check filtered to read its impacts; it was not checked",
    "transient_load": "a record's amplitude builds up and dies away: its load is a transient, not a stationary random load; e is declined",
}

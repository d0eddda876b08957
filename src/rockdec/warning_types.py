"""The warnings rockdec raises, each a class a user can filter (all importable from ``rockdec``).

The estimate's own warnings are not Python warnings: they are sentences with codes in its
report (:class:`rockdec.EstimateWarning`, docs/explanation/method/warnings.md).
"""

__all__ = ["ModelValidityWarning", "NoTriggerWarning", "SimulationWarning"]


class SimulationWarning(UserWarning):
    """A simulation that did not make what was asked: series that overturned, or a sampling
    off the requested samples per cycle (:func:`rockdec.physics.run.simulation_report`)."""


class ModelValidityWarning(RuntimeWarning):
    """The simplified model (eq. 4) was asked for where its period departs from Housner's
    (eq. 3) beyond the tolerance (:func:`rockdec.physics.run.model_for`)."""


class NoTriggerWarning(RuntimeWarning):
    """A window caught no trigger, so its signature is NaN."""

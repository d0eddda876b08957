"""rockdec: the coefficient of restitution of a rocking block, by the Random Decrement technique.

A rocking rigid block loses a share of its angular velocity at every impact; the share it
keeps is its coefficient of restitution ``e``. rockdec estimates ``e`` from the block's
random response alone: the record's Random Decrement signatures give raw estimates, and
records simulated at known ``e`` with the record's own length, sampling and model correct
their bias and give a 95 % interval whose coverage is measured.

The functions a user calls:

- :func:`estimate` -- ``e`` of a record (array, DataArray, Series, or several of one
  block), as a :class:`RestitutionEstimate` (``.e``, ``.confidence_interval``,
  ``.summary()``, ``.to_dict()``, ``.to_dataset()``, ``.plot()``);
- :func:`free_rocking` -- ``e`` from a free-rocking test (the block released from a tilt),
  the reference beside the random test, as the same result object;
- :func:`shake_table` -- ``e`` from a shake-table test (a recorded base motion, then the
  block rocking to rest): the free-decay tails after the shaking, pooled;
- :func:`read_record` -- read a record from CSV, ``.npy``, NetCDF or MATLAB ``.mat``;
- :func:`simulate` -- a record of known ``e``, simulated exactly;
- :class:`InputError`, :class:`RecordError` -- what is refused, in one sentence naming the
  parameter and the fix;
- :class:`SimulationWarning`, :class:`ModelValidityWarning`, :class:`NoTriggerWarning` -- the
  Python warnings rockdec raises.

Example::

    import rockdec
    theta = rockdec.simulate(0.85, 20_000, seed=1)     # a record of known e
    res = rockdec.estimate(theta)                      # calibrated on first use (seconds)
    print(res.summary())
    res.plot()

The command line (``rockdec estimate FILE``) is the same call.
"""

from rockdec._version import __version__
from rockdec.lazy import lazy_names

__all__ = [
    "ConfidenceInterval",
    "EstimateWarning",
    "InputError",
    "ModelValidityWarning",
    "NoTriggerWarning",
    "RecordError",
    "RestitutionEstimate",
    "SimulationWarning",
    "__version__",
    "estimate",
    "free_rocking",
    "read_record",
    "shake_table",
    "simulate",
]

#: Where each public name lives (imported on first use, so ``import rockdec`` stays fast).
_HOMES = {
    "estimate": "rockdec.api",
    "free_rocking": "rockdec.api",
    "read_record": "rockdec.api",
    "shake_table": "rockdec.api",
    "simulate": "rockdec.api",
    "RestitutionEstimate": "rockdec.report.result",
    "ConfidenceInterval": "rockdec.report.result",
    "EstimateWarning": "rockdec.report.result",
    "InputError": "rockdec.validate",
    "RecordError": "rockdec.timeaxis",
    "SimulationWarning": "rockdec.warning_types",
    "ModelValidityWarning": "rockdec.warning_types",
    "NoTriggerWarning": "rockdec.warning_types",
}

__getattr__, __dir__ = lazy_names(__name__, _HOMES)

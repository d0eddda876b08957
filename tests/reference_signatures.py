"""The signature sums one window at a time: the reference for the one-pass binning of
:mod:`rockdec.rdd.signatures` (``tests/rdd/test_signatures.py``) and for its timing
(``benchmarks/bench_signatures.py``)."""

from __future__ import annotations

import numpy as np

from rockdec.rdd.signatures import SignatureSums, _run


def reference_per_window(y, trigger, target, half_widths, n_lag, *, dt=1.0, both_signs=True) -> SignatureSums:
    """Reference implementation: one full rescan of the record per window.

    Calls the kernel once for each half-width alone (no binning, no cumulative sum) and
    stacks the results; same conventions as :func:`rockdec.rdd.signatures.extremum_sums`
    (``trigger="a"``) and :func:`rockdec.rdd.signatures.crossing_sums` (``trigger="v"``), slower
    by about the number of windows.
    """
    parts = [_run(trigger, y, target, [width], n_lag, dt, both_signs, None, None) for width in np.atleast_1d(half_widths)]
    return SignatureSums(
        np.concatenate([part.sum for part in parts], axis=-2),
        np.concatenate([part.count for part in parts], axis=-1),
        np.concatenate([part.skipped for part in parts], axis=-1),
    )

"""Whether a record's load is a transient (an earthquake or a shake-table test), read off its envelope.

The random test assumes a stationary random load: the block's response keeps one strength
over the record. The response to an earthquake or a shake-table test builds up, holds and dies
away, and the block rocks down to rest after the base stops. :func:`envelope` splits each record
into :data:`BLOCKS` blocks of equal length and compares the variance of the strongest with that
of the stronger of its two end blocks (:attr:`Envelope.decades`, in decades): a record that
builds up from rest and rocks down to rest begins and ends with blocks whose variance is little
more than the sensor's, decades below its strong phase, while a stationary record's end blocks
are as strong as any other block, give or take its random bursts. Above :data:`DECADES` the record's
load is a transient and ``e`` is declined before any calibration
(:func:`rockdec.calibrate.inference.transient_decline`). Evidence:
``tests/calibrate/test_transient_load.py`` (its false alarms on stationary records of the
project's simulator and of an independent generator, its detections on transients).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = ["BLOCKS", "DECADES", "Envelope", "STRETCH", "envelope"]

#: Blocks of equal length each record is split into.
BLOCKS = 16

#: A record whose strongest block's variance is more than this many decades above both its end
#: blocks' is a transient (evidence: the module docstring).
DECADES = 3.0

#: The strongest stretch the reason names: this many consecutive blocks.
STRETCH = 4


class Envelope(NamedTuple):
    """A record's envelope: ``decades`` between its strongest block's variance and the larger of
    its first and last blocks' (``inf`` when neither moves), the ``seconds`` of its strongest stretch of
    :data:`STRETCH` blocks and the ``share`` of the record's energy (sum of squares about each
    block's mean) it holds; ``transient``: ``decades`` above :data:`DECADES`."""

    decades: float
    seconds: float
    share: float

    @property
    def transient(self) -> bool:
        """Whether the record's load is a transient."""
        return self.decades > DECADES


def envelope(theta: np.ndarray, dt: float) -> Envelope | None:
    """The :class:`Envelope` of the record ``theta`` sampled at ``dt`` s (NaN samples left out);
    ``None`` when a block holds fewer than two finite samples or the record does not move."""
    blocks = np.array_split(np.asarray(theta, dtype=float), BLOCKS)
    finite = np.array([np.count_nonzero(np.isfinite(b)) for b in blocks])
    if finite.min() < 2:
        return None
    var = np.array([np.nanvar(b) for b in blocks])
    if not var.max() > 0.0:
        return None
    energy = var * finite
    stretch = np.convolve(energy, np.ones(STRETCH), mode="valid")
    strongest = int(np.argmax(stretch))
    seconds = sum(b.size for b in blocks[strongest:strongest + STRETCH]) * dt
    ends = max(var[0], var[-1])
    decades = float(np.log10(var.max() / ends)) if ends > 0.0 else float("inf")
    return Envelope(decades, float(seconds), float(stretch[strongest] / energy.sum()))

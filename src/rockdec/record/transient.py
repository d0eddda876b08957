"""Whether a record's load is a transient (an earthquake or a shake-table test), read off its envelope.

The random test assumes a stationary random load: the block's response keeps one strength
over the record. The response to an earthquake or a shake-table test builds up, holds and dies
away, and the block rocks down to rest after the base stops. :func:`envelope` splits each record
into :data:`BLOCKS` blocks of equal length and compares the variance of the strongest with that
of the stronger of its two end blocks, their white sensor noise taken out (:attr:`Envelope.decades`,
in decades): a record that builds up from rest and rocks down to rest begins and ends with blocks
that hold little but the sensor's noise, while a stationary record's end blocks rock as strongly
as any other block, give or take its random bursts. Above :data:`DECADES` the record's
load is a transient and ``e`` is declined before any calibration
(:func:`rockdec.estimation.transient_decline`). Evidence:
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
#: blocks' (their white noise taken out) is a transient (evidence: the module docstring).
DECADES = 4.0

#: The strongest stretch the reason names: this many consecutive blocks.
STRETCH = 4


class Envelope(NamedTuple):
    """A record's envelope: ``decades`` between its strongest block's variance and the larger of
    its first and last blocks', their white noise taken out (``inf`` when neither rocks), the ``seconds`` of its strongest stretch of
    :data:`STRETCH` blocks and the ``share`` of the record's energy (sum of squares about each
    block's mean) it holds; ``transient``: ``decades`` above :data:`DECADES`."""

    decades: float
    seconds: float
    share: float

    @property
    def transient(self) -> bool:
        """Whether the record's load is a transient."""
        return self.decades > DECADES


def _rocking_variance(block: np.ndarray) -> float:
    """The variance of ``block`` less its white sensor noise's, read off the first differences
    (white noise's differences have twice its variance; a smooth rocking record's far less)."""
    return float(np.nanvar(block) - 0.5 * np.nanvar(np.diff(block)))


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
    ends = max(_rocking_variance(blocks[0]), _rocking_variance(blocks[-1]))
    decades = float(np.log10(var.max() / ends)) if ends > 0.0 else float("inf")
    return Envelope(decades, float(seconds), float(stretch[strongest] / energy.sum()))

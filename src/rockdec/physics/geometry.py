"""A rectangular block's geometry: its critical angle and Housner's coefficient of restitution.

A block of height ``H`` and width ``B`` on a rigid base tips over at ``alpha = atan(B/H)``
(the Housner model's ``theta_cr``, eq. 2) and, by conservation of angular momentum about the
new corner at an impact, keeps ``e = 1 - 1.5 sin^2(alpha)`` of its angular velocity
(Housner 1963): the prediction a measured ``e`` is set against. Explanation:
docs/explanation/method/models.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from rockdec.validate import InputError, show

__all__ = ["Block", "parse_block"]


@dataclass(frozen=True)
class Block:
    """A rectangular block of ``height`` and ``width`` (one unit, any).

    Examples
    --------
    >>> b = Block(0.6, 0.2)
    >>> round(b.theta_cr, 6), round(b.housner_e, 6)
    (0.321751, 0.85)
    """

    height: float
    width: float

    def __post_init__(self):
        for name in ("height", "width"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float) or not (math.isfinite(value) and value > 0.0):
                raise InputError(f"the block's {name} {show(value)} is not a length > 0; give the height and width in one unit, as H,B.")

    @property
    def theta_cr(self) -> float:
        """The critical angle ``alpha = atan(B/H)`` (rad)."""
        return math.atan2(self.width, self.height)

    @property
    def housner_e(self) -> float:
        """Housner's ``e = 1 - 1.5 sin^2(alpha)``."""
        return 1.0 - 1.5 * math.sin(self.theta_cr) ** 2


def parse_block(value) -> Block | None:
    """A :class:`Block` from ``"H,B"``, a pair ``(H, B)``, a :class:`Block` or ``None``.

    Examples
    --------
    >>> parse_block("0.6,0.2") == Block(0.6, 0.2)
    True
    """
    if value is None or isinstance(value, Block):
        return value
    if isinstance(value, str):
        parts = [p.strip() for p in value.split(",")]
        try:
            numbers = [float(p) for p in parts]
        except ValueError:
            numbers = []
        if len(numbers) != 2:
            raise InputError(f"`block` {value!r} is not a height and a width; give them as H,B in one unit (e.g. 0.6,0.2).")
        return Block(*numbers)
    try:
        height, width = value
    except (TypeError, ValueError):
        raise InputError(f"`block` {show(value)} is not a height and a width; give block=(H, B) in one unit.") from None
    return Block(height, width)

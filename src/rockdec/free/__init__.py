"""The free-rocking (free-decay) reference test: ``e`` from a record of a block tilted,
released and rocking down to rest (paper §2: eqs. 2, 4, 6).

:mod:`rockdec.free.impacts` finds the releases and the impacts (the zero crossings),
:mod:`rockdec.free.arcs` fits the flight arcs between them with the model's closed-form
free flight, and :mod:`rockdec.free.analysis` reads ``e`` per impact and pooled
(:func:`rockdec.free.analysis.analyse_free_rocking`, the one entry point).
"""

__all__ = ["NO_RECORD_MODEL", "no_record_model"]

#: Why a free-rocking test takes no ``g``, load, sensor noise or sensor filter (the command
#: line and the campaign sheet refuse them with it).
NO_RECORD_MODEL = "the free-rocking test reads g off its arcs and needs no record model"


def no_record_model(test: str) -> str:
    """Why the ``test`` "free" or "shake" takes no record model (load, sensor noise, sensor
    filter; a free-rocking test no ``g`` either), in words.

    Examples
    --------
    >>> no_record_model("shake")
    'the shake-table test fits the free decay after the shaking and needs no record model'
    """
    return NO_RECORD_MODEL if test == "free" else "the shake-table test fits the free decay after the shaking and needs no record model"

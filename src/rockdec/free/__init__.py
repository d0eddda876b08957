"""The free-rocking (free-decay) reference test: ``e`` from a record of a block tilted,
released and rocking down to rest (paper §2: eqs. 2, 4, 6).

:mod:`rockdec.free.impacts` finds the releases and the impacts (the zero crossings),
:mod:`rockdec.free.arcs` fits the flight arcs between them with the model's closed-form
free flight, and :mod:`rockdec.free.analysis` reads ``e`` per impact and pooled
(:func:`rockdec.free.analysis.analyse_free_rocking`, the one entry point).
"""

"""The estimators of ``e``, declared once (paper §5; docs/method.md §5).

Every fact about an estimator lives in its :class:`EstimatorSpec`: its name, the signature
it reads (``trigger``: ``"a"`` the free response of ``D_a``, ``"v"`` the two-sided ``D_v``),
the paper's equation, its labels, whether it may be reported as ``e`` and where the studies
list it. The order of :data:`REGISTRY` is the order of the ``estimator`` coordinate and of
the batch kernel's output columns (:func:`column`); the tables, figures, the command line
and the calibration read their lists here. How to add an estimator: docs/adding-an-estimator.md.

This module imports nothing heavy: the Snakefile, the figures and the command line read it
without loading numba or xarray.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["BY_RANK", "CANDIDATES", "DEFAULT_ESTIMATOR", "ESTIMATORS", "REGISTRY", "spec", "trigger"]


@dataclass(frozen=True)
class EstimatorSpec:
    """One estimator of ``e``.

    ``name``: the ``estimator`` coordinate value; ``trigger``: ``"a"`` or ``"v"``, the
    signature it reads and whose trigger counts weight its extrapolation; ``equation``: the
    paper's equation numbers; ``label``: a few plain words for legends; ``symbol``: its
    formula in matplotlib's TeX; ``candidate``: it may be reported as ``e`` (the figures of
    the amplitude and coverage studies show the candidates); ``rank``: its place in the
    studies' tables (1 first: the most accurate at the paper's sizes); ``reads``: what of
    the signature it reads, in words (``rockdec estimate``'s report).
    """

    name: str
    trigger: str
    equation: str
    label: str
    symbol: str
    candidate: bool
    rank: int
    reads: str


REGISTRY = (
    EstimatorSpec("e_g", "a", "eqs. 25, 7", "global", r"$\hat e_g$", False, 7,
        "decay of every peak of D_a"),
    EstimatorSpec("e_0", "a", "eq. 26", "first peak", r"$\hat e_0$", True, 3,
        "first peak and trough of D_a"),
    EstimatorSpec("e1", "a", "eq. 27", "local, peak ratio", r"$\hat e_1 = \sqrt{|c_2|/c_1}$", False, 4,
        "start and first trough of D_a"),
    EstimatorSpec("e2", "a", "eq. 27", "local, slope ratio", r"$\hat e_2 = v_2/v_1$", False, 5,
        "slopes of D_a at the impact"),
    EstimatorSpec("e3", "a", "eq. 27", "local, mixed", r"$\hat e_3 = (|c_2|/c_1)\,t_1/(t_2 - t_1)$", False, 6,
        "trough and impact time of D_a"),
    EstimatorSpec("e4", "a", "eq. 27, corrected", "local, time ratio", r"$\hat e_4 = (t_2 - t_1)/t_1$ (corrected)", True, 1,
        "impact and trough times of D_a"),
    EstimatorSpec("e_v", "v", "eq. 6", "D_v slope jump", r"$\hat e_v$", True, 2,
        "slope jump of D_v at the impact"),
)
"""Every estimator, in the order of the ``estimator`` coordinate and of the kernel's columns."""

ESTIMATORS = tuple(spec.name for spec in REGISTRY)
"""Names of the estimators, in registry order."""

CANDIDATES = tuple(spec.name for spec in REGISTRY if spec.candidate)
"""The estimators that may be reported as ``e``, in registry order."""

BY_RANK = tuple(spec.name for spec in sorted(REGISTRY, key=lambda spec: spec.rank))
"""The estimators in the order of the studies' tables."""

DEFAULT_ESTIMATOR = "e_v"
"""The candidate reported as ``e``: the calibration's coverage study shows it best
(smallest spread and bias of the corrected value, coverage closest to 95 %)."""

_BY_NAME = {spec.name: spec for spec in REGISTRY}


def spec(name: str) -> EstimatorSpec:
    """The declaration of estimator ``name`` (``KeyError`` for an unknown name)."""
    return _BY_NAME[str(name)]


def column(name: str) -> int:
    """The column of estimator ``name`` in the batch kernel's output (its registry position)."""
    return ESTIMATORS.index(str(name))


def trigger(name: str) -> str:
    """The trigger (``"a"`` or ``"v"``) of the signature estimator ``name`` reads."""
    return spec(name).trigger


"""The confidence belt: a calibration (:mod:`rockdec.calibration`) turned into a
bias-corrected ``e`` and its 95 % interval.

Neyman construction. At each true ``e`` the raw estimate is taken as normal with mean
``m(e)`` and spread ``s(e)``, both smooth in ``e``: ``m`` a weighted least-squares cubic in
``e`` through the means of the calibration's grid points, ``log s`` a quadratic in
``log(1 - e)`` through their spreads (the spread shrinks like a power of ``1 - e`` as
``e -> 1``; a quadratic in ``e`` itself misses that and understates it by 20-30 % between
0.85 and 0.95). The corrected estimate solves ``m(e) = x`` for the observed ``x``; the
95 % interval is every ``e`` with ``|x - m(e)| <= 1.96 sqrt(s(e)^2 + var m(e))`` (``var m``
the uncertainty of the fitted mean, so a small calibration widens the interval rather
than shifting it unseen). A belt is inverted at the observed value, so it covers the
truth as often as the simulated spread says, whatever the bias; a parametric bootstrap
would need fresh simulations around each record, where the belt's grid is cached and
serves every record with the same settings. Whether it holds is measured, not assumed
(:mod:`rockdec.coverage`).

Kept apart from :mod:`rockdec.calibration` so that a change here never makes the stored
calibrations stale (their name hashes the source of the modules that build them).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np

if TYPE_CHECKING:  # annotations only: xarray loads where a function needs it
    import xarray as xr

    from rockdec import ncread

#: Two-sided normal quantile of the 95 % interval.
Z95 = 1.959963984540054


class Corrected(NamedTuple):
    """A bias-corrected estimate: ``value`` and the 95 % interval ``[low, high]``; ``notes``
    say when the interval reaches the end of the calibrated range or the raw value lies
    outside what any calibrated ``e`` produces."""

    value: float
    low: float
    high: float
    notes: tuple[str, ...]


class Belt(NamedTuple):
    """Smooth mean and spread of one estimator against the true ``e`` (module docstring);
    ``failed``: the fraction of calibration sets on which the estimator gave NaN."""

    e: np.ndarray
    mean: np.ndarray
    spread: np.ndarray
    failed: float


def belt(cal: ncread.Stored | xr.Dataset, name: str, points: int = 4001) -> Belt:
    """The belt of estimator ``name`` on a dense grid of ``points`` values of ``e``.

    ``failed``: the fraction of calibration sets on which the estimator gave NaN. Fewer
    than 5 usable grid points give an empty belt, which :func:`correct` refuses to invert.
    """
    raw = cal["raw"].sel(name=name).values
    e_grid = cal["e_true"].values
    ok = np.isfinite(raw)
    n = ok.sum(axis=1)
    use = n >= 3
    means = np.array([raw[j, ok[j]].mean() if use[j] else np.nan for j in range(e_grid.size)])
    sds = np.array([raw[j, ok[j]].std(ddof=1) if use[j] else np.nan for j in range(e_grid.size)])
    use &= sds > 0
    if use.sum() < 5:  # an empty belt: correct() says why
        return Belt(np.empty(0), np.empty(0), np.empty(0), float(1.0 - ok.sum() / ok.size))
    x = e_grid[use]
    log_s = np.polyfit(np.log1p(-x), np.log(sds[use]), 2)
    s_fit = np.exp(np.polyval(log_s, np.log1p(-x)))
    design = np.vander(x, 4)
    w = n[use] / s_fit**2
    cov = np.linalg.inv(design.T @ (design * w[:, None]))
    coef = cov @ (design.T @ (w * means[use]))
    dense = np.linspace(x[0], x[-1], points)
    dense_design = np.vander(dense, 4)
    mean = dense_design @ coef
    var_mean = np.einsum("ij,jk,ik->i", dense_design, cov, dense_design)
    spread = np.sqrt(np.exp(np.polyval(log_s, np.log1p(-dense))) ** 2 + var_mean)
    return Belt(dense, mean, spread, float(1.0 - ok.sum() / ok.size))


def belts(cal: ncread.Stored | xr.Dataset) -> dict[str, Belt]:
    """The belt of every name the calibration holds (each estimator of ``e``, and ``g``)."""
    return {str(name): belt(cal, str(name)) for name in cal["name"].values}


def _inside(b: Belt, observed: np.ndarray) -> np.ndarray:
    """``(observation, dense e)``: where the 95 % band of the belt holds each observation."""
    return np.abs(observed[:, None] - b.mean[None, :]) <= Z95 * b.spread[None, :]


def _ends(b: Belt, inside: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The 95 % interval of each row of :func:`_inside`: its first and last ``e``."""
    return b.e[np.argmax(inside, axis=1)], b.e[b.e.size - 1 - np.argmax(inside[:, ::-1], axis=1)]


def correct_g(g_belt: Belt, g_raw: float, e: float) -> float:
    """``g`` read off a record, corrected for its window bias: ``g_raw`` over the mean
    ratio (measured ``g`` / true ``g``) of the calibration at the corrected ``e``; NaN when
    ``e`` is NaN or the ``g`` belt is empty."""
    if g_belt.e.size == 0 or not np.isfinite(e):
        return float("nan")
    return float(g_raw / np.interp(e, g_belt.e, g_belt.mean))


def correct(b: Belt, observed: float) -> Corrected:
    """Invert the belt at ``observed``: the corrected ``e`` and its 95 % interval."""
    if not np.isfinite(observed):
        return Corrected(np.nan, np.nan, np.nan, ("no raw estimate",))
    if b.e.size == 0:
        return Corrected(np.nan, np.nan, np.nan, (f"the estimator failed on {b.failed:.0%} of the calibration records, too many for a belt",))
    notes = []
    inside = _inside(b, np.array([observed]))[0]
    if not inside.any():
        nearest = int(np.argmin(np.abs(observed - b.mean) / b.spread))
        return Corrected(np.nan, np.nan, np.nan, (f"the raw value {observed:.4f} is not produced by any calibrated e (nearest e = {b.e[nearest]:.3f})",))
    idx = np.flatnonzero(inside)
    low, high = _ends(b, inside[None])
    low, high = low[0], high[0]
    if idx[0] == 0 or idx[-1] == b.e.size - 1:
        notes.append(f"the interval reaches the end of the calibrated range [{b.e[0]:.3f}, {b.e[-1]:.3f}]")
    # corrected value: where the mean curve meets the observation, inside the interval
    gap = b.mean[idx] - observed
    crossing = np.flatnonzero(np.diff(np.sign(gap)) != 0)
    if crossing.size:
        i = idx[crossing[0]]
        value = float(np.interp(observed, sorted([b.mean[i], b.mean[i + 1]]), [b.e[i], b.e[i + 1]][:: 1 if b.mean[i] <= b.mean[i + 1] else -1]))
    else:
        value = float(b.e[idx[np.argmin(np.abs(gap))]])
        notes.append("the raw value lies beyond the calibrated mean curve; the corrected value is its nearest point")
    return Corrected(value, float(low), float(high), tuple(notes))


def calibration_coverage(cal: ncread.Stored | xr.Dataset, name: str, b: Belt) -> float:
    """Share of the calibration's own record sets whose 95 % interval (:func:`correct`)
    holds their true ``e``: the coverage of the interval at the record's own settings.

    In-sample (the belt was fitted to these sets), so it can only flatter the interval a
    little; the out-of-sample check is :mod:`rockdec.coverage`. Sets at a true ``e``
    outside the belt's range, and failed sets, count as not covered. NaN for an empty belt.
    """
    if b.e.size == 0:
        return float("nan")
    raw = cal["raw"].sel(name=name).values  # (e_true, set)
    truth = np.broadcast_to(cal["e_true"].values[:, None], raw.shape).ravel()
    x = raw.ravel()
    inside = _inside(b, x)
    any_inside = inside.any(axis=1) & np.isfinite(x)
    low, high = _ends(b, inside)
    return float(np.mean(any_inside & (low <= truth) & (truth <= high)))

"""The analysis of one measured record (or several records of one block), end to end.

:func:`analyse` takes rocking records sampled at ``dt`` and returns every estimator of ``e``
at zero window (eqs. 25-27, ``e_v``), the restoring acceleration ``g`` read off the
signature and the sampling density, as an :class:`Analysis`. The calibration runs this very
function on simulated records, so whatever it does to a measured record it also does to the
records that calibrate it. Each record loses its mean; ``sigma_Y`` and ``sigma_Ydot`` are
pooled; a first ``D_a`` signature locates the free response's first zero crossing ``t1``,
and ``g = 2 r(0)/t1^2`` (the free flight ``a - g tau^2/2`` of eq. 4) sizes the lag range
(``n_periods`` periods at ``a``, eq. 5) and the samples per cycle. The triggers of all
records pool into one signature per window at one trigger level, and from the pooled sums
on the analysis is the workflow's core (:func:`rockdec.rdd.estimators.window_estimates`,
:func:`rockdec.rdd.estimators.zero_window`). The reported ``g = 2 c1/t1^2`` takes ``c1``,
``t1`` from the fits of eq. 27 at the largest window (the least noisy); its window bias is
calibrated away like ``e``'s. :func:`rocking_shape` says why a free response does not look
like rocking.

Explanation: docs/explanation/method/measured-record.md (``g`` from the record).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from rockdec.rdd import estimators, fits, registry, signatures
from rockdec.rdd.estimators import G_NAME
from rockdec.physics.models import period_from_g

__all__ = ["Analysis", "DEFAULT_SETTINGS", "G_NAME", "analyse", "rocking_shape"]

#: Settings of the analysis and their defaults (the workflow's scene defaults, see the schema).
DEFAULT_SETTINGS = {
    "level": 2.0,
    "windows": signatures.DEFAULT_WINDOWS,
    "window_max": 0.28,
    "v_level": 1.0,
    "dv_max": 0.28,
    "n_periods": 2.5,
    "both_signs": True,
    "fit_points": fits.DEFAULT_FIT_POINTS,
    "weights": "window",
}

#: Fewest samples from lag 0 to the first zero crossing of a rocking free response: white
#: noise crosses sooner, simulated rocking later (evidence: docs/explanation/constants.md).
MIN_HALF_CYCLE_SAMPLES = 3

#: Largest rms misfit, relative to its start value, of the parabola of eq. 4 through the
#: first half cycle of the free response: three times the largest measured on simulated
#: rocking (docs/explanation/constants.md).
MAX_PARABOLA_MISFIT = 0.15

#: Largest relative spread (std/mean) of ``g`` fitted at each window: three times the
#: largest measured on simulated rocking (docs/explanation/constants.md).
MAX_G_SPREAD = 0.5


class Analysis(NamedTuple):
    """What :func:`analyse` measures on a set of records.

    ``raw``: zero-window value per estimator of :data:`rockdec.rdd.registry.ESTIMATORS`
    (dimensionless) and ``"g"`` (rad/s^2, largest window); ``per_window``: the same names, one value per
    window; ``count``: triggers per window, ``{"a": ..., "v": ...}``; ``sigma_y`` (rad),
    ``points_per_cycle`` (samples per cycle at amplitude ``sigma_y`` with the measured
    ``g``, eq. 5), ``dt`` (s), ``n_lag``; ``free_response`` (largest window,
    ``tau >= 0``) and ``velocity_signature`` (``D_v`` at the largest window, two-sided,
    ``tau`` from ``-n_lag dt`` to ``n_lag dt``) for plots; ``nan_samples``: NaN samples in the records.
    """

    raw: dict
    per_window: dict
    count: dict
    sigma_y: float
    points_per_cycle: float
    dt: float
    n_lag: int
    free_response: np.ndarray
    velocity_signature: np.ndarray
    nan_samples: int


def _pooled(records, sums):
    """``sums(y)`` (a tuple of arrays) of every record, added: signatures pool by adding
    their sums and counts (eq. 8)."""
    total = None
    for y in records:
        part = sums(y)
        total = part if total is None else tuple(t + p for t, p in zip(total, part))
    return total


def _largest_window_response(sums: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """The free-response estimate (eq. 20) of the ``D_a`` sums ``sums[window, lag]`` at the
    largest window; NaN when it holds no trigger (the counts say so)."""
    return signatures.free_response(signatures.mean_signature(sums[None, -1:], counts[None, -1:], triggers=("a",), warn=False)[0, 0])


def _sampled_crossing_g(r: np.ndarray, dt: float) -> float:
    """``g = 2 r[0] / t1^2`` with ``t1`` the first sign change of ``r``, linearly
    interpolated: the rough ``g`` that sizes the lag range; NaN when ``r`` never crosses.
    A step so large that ``t1^2`` overflows gives 0, which :func:`analyse` refuses."""
    below = np.flatnonzero(r <= 0.0)
    if not (r.size and r[0] > 0.0 and below.size):
        return np.nan
    k = below[0]
    t1 = (k - 1 + r[k - 1] / (r[k - 1] - r[k])) * dt
    with np.errstate(over="ignore"):  # thread-local, unlike a warnings filter: the analysis runs in threads
        return float(2.0 * r[0] / np.float64(t1) ** 2)


def _nanmean(x) -> float:
    """``np.nanmean(x)``, in one pass when ``x`` holds no NaN (its plain mean is then the same
    number: the same sum over the same values, by the same count)."""
    x = np.asarray(x, dtype=np.float64)
    with np.errstate(invalid="ignore"):  # inf - inf: nanmean says so
        mean = np.mean(x) if x.size else np.nan
    return mean if not np.isnan(mean) else np.nanmean(x)


def _crossing_interval(records) -> float:
    """Mean number of samples between zero crossings over the records (at least 1)."""
    crossings = sum(int(np.count_nonzero(np.diff(np.signbit(y[np.isfinite(y)])))) for y in records)
    samples = sum(int(np.isfinite(y).sum()) for y in records)
    return samples / max(crossings, 1)


def rocking_shape(analysis: Analysis) -> str | None:
    """Why the free response does not look like rocking (eq. 4), or ``None`` when it does.

    Three checks on the largest window: the free response stays positive for at least
    :data:`MIN_HALF_CYCLE_SAMPLES` samples; its first half cycle fits the parabola
    ``c - g tau^2 / 2`` of eq. 4 (least squares, no linear term: the velocity is zero at the
    trigger) within :data:`MAX_PARABOLA_MISFIT` of ``c``; and ``g`` fitted at each window
    (eq. 27) is found at half the windows at least and agrees between them within
    :data:`MAX_G_SPREAD`. White noise fails the first; a record with no rocking half cycle
    fails the others.
    """
    r = analysis.free_response
    below = np.flatnonzero(~(r > 0.0))
    k1 = int(below[0]) if below.size else r.size
    if k1 < MIN_HALF_CYCLE_SAMPLES:
        return (
            f"its free response falls to zero {k1} sample(s) after the trigger, where rocking takes at least "
            f"{MIN_HALF_CYCLE_SAMPLES} ({analysis.points_per_cycle:.1f} samples per cycle): the record looks like white "
            "noise, not rocking, or is sampled far too coarsely"
        )
    tau2 = (np.arange(k1) * analysis.dt) ** 2
    design = np.c_[np.ones(k1), tau2]
    coef, *_ = np.linalg.lstsq(design, r[:k1], rcond=None)
    misfit = float(np.sqrt(np.mean((design @ coef - r[:k1]) ** 2)) / r[0])
    if not misfit <= MAX_PARABOLA_MISFIT:
        return (
            f"the first half cycle of its free response misses the parabola of free rocking (eq. 4) by {misfit:.0%} "
            f"of its start value, where rocking stays within {MAX_PARABOLA_MISFIT:.0%}"
        )
    g = analysis.per_window[G_NAME]
    found = g[np.isfinite(g)]
    spread = float(np.std(found) / np.mean(found)) if found.size > 1 else np.inf
    if found.size < g.size / 2 or not abs(spread) <= MAX_G_SPREAD:
        return (
            f"g fitted at each window is found at {found.size} of {g.size} windows and spreads by {spread:.0%}, "
            f"where rocking gives one g at every window within {MAX_G_SPREAD:.0%}"
        )
    return None


def analyse(records, dt: float, settings: dict | None = None, g: float | None = None) -> Analysis:
    """Every estimator of ``e`` and ``g`` on the pooled signatures of ``records``.

    ``records``: a sequence of 1-D arrays (rad), each uniformly sampled at ``dt`` (s), NaN
    allowed (segments holding a NaN are skipped); ``settings``: overrides of
    :data:`DEFAULT_SETTINGS`; ``g`` (rad/s^2): the restoring acceleration when known,
    which then sizes the lag range instead of the signature's own estimate (step 2 of
    the module docstring is skipped; ``raw["g"]`` is still measured).
    """
    opts = {**DEFAULT_SETTINGS, **(settings or {})}
    records = [np.asarray(y, dtype=np.float64) - _nanmean(y) for y in records]
    nan_samples = sum(int(np.count_nonzero(~np.isfinite(y))) for y in records)
    sigma_y = float(np.sqrt(_nanmean(np.concatenate([y**2 for y in records]))))
    sigma_ydot = float(np.sqrt(_nanmean(np.concatenate([(np.diff(y) / dt) ** 2 for y in records]))))
    windows = np.asarray(opts["windows"], dtype=np.float64)
    levels = signatures.trigger_levels(
        sigma_y, sigma_ydot, **{key: opts[key] for key in ("level", "windows", "window_max", "v_level", "dv_max")}
    )
    a = levels["a"]
    shortest = min(y.size for y in records)

    g_first = np.nan
    if g is None:
        cap = (shortest - 1) // 2
        n_lag = min(int(np.ceil(4 * _crossing_interval(records))), cap)
        while True:
            total, count = _pooled(
                records, lambda y: signatures.extremum_sums(y, a, levels["a_widths"][-1:], n_lag, both_signs=opts["both_signs"])[:2]
            )
            g_first = _sampled_crossing_g(_largest_window_response(total, count), dt)
            if np.isfinite(g_first) or n_lag >= cap or not count.any():
                break
            n_lag = min(2 * n_lag, cap)
        if not count.any() and nan_samples:
            raise ValueError(
                f"{nan_samples} of {sum(y.size for y in records)} samples are NaN, scattered so that every segment of "
                f"{2 * n_lag + 1} samples around a trigger holds one and no signature can be formed; fill short gaps "
                "(interpolate them) or cut the record into pieces without gaps"
            )
        if np.isfinite(g_first) and not g_first >= np.finfo(np.float64).tiny:
            raise ValueError(
                f"g read off the record, {g_first:.3g} rad/s^2 at a step of {dt:g} s, is 0 in floating point; "
                "give the sampling step in s"
            )
        if not np.isfinite(g_first):
            raise ValueError(
                "the free-response estimate never crosses zero inside the record, so g cannot be read off it; "
                "give `g`, or a longer record"
            )
    lag_g = g if g is not None else g_first
    n_lag = signatures.lag_samples(opts["n_periods"], a, lag_g, dt)
    signatures.check_lag_range(
        n_lag, shortest, 1, windows.size,  # sums are taken one record at a time
        f"a lag range of {opts['n_periods']} rocking periods at the trigger level (g = {lag_g:.3g} rad/s^2)",
        "use longer records, a smaller n_periods, or the right g",
    )
    sums, counts = _pooled(
        records, lambda y: signatures.trigger_sums(y, **levels, n_lag=n_lag, dt=dt, both_signs=opts["both_signs"])[:2]
    )
    values = estimators.window_estimates(sums, counts, dt, opts["fit_points"])
    value, _, _ = estimators.zero_window(windows, values, counts, opts["weights"])
    per_window = dict(zip(estimators.COLUMNS, values))
    return Analysis(
        raw={G_NAME: per_window[G_NAME][-1], **{name: float(v) for name, v in zip(registry.ESTIMATORS, value)}},
        per_window=per_window,
        count=dict(zip(signatures.TRIGGERS, counts)),
        sigma_y=sigma_y,
        points_per_cycle=float(period_from_g(sigma_y, lag_g) / dt),
        dt=float(dt),
        n_lag=int(n_lag),
        free_response=_largest_window_response(sums[0], counts[0]),
        velocity_signature=signatures.mean_signature(sums[1][None, -1:], counts[1][None, -1:], triggers=("v",), warn=False)[0, 0],
        nan_samples=nan_samples,
    )

"""Estimators of the coefficient of restitution ``e`` from RDD signatures (paper §5).

Inputs: ``r``, the free-response estimate (the even part of a two-sided ``D_a`` signature,
eq. 19; ideally the parabola ``a - g tau^2/2`` to ``t1 = sqrt(2a/g)``, then ``-e^2 a`` at
``t2 = (1 + e) t1``), and ``d``, a two-sided ``D_v`` signature (lag 0 at index ``L``). The
estimators, each an :class:`Estimate` (a value, and why when it is NaN): ``e_g`` (global
logarithmic decrement, eqs. 25, 7), ``e_0`` (first maximum and minimum, eq. 26), ``e1..e4``
(local fits on the first half cycle, eq. 27, :func:`half_cycle`), ``e_v`` (the slope ratio
through the impact of ``D_v``, eq. 6), and ``g = 2 c1/t1^2`` (eq. 4) from the fits
(:data:`COLUMNS`). The numba kernels never raise on bad data: a NaN carries a reason code.
:func:`estimate_all` runs them on one signature, :func:`estimate_cube` on labelled blocks.

The analysis core every analysis runs (the workflow, ``rockdec estimates``,
:func:`rockdec.rdd.measured.analyse`, so ``rockdec estimate`` and the calibration):
:func:`window_estimates` (pooled sums to every column at every window) and
:func:`zero_window` (the weighted extrapolation to zero window, :func:`extrapolation_weights`;
:func:`extrapolate_to_zero`), labelled by :func:`window_cube` and :func:`extrapolate`.
Units: rad, s, rad/s; every ``e`` is dimensionless.

Explanation: docs/explanation/method/estimators.md, docs/explanation/method/extrapolation.md.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
from numba import njit

from rockdec._version import __version__
from rockdec.rdd import registry
from rockdec import validate as checks
from rockdec.rdd.fits import DEFAULT_FIT_POINTS, MIN_FIT_POINTS
from rockdec.rdd.registry import ESTIMATORS
from rockdec.rdd.signatures import TRIGGERS, free_response, mean_signature

if TYPE_CHECKING:  # annotations only: xarray loads where a function needs it
    import xarray as xr

__all__ = [
    "COLUMNS", "DEFAULT_FIT_POINTS", "ESTIMATORS", "Estimate", "FLAT_ULPS", "G_NAME", "HalfCycle",
    "LOCAL_ESTIMATORS", "MIN_FIT_POINTS", "estimate_all", "estimate_cube", "extrapolate",
    "extrapolate_to_zero", "extrapolation_weights", "half_cycle", "window_cube", "window_estimates",
    "zero_window",
]

LOCAL_ESTIMATORS = ("e1", "e2", "e3", "e4")
"""The estimators of eq. 27, computed from one set of half-cycle fits (:func:`_local_measures`)."""

G_NAME = "g"
"""Name of the restoring acceleration ``g = 2 c1 / t1^2`` (rad/s^2, eq. 4) read off the
half-cycle fits of eq. 27, the column after the estimators of ``e``."""

COLUMNS = (*ESTIMATORS, G_NAME)
"""The batch kernel's output columns: every registered estimator (registry order), then ``g``."""

_KERNEL_OUTPUTS = ("e_g", "e_0", *LOCAL_ESTIMATORS, "e_v", G_NAME)
"""What :func:`_estimate_rows` computes, in its order of work (the kernel reads the first
eight positions; a new estimator goes at the end); :data:`_COLUMNS` places each in its
column of :data:`COLUMNS`. Every registered estimator has one, checked at import."""

if sorted(_KERNEL_OUTPUTS) != sorted(COLUMNS):
    raise ImportError(f"the estimator kernel computes {_KERNEL_OUTPUTS} but the registry declares {ESTIMATORS}")

_COLUMNS = np.array([COLUMNS.index(name) for name in _KERNEL_OUTPUTS], dtype=np.int64)
"""Column of each of :data:`_KERNEL_OUTPUTS` (the registry's for the estimators), passed to
the kernel at run time (a numba cache does not see a change of another module's constants)."""

_TRIGGER_ROWS = np.array([TRIGGERS.index(registry.trigger(name)) for name in ESTIMATORS], dtype=np.int64)
"""Index along ``trigger`` (:data:`rockdec.rdd.signatures.TRIGGERS`) of the signature each
estimator reads (:func:`rockdec.rdd.registry.trigger`): the counts that weight its extrapolation."""


class Estimate(NamedTuple):
    """One estimate of ``e`` (dimensionless); ``reason`` is ``""`` unless ``value`` is NaN."""

    value: float
    reason: str = ""


class HalfCycle(NamedTuple):
    """Second-order-fit features of the first half cycle of ``r`` (eq. 27).

    ``c1`` value at ``tau = 0`` (rad); ``t1`` first zero crossing (s); ``v1``, ``v2`` slopes
    just before and just after it, both taken at ``t1`` (rad/s); ``t2``, ``c2`` time (s)
    and value (rad) of the first minimum. All NaN when ``reason`` is not ``""``.
    """

    c1: float
    t1: float
    v1: float
    v2: float
    t2: float
    c2: float
    reason: str = ""


class Extrapolation(NamedTuple):
    """A weighted straight line ``y = value + slope * x`` and the standard error of ``value``."""

    value: float
    stderr: float
    slope: float
    reason: str = ""


# --------------------------------------------------------------------------- reason codes

_REASONS: list[str] = []
"""Why a kernel's value is NaN, indexed by its integer code (0: no NaN)."""


def _reason_code(text: str) -> int:
    """A new reason code for ``text`` (the numba kernels see the returned integer)."""
    _REASONS.append(text)
    return len(_REASONS) - 1


_OK = _reason_code("")
_EMPTY = _reason_code("empty signature")
_NAN = _reason_code("NaN in signature")
_R0_NOT_POSITIVE = _reason_code("r[0] not positive")
_NO_CROSSING = _reason_code("no zero crossing")
_BEYOND_LAGS = _reason_code("first minimum beyond the lag range")
_FEW_POINTS = _reason_code(f"fewer than {MIN_FIT_POINTS} points for a fit")
_NO_ROOT = _reason_code("before-crossing fit has no real root")
_TOUCHES_ZERO = _reason_code("before-crossing fit touches zero without crossing")
_NO_MINIMUM = _reason_code("minimum fit has no minimum")
_C1_NOT_POSITIVE = _reason_code("fitted c1 not positive")
_T1_OUTSIDE = _reason_code("fitted crossing t1 not between 0 and t2")
_NOT_FINITE = _reason_code("not finite: the signature values overflow the arithmetic")
_EVEN_LENGTH = _reason_code("D_v signature length not odd: no lag 0")
_FEW_LAGS = _reason_code("fewer than fit_points={fit_points} lags on a side")
_ZERO_SLOPE = _reason_code("zero slope before the impact")
_NO_DV = _reason_code("no D_v signature")


def _reason(code, fit_points=None) -> str:
    return _REASONS[code].format(fit_points=fit_points)


def _as_estimate(value, code, fit_points=None) -> Estimate:
    return Estimate(float(value), _reason(code, fit_points))


# --------------------------------------------------------------------------- numba kernels

_jit = njit(nogil=True, cache=True, error_model="numpy")  # IEEE results (inf, NaN), never raise
_inline = njit(nogil=True, cache=True, error_model="numpy", inline="always")  # typed into each caller: no compile of its own


@_inline
def _finite(value):
    """``(value, 0)``, or ``(NaN, not finite)`` when the arithmetic left the floating-point range."""
    if math.isfinite(value):
        return value, _OK
    return np.nan, _NOT_FINITE


@_jit
def _fit2(k0, dt, y):
    """Least-squares parabola ``y = c0 + c1 (t - tc) + c2 (t - tc)^2`` through the samples
    ``y[j]`` at the times ``t_j = (k0 + j) dt`` (lag ``k0 + j``, ``k0`` an integer).

    Returns ``(tc, c0, c1, c2)``. Solved by the 3x3 normal equations in the scaled variable
    ``u = (t - tc)/h`` in ``[-1, 1]`` (``tc``, ``h`` the centre and half-range of ``t``,
    at least 3 points), by Gaussian elimination with partial pivoting as ``np.linalg.solve``
    does: well conditioned for the few points of each fit, and far cheaper than a general
    polynomial fit.
    """
    n = y.size
    first, last = dt * k0, dt * (k0 + n - 1)
    tc = 0.5 * (first + last)
    h = 0.5 * (last - first)
    s1 = s2 = s3 = s4 = b0 = b1 = b2 = 0.0
    for j in range(n):
        u = (dt * (k0 + j) - tc) / h
        u2 = u * u
        s1 += u
        s2 += u2
        s3 += u2 * u
        s4 += u2 * u2
        b0 += y[j]
        b1 += u * y[j]
        b2 += u2 * y[j]
    a = np.empty((3, 4))  # the augmented normal equations [A | b]
    a[0, 0], a[0, 1], a[0, 2], a[0, 3] = n, s1, s2, b0
    a[1, 0], a[1, 1], a[1, 2], a[1, 3] = s1, s2, s3, b1
    a[2, 0], a[2, 1], a[2, 2], a[2, 3] = s2, s3, s4, b2
    for col in range(3):  # LU with partial pivoting, the order of operations of LAPACK's gesv
        pivot = col
        for row in range(col + 1, 3):
            if abs(a[row, col]) > abs(a[pivot, col]):
                pivot = row
        if pivot != col:
            for k in range(col, 4):
                a[col, k], a[pivot, k] = a[pivot, k], a[col, k]
        inverse = 1.0 / a[col, col]
        for row in range(col + 1, 3):
            factor = a[row, col] * inverse
            for k in range(col + 1, 4):
                a[row, k] -= factor * a[col, k]
    for col in range(2, -1, -1):  # back substitution by columns
        a[col, 3] /= a[col, col]
        for row in range(col):
            a[row, 3] -= a[row, col] * a[col, 3]
    a0, a1, a2 = a[0, 3], a[1, 3], a[2, 3]
    return tc, a0, a1 / h, a2 / (h * h)


@_inline
def _value(p, t):
    u = t - p[0]
    return p[1] + u * (p[2] + u * p[3])


@_inline
def _slope(p, t):
    return p[2] + 2.0 * p[3] * (t - p[0])


#: A slope within this many rounding units of the fitted values' scale over the fit's
#: span is zero: a flat stretch fits to 0 or to +-1e-17, depending on the order of operations.
FLAT_ULPS = 64.0
_EPS = float(np.finfo(np.float64).eps)  # a constant to the kernels: no np.finfo to compile


@_inline
def _flat(slope, y, span):
    """Whether ``slope`` (rad/s) is zero to rounding, given values ``y`` fitted over ``span`` s."""
    scale = 0.0
    for k in range(y.size):
        scale = max(scale, abs(y[k]))
    return abs(slope) * span <= FLAT_ULPS * _EPS * scale


@_inline
def _root_nearest(p, target):
    """``(found, t)``: the real root of parabola ``p`` nearest ``target``, computed without
    cancellation (``q = -(c1 + sign(c1) sqrt(disc))/2``, roots ``q/c2`` and ``c0/q``); a NaN
    root counts as nearest (as ``argmin`` does)."""
    tc, c0, c1, c2 = p
    if c2 == 0.0:
        if c1 == 0.0:
            return False, np.nan
        return True, tc - c0 / c1
    disc = c1 * c1 - 4.0 * c2 * c0
    if disc < 0.0:
        return False, np.nan
    q = -0.5 * (c1 + math.copysign(math.sqrt(disc), c1))
    first = tc + q / c2
    if q == 0.0:
        return True, first
    second = tc + c0 / q
    d0, d1 = abs(first - target), abs(second - target)
    if not math.isnan(d0) and (math.isnan(d1) or d1 < d0):
        return True, second
    return True, first


@_jit
def _lobes(r):
    """Half cycles of ``r`` and their sampled extremes: ``(code, table)``.

    A lobe is a maximal run of samples of one sign; samples exactly zero belong to no lobe
    and do not split a run of one sign (touching zero is no crossing). ``table[i]`` is
    ``(start, stop, k_extreme)`` of lobe ``i`` (``stop`` exclusive, ``k_extreme`` the first
    sample of largest ``|r|``); no rows and a reason code when fewer than two lobes remain.
    The last lobe is dropped when its extreme is the last sample of the record: ``|r|`` is
    still growing, so its extreme lies beyond the lag range.
    """
    table = np.empty((r.size, 3), np.int64)
    if r.size == 0:
        return _EMPTY, table[:0]
    for k in range(r.size):
        if not math.isfinite(r[k]):
            return _NAN, table[:0]
    if r[0] <= 0.0:
        return _R0_NOT_POSITIVE, table[:0]
    n, sign, largest = 0, 0.0, 0.0
    for k in range(r.size):
        if r[k] == 0.0:
            continue
        size = abs(r[k])
        if (r[k] > 0.0) != (sign > 0.0) or n == 0:
            sign = 1.0 if r[k] > 0.0 else -1.0
            table[n, 0], table[n, 1], table[n, 2] = k, k + 1, k
            largest = size
            n += 1
        else:
            table[n - 1, 1] = k + 1
            if size > largest:
                largest = size
                table[n - 1, 2] = k
    if n < 2:
        return _NO_CROSSING, table[:0]
    if table[n - 1, 2] == r.size - 1:
        n -= 1
    if n < 2:
        return _BEYOND_LAGS, table[:0]
    return _OK, table[:n]


@_inline
def _e_global(r, code, lobes):
    """``e_g`` (eqs. 25, 7) from the lobes of ``r``: ``(value, code)``.

    The extremes ``r_i`` are the sampled values of largest ``|r|`` of each lobe (no
    derivative, no threshold: robust on noisy estimates; off the true extreme by at most
    ``g dt^2/8``). With ``2 ln|r_i| = 2 ln r_0 - i delta`` (eq. 25) the least-squares slope
    of ``2 ln|r_i|`` on ``i`` is ``-delta``, and ``e = exp(-delta/4)`` (eq. 7).
    """
    if code != _OK:
        return np.nan, code
    n = lobes.shape[0]
    num = den = 0.0
    for j in range(n):
        i = j - 0.5 * (n - 1)  # centred index: the slope needs no intercept
        num += i * (2.0 * math.log(abs(r[lobes[j, 2]])))
        den += i * i
    return _finite(math.exp(num / den / 4.0))


@_inline
def _e_first_peak(r, code, lobes):
    """``e_0 = sqrt(|r_1| / r_0)`` (eq. 26), the first two sampled extremes of ``r``: ``(value, code)``."""
    if code != _OK:
        return np.nan, code
    return _finite(math.sqrt(abs(r[lobes[1, 2]]) / r[lobes[0, 2]]))


@_jit
def _half_cycle(r, dt, code, lobes):
    """The fits of eq. 27 (see :func:`half_cycle`): ``((c1, t1, v1, v2, t2, c2), code)``."""
    nan6 = (np.nan, np.nan, np.nan, np.nan, np.nan, np.nan)
    if code != _OK:
        return nan6, code
    end0 = lobes[0, 1]
    start1, end1, m = lobes[1, 0], lobes[1, 1], lobes[1, 2]
    n_h = m + 1
    n8 = max(MIN_FIT_POINTS, n_h // 8)
    n4 = max(MIN_FIT_POINTS, n_h // 4)
    a_start, b_start = lobes[0, 0], min(n8, end0)  # lag 0, where lobe 0 starts (r[0] > 0); a literal 0 would compile _fit2 again
    a_before, b_before = max(0, end0 - n8), end0
    a_after, b_after = start1, min(start1 + n8, end1)
    a_min, b_min = max(start1, m - (n4 - 1) // 2), min(end1, m + n4 // 2 + 1)
    if min(b_start - a_start, b_before - a_before, b_after - a_after, b_min - a_min) < MIN_FIT_POINTS:
        return nan6, _FEW_POINTS
    before = _fit2(a_before, dt, r[a_before:b_before])
    found, t1 = _root_nearest(before, 0.5 * (dt * (end0 - 1) + dt * start1))
    if not found:
        return nan6, _NO_ROOT
    v1 = _slope(before, t1)
    if v1 == 0.0:
        return nan6, _TOUCHES_ZERO
    minimum = _fit2(a_min, dt, r[a_min:b_min])
    if not minimum[3] > 0.0:
        return nan6, _NO_MINIMUM
    t2 = minimum[0] - minimum[2] / (2.0 * minimum[3])
    c1 = _value(_fit2(a_start, dt, r[a_start:b_start]), 0.0)
    if not c1 > 0.0:
        return nan6, _C1_NOT_POSITIVE
    if not 0.0 < t1 < t2:
        return nan6, _T1_OUTSIDE
    v2 = _slope(_fit2(a_after, dt, r[a_after:b_after]), t1)
    return (c1, t1, v1, v2, t2, _value(minimum, t2)), _OK


@_inline
def _local_measures(h, code, values, codes, columns):
    """``e1..e4`` of eq. 27 from the half-cycle features ``h`` into ``values[columns[k]]``,
    ``codes[columns[k]]`` (``columns``: the columns of ``e1..e4``).

    ``e1 = sqrt(|c2|/c1)``, ``e2 = v2/v1``, ``e3 = (|c2|/c1) t1/(t2 - t1)``,
    ``e4 = (t2 - t1)/t1`` (the paper prints its reciprocal, ``1/e`` on the ideal response;
    docs/method.md §5.3, §6).
    """
    if code != _OK:
        for k in range(4):
            values[columns[k]] = np.nan
            codes[columns[k]] = code
        return
    c1, t1, v1, v2, t2, c2 = h
    ratio = abs(c2) / c1
    values[columns[0]], codes[columns[0]] = _finite(math.sqrt(ratio))
    values[columns[1]], codes[columns[1]] = _finite(v2 / v1)
    values[columns[2]], codes[columns[2]] = _finite(ratio * t1 / (t2 - t1))
    values[columns[3]], codes[columns[3]] = _finite((t2 - t1) / t1)


@_inline
def _e_impact_slope(d, dt, fit_points):
    """``e_v`` (eq. 6): the ratio of the slopes of a ``D_v`` signature ``d`` after and before
    lag 0, ``(value, code)``.

    Lag 0 (index ``L`` of the ``2L+1`` lags) is a zero crossing where the velocity is
    multiplied by ``e``. Each side is fitted by a parabola (the free flight of eq. 4 is one,
    so the fit has no curvature bias) on the ``fit_points`` lags strictly on that side;
    lag 0 belongs to neither, because the slope is discontinuous there. Both fits are
    differentiated at ``tau = 0``: ``e_v = slope_after / slope_before``.
    """
    if d.size % 2 == 0:
        return np.nan, _EVEN_LENGTH
    for k in range(d.size):
        if not math.isfinite(d[k]):
            return np.nan, _NAN
    lag0 = d.size // 2
    if lag0 < fit_points:
        return np.nan, _FEW_LAGS
    lo, hi = lag0 - fit_points, lag0 + 1  # the first sample of each side's fit
    before = _slope(_fit2(lo - lag0, dt, d[lo:lag0]), 0.0)
    after = _slope(_fit2(hi - lag0, dt, d[hi : hi + fit_points]), 0.0)
    if _flat(before, d[lo:lag0], dt * fit_points):
        return np.nan, _ZERO_SLOPE
    return _finite(after / before)


@_jit
def _estimate_rows(r, d, dt, fit_points, columns):
    """Every column of :data:`COLUMNS` on every row: ``(values[n, column], codes[n, column])``.

    ``e_g`` (eqs. 25, 7), ``e_0`` (eq. 26), ``e1..e4`` (eq. 27) and ``g = 2 c1 / t1^2``
    (eq. 4: the free flight ``c1 - g tau^2/2`` crosses zero at ``t1``) from one lobe search
    and one set of half-cycle fits per free response, ``e_v`` (eq. 6) from its ``D_v`` row;
    each goes to its column ``columns[k]`` (:data:`_COLUMNS`, in the order of
    :data:`_KERNEL_OUTPUTS`).

    ``r[n, lag_pos]`` free responses, ``d[n, lag]`` their ``D_v`` signatures or ``None``
    (``e_v`` NaN, "no D_v signature"); ``dt`` and ``fit_points`` already checked.
    The batch kernel of :func:`estimate_cube` and :func:`estimate_all`.
    """
    n = r.shape[0]
    values = np.empty((n, columns.size))
    codes = np.empty((n, columns.size), np.int64)
    e_g, e_0, e_v, g = columns[0], columns[1], columns[6], columns[7]
    for i in range(n):
        row = r[i]
        code, lobes = _lobes(row)
        values[i, e_g], codes[i, e_g] = _e_global(row, code, lobes)
        values[i, e_0], codes[i, e_0] = _e_first_peak(row, code, lobes)
        h, h_code = _half_cycle(row, dt, code, lobes)
        _local_measures(h, h_code, values[i], codes[i], columns[2:6])
        if h_code == _OK:
            values[i, g], codes[i, g] = _finite(2.0 * h[0] / (h[1] * h[1]))
        else:
            values[i, g], codes[i, g] = np.nan, h_code
        if d is None:
            values[i, e_v], codes[i, e_v] = np.nan, _NO_DV
        else:
            values[i, e_v], codes[i, e_v] = _e_impact_slope(d[i], dt, fit_points)
    return values, codes


# --------------------------------------------------------------------------- one signature


def _as_row(a) -> np.ndarray:
    """``a`` as a contiguous float64 row; anything not one-dimensional as an empty row (whose
    kernels then say "empty signature" for ``r`` and "length not odd" for ``d``)."""
    a = np.asarray(a, dtype=float)
    return np.ascontiguousarray(a) if a.ndim == 1 else np.empty(0)


def _check_options(dt, fit_points, with_dv: bool) -> tuple[float, int]:
    """The input checks: ``fit_points`` (only when there is a ``D_v`` signature), then ``dt``.

    Returns ``dt`` and ``fit_points`` as the kernels take them (``fit_points`` 0, unused,
    without ``D_v``).
    """
    if not with_dv:
        return checks.positive(dt, "dt", "give the sampling interval in s, > 0"), 0
    if not (checks.is_whole(fit_points) and fit_points >= MIN_FIT_POINTS):
        raise checks.InputError(f"fit_points={fit_points}: need a whole number of at least {MIN_FIT_POINTS} points")
    return checks.positive(dt, "dt", "give the sampling interval in s, > 0"), int(fit_points)


def _lobes_of(r, lobes):
    """``lobes`` when the caller has them (the result of :func:`_lobes` on ``r``), else found."""
    return _lobes(r) if lobes is None else lobes


def half_cycle(r, dt: float, lobes=None) -> HalfCycle:
    """Fit the first half cycle of ``r`` with second-order polynomials (eq. 27).

    ``N_h = m + 1`` is the number of samples from ``tau = 0`` to the sampled first minimum
    ``m`` (:func:`_lobes`). Fits, each least squares of degree 2
    (:func:`_fit2`) in ``tau = k*dt``:

    - start: the first ``N_h // 8`` samples; ``c1`` = the fit at ``tau = 0``;
    - minimum: ``N_h // 4`` samples centred on ``m``; ``t2``, ``c2`` = its vertex;
    - before: the last ``N_h // 8`` samples before the first crossing; ``t1`` = its root
      nearest the crossing (between the last positive and the first negative sample),
      ``v1`` = its slope at ``t1``;
    - after: the first ``N_h // 8`` samples after the crossing; ``v2`` = its slope at ``t1``.

    Every window is clipped to the half cycle it describes, so no fit straddles a zero
    crossing (across one the response is no single parabola), and gets at least
    :data:`MIN_FIT_POINTS` points, or the result is NaN with a reason. For the ideal
    response (eqs. 4, 6) every window holds samples of one parabola and the features are
    exact to rounding.
    """
    dt = checks.positive(dt, "dt", "give the sampling interval in s, > 0")
    r = _as_row(r)
    features, code = _half_cycle(r, dt, *_lobes_of(r, lobes))
    return HalfCycle(*features, reason=_reason(code))


def estimate_all(r, d, dt: float, fit_points: int = DEFAULT_FIT_POINTS) -> dict[str, Estimate]:
    """Every registered estimator on one free response ``r`` and one ``D_v``
    signature ``d`` (``None`` when there is none: ``e_v`` is then NaN): the batch kernel
    :func:`_estimate_rows` on a batch of one."""
    dt, points = _check_options(dt, fit_points, with_dv=d is not None)
    rows = None if d is None else _as_row(d)[None]
    values, codes = _estimate_rows(_as_row(r)[None], rows, dt, points, _COLUMNS)
    return {name: _as_estimate(v, c, fit_points) for name, v, c in zip(ESTIMATORS, values[0], codes[0])}


# --------------------------------------------------------------------------- zero window

_EXTRAPOLATION_REASONS = ("", "fewer than 2 usable points", "all points at one window size")


def _extrapolate_rows(x, y, w):
    """:func:`extrapolate_to_zero` (§5) on every row at once (last axis; ``x``, ``y``, ``w``
    broadcast): arrays ``value``, ``stderr``, ``slope`` and the reason code (index of
    :data:`_EXTRAPOLATION_REASONS`)."""
    x, y, w = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (x, y, w)))
    if np.any(w < 0):
        raise ValueError("weights must be non-negative")
    use = np.isfinite(x) & np.isfinite(y) & np.isfinite(w) & (w > 0)
    n = use.sum(axis=-1)

    def wsum(terms):  # sum of w * terms over the usable points only
        return np.where(use, w * terms, 0.0).sum(axis=-1)

    with np.errstate(all="ignore"):
        total = wsum(1.0)
        xm = wsum(x) / total
        ym = wsum(y) / total
        dx, dy = x - xm[..., None], y - ym[..., None]
        sxx = wsum(dx**2)
        slope = wsum(dx * dy) / sxx
        value = ym - slope * xm
        s2 = wsum((y - value[..., None] - slope[..., None] * x) ** 2) / (n - 2)
        stderr = np.sqrt(s2 * (1.0 / total + xm**2 / sxx))
    code = np.where(n < 2, 1, np.where(sxx == 0, 2, 0))
    value, slope = (np.where(code == 0, a, np.nan) for a in (value, slope))
    stderr = np.where((code == 0) & (n > 2), stderr, np.nan)
    return value, stderr, slope, code


def extrapolate_to_zero(x, y, weights=None) -> Extrapolation:
    """Weighted least-squares line ``y = value + slope * x``; ``value`` is ``y`` at ``x = 0``.

    Paper §5: ``x`` is the window size, ``y`` an estimate of ``e`` at that window; the
    weights stand for reciprocal variances, about proportional to the trigger count, which
    is about proportional to the window size: ``weights=None`` means ``weights = x``; pass
    the trigger counts to use them directly. Only relative weights matter.

    Points with a NaN in ``x``, ``y`` or the weight, or a weight of zero, are left out (a
    point of weight zero has no influence). With ``W = sum w``, weighted means
    ``xm = sum w x / W``, ``ym = sum w y / W`` and ``Sxx = sum w (x - xm)^2``:
    ``slope = sum w (x - xm)(y - ym) / Sxx``, ``value = ym - slope * xm``. The standard
    error takes ``Var(y_i) = s^2 / w_i`` with ``s^2`` estimated from the weighted residuals,
    ``s^2 = sum w (y - value - slope x)^2 / (n - 2)``:
    ``stderr = sqrt(s^2 (1/W + xm^2/Sxx))``. With exactly two points there is no residual
    degree of freedom and ``stderr`` is NaN (``value`` and ``slope`` are exact).
    Fewer than two usable points, or all at one ``x``: everything NaN, with a reason.
    Negative weights are a caller error (``ValueError``).
    """
    value, stderr, slope, code = _extrapolate_rows(x, y, x if weights is None else weights)
    return Extrapolation(float(value), float(stderr), float(slope), _EXTRAPOLATION_REASONS[int(code)])


# --------------------------------------------------------------------------- the analysis core


def _estimate_block(r, d, dt, fit_points):
    """:func:`_estimate_rows` on a block ``r[..., lag_pos]``, ``d[..., lag]`` (leading axes
    broadcast) -> ``values[..., column]`` (:data:`COLUMNS`)."""
    shape = r.shape[:-1] if d is None else np.broadcast_shapes(r.shape[:-1], d.shape[:-1])

    def rows(a):  # a writable copy: the kernel then has the one type estimate_all gives it, compiled once
        return np.array(np.broadcast_to(a, shape + a.shape[-1:]), dtype=float, order="C").reshape(math.prod(shape), a.shape[-1])

    values, _ = _estimate_rows(rows(r), None if d is None else rows(d), dt, fit_points, _COLUMNS)
    return values.reshape(shape + (len(COLUMNS),))


def window_estimates(sums, counts, dt: float, fit_points: int = DEFAULT_FIT_POINTS) -> np.ndarray:
    """Every column of :data:`COLUMNS` at every window, from pooled signature sums and counts.

    ``sums[..., trigger, window, lag]`` and ``counts[..., trigger, window]`` (triggers in the
    order of :data:`rockdec.rdd.signatures.TRIGGERS`, two-sided lags, pooled over whatever
    series the caller pools) give the signatures ``sum / count`` (eq. 8; NaN in a window
    without a trigger, which ``counts`` reports), the free response of ``D_a`` (its even
    part, eq. 20) and ``D_v`` (eq. 19). The batch kernel :func:`_estimate_rows` takes every
    window of every leading index at once. Returns ``values[..., column, window]``: the
    estimators of ``e`` (eqs. 25-27, 6; dimensionless) and ``g`` (rad/s^2, eq. 4).
    """
    dt, points = _check_options(dt, fit_points, with_dv=True)
    signature = mean_signature(sums, counts, warn=False)  # empty windows are reported through ``counts``
    values = _estimate_block(free_response(signature[..., 0, :, :]), signature[..., 1, :, :], dt, points)
    return np.swapaxes(values, -1, -2)


def extrapolation_weights(windows, counts, weights: str = "window") -> np.ndarray:
    """The weights of every estimator's zero-window extrapolation (paper §5), ``[..., estimator, window]``.

    ``"window"``: the window sizes ``windows`` (the paper's choice: the trigger count, and
    so the reciprocal variance, grows about as the window); ``"count"``: the trigger counts
    ``counts[..., trigger, window]`` of the signature each estimator reads
    (:func:`rockdec.rdd.registry.trigger`).
    """
    counts = np.asarray(counts)
    if weights == "count":
        return np.take(counts, _TRIGGER_ROWS, axis=-2).astype(float)
    if weights == "window":
        windows = np.asarray(windows, dtype=float)
        return np.broadcast_to(windows, counts.shape[:-2] + (len(ESTIMATORS), windows.size))
    raise ValueError(f"unknown extrapolation weights '{weights}'; use window or count")


def zero_window(windows, values, counts, weights: str = "window"):
    """Every estimator of ``values[..., column, window]`` (:func:`window_estimates`)
    extrapolated to zero window: ``(value, stderr, slope)``, each ``[..., estimator]``.

    The weighted least-squares line in the window size of :func:`extrapolate_to_zero`
    (paper §5), every row at once (:func:`_extrapolate_rows`), with the weights of
    :func:`extrapolation_weights`. The ``g`` column is not extrapolated: ``g`` is read at
    the largest window, where most triggers make it least noisy.
    """
    estimates = np.asarray(values)[..., : len(ESTIMATORS), :]
    return _extrapolate_rows(windows, estimates, extrapolation_weights(windows, counts, weights))[:3]


# --------------------------------------------------------------------------- labelled


def _e_hat_attrs(fit_points) -> dict:
    return {"units": "1", "long_name": "estimated coefficient of restitution", "fit_points": fit_points}


def window_cube(cube: xr.Dataset, fit_points: int = DEFAULT_FIT_POINTS) -> xr.Dataset:
    """:func:`window_estimates` on every signature of a cube (:func:`rockdec.rdd.signatures.signature_cube`).

    Reads ``signature_sum(..., trigger, window, lag)``, ``count(..., trigger, window)`` and
    ``dt``; NumPy or Dask (chunks of the leading dimensions stay lazy). Returns ``e_hat``
    (dimension ``estimator`` first, :data:`rockdec.rdd.registry.ESTIMATORS`, then the cube's
    leading dimensions and ``window``) and ``g_hat`` (rad/s^2, eq. 4).
    """
    import xarray as xr

    dt, points = _check_options(cube.attrs["dt"], fit_points, with_dv=True)  # now, not when a lazy cube computes
    values = xr.apply_ufunc(
        window_estimates,
        cube["signature_sum"],
        cube["count"],
        input_core_dims=[["trigger", "window", "lag"], ["trigger", "window"]],
        output_core_dims=[["column", "window"]],
        kwargs={"dt": dt, "fit_points": points},
        dask="parallelized",
        output_dtypes=[float],
        dask_gufunc_kwargs={"output_sizes": {"column": len(COLUMNS)}},
    )
    e_hat = values.isel(column=slice(0, len(ESTIMATORS))).rename(column="estimator")
    e_hat = e_hat.transpose("estimator", ...).assign_coords(estimator=list(ESTIMATORS))
    e_hat.attrs = _e_hat_attrs(fit_points)
    e_hat["estimator"].attrs["long_name"] = "estimator of e (paper eqs. 25-27, e_v from D_v)"
    g_hat = values.isel(column=len(ESTIMATORS), drop=True)
    g_hat.attrs = {"units": "rad s-2", "long_name": "restoring acceleration g = 2 c1/t1^2 (eqs. 4, 27)"}
    return xr.Dataset({"e_hat": e_hat, "g_hat": g_hat}, attrs={"history": f"rockdec {__version__}: window_cube"})


def estimate_cube(
    free_response: xr.DataArray,
    dv_signature: xr.DataArray | None,
    dt: float,
    fit_points: int = DEFAULT_FIT_POINTS,
) -> xr.Dataset:
    """:func:`estimate_all` over every free response of a labelled cube.

    ``free_response`` has core dimension ``lag_pos`` (``tau >= 0``), ``dv_signature`` core
    dimension ``lag`` (two-sided) or is ``None``; their other dimensions broadcast by
    name. Each block (all of a NumPy cube, each chunk of a Dask one, which stays lazy)
    goes to the batch kernel :func:`_estimate_rows` at once. Returns ``e_hat`` with
    dimension ``estimator`` (:data:`rockdec.rdd.registry.ESTIMATORS`) first; NaN where an estimator failed
    (:func:`estimate_all` on that signature says why).
    """
    import xarray as xr

    dt, points = _check_options(dt, fit_points, with_dv=dv_signature is not None)
    common = dict(
        dask="parallelized",
        output_core_dims=[["estimator"]],
        output_dtypes=[float],
        dask_gufunc_kwargs={"output_sizes": {"estimator": len(ESTIMATORS)}},
    )
    if dv_signature is None:
        e_hat = xr.apply_ufunc(
            lambda r: _estimate_block(r, None, dt, points)[..., : len(ESTIMATORS)],
            free_response,
            input_core_dims=[["lag_pos"]],
            **common,
        )
    else:
        e_hat = xr.apply_ufunc(
            lambda r, d: _estimate_block(r, d, dt, points)[..., : len(ESTIMATORS)],
            free_response,
            dv_signature,
            input_core_dims=[["lag_pos"], ["lag"]],
            **common,
        )
    e_hat = e_hat.transpose("estimator", ...).assign_coords(estimator=list(ESTIMATORS))
    e_hat.attrs = _e_hat_attrs(fit_points)
    e_hat["estimator"].attrs["long_name"] = "estimator of e (paper eqs. 25-27, e_v from D_v)"
    return xr.Dataset({"e_hat": e_hat}, attrs={"history": f"rockdec {__version__}: estimate_cube"})


def _extrapolation_block(x, y, w):
    return _extrapolate_rows(x, y, w)[:3]


def extrapolate(e_hat: xr.DataArray, weights: xr.DataArray | str | None = None, count: xr.DataArray | None = None) -> xr.Dataset:
    """:func:`extrapolate_to_zero` along ``window`` for every other index of ``e_hat``.

    ``x`` is the ``window`` coordinate; ``weights`` default to it (paper §5). Pass weights
    (dimension ``window``, broadcast by name), or a name of :func:`extrapolation_weights`
    with the trigger counts ``count(..., trigger, window)``: ``"window"`` or ``"count"``
    (each estimator weighted by the counts of its trigger; ``e_hat`` then has the
    ``estimator`` dimension). All rows of a block are fitted at once
    (:func:`_extrapolate_rows`). Returns ``e_hat0`` (value at zero window),
    ``e_hat0_stderr`` and ``slope``; reasons are dropped (NaN stays NaN).
    """
    import xarray as xr

    window = e_hat["window"]
    if isinstance(weights, str):
        weights = xr.apply_ufunc(
            extrapolation_weights,
            window,
            count,
            kwargs={"weights": weights},
            input_core_dims=[["window"], ["trigger", "window"]],
            output_core_dims=[["estimator", "window"]],
            dask="parallelized",
            output_dtypes=[float],
            dask_gufunc_kwargs={"output_sizes": {"estimator": len(ESTIMATORS)}},
        ).assign_coords(estimator=list(ESTIMATORS))
    w = window if weights is None else weights
    value, stderr, slope = xr.apply_ufunc(
        _extrapolation_block,
        window,
        e_hat,
        w,
        input_core_dims=[["window"]] * 3,
        output_core_dims=[[], [], []],
        dask="parallelized",
        output_dtypes=[float] * 3,
    )
    window_units = window.attrs.get("units", "1")
    return xr.Dataset(
        {
            "e_hat0": value.assign_attrs(
                units="1", long_name="estimated coefficient of restitution at zero window"
            ),
            "e_hat0_stderr": stderr.assign_attrs(
                units="1", long_name="standard error of e_hat0 (weighted least squares)"
            ),
            "slope": slope.assign_attrs(
                units="1" if window_units == "1" else f"1/({window_units})",
                long_name="slope of the estimate in the window size",
            ),
        },
        attrs={"history": f"rockdec {__version__}: extrapolate"},
    )

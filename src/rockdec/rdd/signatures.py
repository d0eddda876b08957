"""Random Decrement signatures of a rocking record (paper §3, eqs. 8, 18-20).

A signature (eq. 8) averages two-sided record segments ``y(t_i + tau)``,
``tau = -L dt .. +L dt`` (index ``L`` is ``tau = 0``), over trigger times ``t_i`` of eq. 19:
``D_a``, the extremum trigger (a sampled maximum within ``[a - da, a + da]``), and ``D_v``,
the zero-crossing trigger (the pre-impact velocity, from the parabola through the three
incoming samples, within ``[v - dv, v + dv]``, the segment interpolated to the chord root).
The nested windows are filled in one pass, and the kernels return *sums* and *counts*, so
signatures pool exactly by adding (over series, seeds, groups or time chunks).

Layers: the NumPy/numba kernels (:func:`extremum_sums`, :func:`crossing_sums`, both at once
:func:`trigger_sums`), small helpers (:func:`trigger_levels`, :func:`lag_samples`,
:func:`free_response`, :func:`pool`) and the xarray/Dask wrapper :func:`signature_cube`; the
estimators read the sums (:func:`rockdec.rdd.estimators.window_estimates`).

Explanation: docs/explanation/method/signatures.md (the tie rule, the crossing's velocity
and interpolation, gaps: §4.5).
"""

from __future__ import annotations

import warnings
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
from numba import njit

from rockdec._version import __version__
from rockdec import validate as checks
from rockdec.physics.models import period_from_g
from rockdec.timeaxis import sampling_step
from rockdec.warning_types import NoTriggerWarning

if TYPE_CHECKING:  # annotations only: xarray loads where a function needs it
    import xarray as xr

__all__ = [
    "DEFAULT_WINDOWS",
    "NoTriggerWarning",
    "SUM_VARS",
    "SignatureSums",
    "TRIGGERS",
    "check_lag_range",
    "crossing_sums",
    "extremum_sums",
    "free_response",
    "lag_samples",
    "mean_signature",
    "pool",
    "signature_cube",
    "trigger_levels",
    "trigger_sums",
]

DEFAULT_WINDOWS = (0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0)
"""Window half-widths relative to the largest one (``da/da_max``, ``dv/dv_max``)."""

TRIGGERS = ("a", "v")
SUM_VARS = ("signature_sum", "count", "skipped")
"""The variables of a cube that pool by adding (:func:`pool`); the rest derive from them."""


class SignatureSums(NamedTuple):
    """Per-series accumulators of one trigger, cumulative over the windows.

    ``sum[..., window, lag]`` (float64, sum of the segments), ``count[..., window]``
    (int64, triggers added) and ``skipped[..., window]`` (int64, triggers whose segment
    held a NaN).
    """

    sum: np.ndarray
    count: np.ndarray
    skipped: np.ndarray


# --------------------------------------------------------------------------- kernels


@njit(nogil=True, cache=True, inline="always")
def _nan_prefix(row, out):
    """``out[j]`` = number of NaN among ``row[:j]``."""
    out[0] = 0
    for j in range(row.size):
        out[j + 1] = out[j] + (1 if np.isnan(row[j]) else 0)


@njit(nogil=True, cache=True, inline="always")
def _close_windows(sums, counts, skipped):
    """Per-bin accumulators of one output row -> cumulative over the nested windows."""
    for w in range(1, counts.size):
        counts[w] += counts[w - 1]
        skipped[w] += skipped[w - 1]
        for k in range(sums.shape[1]):
            sums[w, k] += sums[w - 1, k]


@njit(nogil=True, cache=True, inline="always")
def _window(edges, dist):
    """The smallest window ``w`` with ``dist <= edges[w]`` (``np.searchsorted``; ``dist`` at most
    ``edges[-1]``): a scan, as short as the few windows."""
    w = 0
    while edges[w] < dist:
        w += 1
    return w


@njit(nogil=True, cache=True, inline="always")
def _add_interpolated(seg, row, base, n_lag, sign, frac):
    """``seg[k] += sign * y(t_base + (k + frac) dt)`` for every ``k`` of ``0..2 n_lag`` but lag 0
    (``k = n_lag``, the chord root, where the interpolant is 0), linear interpolation."""
    for k in range(2 * n_lag + 1):
        if k != n_lag:
            left = row[base + k]
            seg[k] += sign * (left + frac * (row[base + k + 1] - left))


@njit(nogil=True, cache=True)
def _extremum_kernel(y, rows_to, level, edges, n_lag, both_signs, lo, hi, sums, counts, skipped, nan_before):
    """One pass of the extremum trigger over ``y[row, time]`` for all windows ``edges``.

    Row ``r`` adds its segments, counts and skips into output row ``rows_to[r]``;
    ``nan_before`` (``time + 1`` int64) is scratch for each row's NaN counts (:func:`_nan_prefix`).
    """
    n_rows, n = y.shape
    widest = edges[edges.size - 1]
    reach = max(n_lag, 1)
    for r in range(n_rows):
        row = y[r]
        out = rows_to[r]
        _nan_prefix(row, nan_before)
        for i in range(max(lo, reach), min(hi, n - reach)):
            y0 = row[i]
            above = abs(y0 - level)  # level test first: cheap, and rarely passed
            below = abs(y0 + level)
            if above <= widest and row[i - 1] < row[i] and row[i] >= row[i + 1]:
                sign = 1.0
                dist = above
            elif both_signs and below <= widest and row[i - 1] > row[i] and row[i] <= row[i + 1]:
                sign = -1.0
                dist = below
            else:
                continue
            w = _window(edges, dist)  # smallest window holding the trigger
            if nan_before[i + n_lag + 1] != nan_before[i - n_lag]:
                skipped[out, w] += 1
                continue
            counts[out, w] += 1
            seg = sums[out, w]
            base = i - n_lag
            for k in range(2 * n_lag + 1):
                seg[k] += sign * row[base + k]
    for out in range(sums.shape[0]):
        _close_windows(sums[out], counts[out], skipped[out])


@njit(nogil=True, cache=True)
def _crossing_kernel(y, rows_to, velocity, edges, n_lag, inv_dt, both_signs, lo, hi, sums, counts, skipped, nan_before):
    """One pass of the zero-crossing trigger over ``y[row, time]`` for all windows ``edges``.

    Row ``r`` adds its segments, counts and skips into output row ``rows_to[r]``;
    ``nan_before`` as in :func:`_extremum_kernel`.
    """
    n_rows, n = y.shape
    widest = edges[edges.size - 1]
    for r in range(n_rows):
        row = y[r]
        out = rows_to[r]
        _nan_prefix(row, nan_before)
        for i in range(max(lo, n_lag, 2), min(hi, n - n_lag - 1)):
            y0 = row[i]
            y1 = row[i + 1]
            if y0 < 0.0 and y1 >= 0.0:
                sign = 1.0
            elif both_signs and y0 > 0.0 and y1 <= 0.0:
                sign = -1.0
            else:
                continue
            frac = y0 / (y0 - y1)  # chord root: crossing at t_i + frac dt
            ym1 = row[i - 1]
            ym2 = row[i - 2]
            # derivative at frac of the parabola through the samples i-2, i-1, i
            slope = 0.5 * (3.0 * y0 - 4.0 * ym1 + ym2) + (y0 - 2.0 * ym1 + ym2) * frac
            dist = abs(sign * slope * inv_dt - velocity)
            if not dist <= widest:
                continue
            w = _window(edges, dist)
            if nan_before[i + n_lag + 2] != nan_before[i - n_lag]:
                skipped[out, w] += 1
                continue
            counts[out, w] += 1
            seg = sums[out, w]
            base = i - n_lag
            _add_interpolated(seg, row, base, n_lag, sign, frac)  # lag 0 stays exactly 0
    for out in range(sums.shape[0]):
        _close_windows(sums[out], counts[out], skipped[out])


def _run(trigger, y, target, half_widths, n_lag, dt, both_signs, owned, rows_to):
    """Shape checks and output allocation around a numba kernel; ``time`` is the last axis.

    Without ``rows_to`` every series has its own output row (shape ``y.shape[:-1]``);
    with it, series ``j`` adds into row ``rows_to[j]`` of ``rows_to.max() + 1`` rows.
    """
    y = np.asarray(y)
    if y.ndim == 0:
        raise ValueError("the record must have a time axis (the last axis)")
    edges = np.atleast_1d(np.asarray(half_widths, dtype=np.float64))
    if edges.ndim != 1 or edges.size == 0 or not np.all(np.isfinite(edges) & (edges >= 0)) or np.any(np.diff(edges) < 0):
        raise checks.InputError(
            f"window half-widths must be a non-empty, finite, non-negative, ascending sequence; got {half_widths!r}"
        )
    n_lag = checks.integer(n_lag, "n_lag", 0)
    checks.finite(target, "the trigger level" if trigger == "a" else "the trigger velocity")
    checks.positive(dt, "dt")
    lead_shape, n = y.shape[:-1], y.shape[-1]
    rows = int(np.prod(lead_shape, dtype=np.int64))
    if rows_to is None:
        out_shape = lead_shape
        rows_to = np.arange(rows, dtype=np.int64)
    else:
        rows_to = np.asarray(rows_to)
        if rows_to.shape != lead_shape or rows_to.dtype.kind not in "iu" or (rows_to.size and rows_to.min() < 0):
            raise checks.InputError(
                f"rows_to must hold a non-negative integer output row for each series, shape {lead_shape}; "
                f"got shape {rows_to.shape}, dtype {rows_to.dtype}"
            )
        out_shape = (int(rows_to.max()) + 1 if rows_to.size else 0,)
        rows_to = rows_to.reshape(rows).astype(np.int64)
    n_out = int(np.prod(out_shape, dtype=np.int64))
    lo, hi = (0, n) if owned is None else (int(owned[0]), int(owned[1]))
    sums = np.zeros((n_out, edges.size, 2 * n_lag + 1))
    counts = np.zeros((n_out, edges.size), np.int64)
    skipped = np.zeros((n_out, edges.size), np.int64)
    nan_before = np.empty(n + 1, np.int64)  # allocated here: the kernels then compile no np.empty
    y = np.ascontiguousarray(y.reshape(rows, n), dtype=np.float64)  # one compiled type: float32 converts exactly
    if trigger == "a":
        _extremum_kernel(y, rows_to, float(target), edges, n_lag, bool(both_signs), lo, hi, sums, counts, skipped, nan_before)
    else:
        _crossing_kernel(
            y, rows_to, float(target), edges, n_lag, 1.0 / float(dt), bool(both_signs), lo, hi, sums, counts, skipped,
            nan_before,
        )
    return SignatureSums(
        sums.reshape(out_shape + sums.shape[1:]),
        counts.reshape(out_shape + counts.shape[1:]),
        skipped.reshape(out_shape + skipped.shape[1:]),
    )


def extremum_sums(y, level, half_widths, n_lag, *, both_signs=True, owned=None, rows_to=None) -> SignatureSums:
    """Sums and counts of the extremum-triggered signature ``D_a`` (eq. 19, first line).

    Parameters
    ----------
    y : array (..., time), float32 or float64 (computed in float64)
        Records, time on the last axis.
    level : float
        Trigger level ``a``, in the units of ``y``.
    half_widths : sequence of float, ascending
        Window half-widths ``da_1 <= ... <= da_W`` (units of ``y``); a trigger is in window
        ``w`` when ``|y(t_i) - a| <= da_w``.
    n_lag : int
        ``L``: segments are ``y[i-L .. i+L]``.
    both_signs : bool
        Also use local minima within ``[-a - da, -a + da]``, sign-flipped.
    owned : (int, int), optional
        Only samples ``lo <= i < hi`` may be triggers (time chunks with overlap); the
        segment may reach outside ``[lo, hi)``. Default: the whole record.
    rows_to : int array of shape ``y.shape[:-1]``, optional
        Output row of each series: the sums and counts of series ``j`` are added into row
        ``rows_to[j]`` inside the kernel (group sums without per-series arrays; exact,
        since signatures pool by adding sums and counts). Default: one row per series.

    Returns
    -------
    SignatureSums
        ``sum (..., W, 2L+1)``, ``count (..., W)``, ``skipped (..., W)``, cumulative over
        the windows, with ``...`` = ``y.shape[:-1]``, or ``rows_to.max() + 1`` rows when
        ``rows_to`` is given. The signature is ``sum / count`` (:func:`mean_signature`).
    """
    return _run("a", y, level, half_widths, n_lag, 1.0, both_signs, owned, rows_to)


def crossing_sums(y, velocity, half_widths, n_lag, dt, *, both_signs=True, owned=None, rows_to=None) -> SignatureSums:
    """Sums and counts of the zero-crossing signature ``D_v`` (eq. 19, second line).

    ``velocity`` is the trigger velocity ``v`` and ``half_widths`` the ascending ``dv_w``,
    in units of ``y`` per second; ``v`` is compared with the *pre-impact* velocity
    (module docstring), estimated from the three samples before the crossing. ``dt`` is
    the sampling interval in s. The segment is interpolated at ``t_c + k dt``,
    ``k = -L .. L``. Other parameters and the result as in :func:`extremum_sums`.
    """
    return _run("v", y, velocity, half_widths, n_lag, dt, both_signs, owned, rows_to)


# --------------------------------------------------------------------------- helpers


def lag_samples(n_periods: float, level: float, g: float, dt: float) -> int:
    """Half-length ``L`` of the lag axis in samples: ``round(n_periods T(a) / dt)``.

    ``T(a) = 4 sqrt(2 a / g)`` is the free-rocking period at amplitude ``a`` of the
    simplified model (eq. 5); ``level`` ``a`` in rad, ``g = nu^2 theta_cr`` in rad/s^2,
    ``dt`` in s.
    """
    checks.positive(n_periods, "n_periods", allow_zero=True)
    checks.positive(level, "level", allow_zero=True)
    checks.positive(g, "g")
    checks.positive(dt, "dt")
    lags = n_periods * float(period_from_g(level, g)) / dt
    if not lags < 2**62:
        raise checks.InputError(
            f"the lag range of n_periods = {n_periods} periods at level {level} and g = {g} is {lags:.3g} samples of "
            f"dt = {dt}; raise g or dt, or lower n_periods."
        )
    return int(np.rint(lags))


def sums_nbytes(n_series: int, n_windows: int, n_lag: int) -> float:
    """Bytes of the per-series sums of both triggers: ``n_series x 2 x n_windows x (2 n_lag + 1)`` float64."""
    return 8.0 * n_series * 2 * n_windows * (2 * n_lag + 1)


def check_lag_range(n_lag: int, n_time: int, n_series: int, n_windows: int, what: str, fix: str) -> None:
    """Refuse, before any work, a lag range with no room in the record or beyond the memory.

    For the edges (command line, files): a segment spans ``2 n_lag + 1`` samples and must
    lie inside the record of ``n_time`` samples, and the sums (:func:`sums_nbytes`) must
    fit in memory. ``what`` names the settings as the user wrote them, ``fix`` the remedy.
    (The kernels themselves accept short records: they count no trigger.)
    """
    width = 2 * int(n_lag) + 1
    if width > n_time:
        raise checks.InputError(
            f"{what} asks for segments of 2L+1 = {width} samples, longer than the record of {n_time} samples, "
            f"so no trigger fits; {fix}."
        )
    checks.memory(sums_nbytes(n_series, n_windows, n_lag), what, fix)


def free_response(signature):
    """Free-response estimate from a two-sided signature: its even part (paper §4, eq. 20).

    ``(D(tau) + D(-tau)) / 2`` for ``tau >= 0``, along the last axis: ``2L + 1`` lags in,
    ``L + 1`` out. Taking the even part imposes the zero-velocity initial condition of
    ``g(a, tau) = G(a, 0, tau)``.
    """
    signature = np.asarray(signature)
    n_lag = (signature.shape[-1] - 1) // 2
    return 0.5 * (signature[..., n_lag:] + signature[..., n_lag::-1])


def mean_signature(sums, counts, *, triggers=TRIGGERS, windows=None, warn=True):
    """Signature ``sum / count`` (eq. 8); NaN where the count is 0.

    ``sums (..., trigger, window, lag)`` and ``counts (..., trigger, window)``. A
    :class:`NoTriggerWarning` names every (trigger, window) that holds no trigger in any
    of the series given (so a cube warns only for windows that are empty everywhere);
    ``warn=False``: none, for a caller that reads the empty windows off ``counts`` (the
    analysis, which runs in threads, where a ``warnings.catch_warnings`` is not safe: its
    filters are the process's).
    """
    sums = np.asarray(sums, dtype=np.float64)
    counts = np.asarray(counts)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = sums / counts[..., None]
    out[counts == 0] = np.nan
    if warn and counts.size:
        empty = np.all(counts.reshape(-1, *counts.shape[-2:]) == 0, axis=0)
        windows = np.arange(counts.shape[-1]) if windows is None else np.asarray(windows)
        for t, w in zip(*np.nonzero(empty)):
            kind = "D_a (extremum)" if triggers[t] == "a" else "D_v (zero crossing)"
            warnings.warn(
                f"no {kind} trigger in window {windows[w]:g}: its signature is NaN; lower "
                "the trigger level, widen the window or use a longer record (or pool more series)",
                NoTriggerWarning,
                stacklevel=2,
            )
    return out


def trigger_levels(sigma_y: float, sigma_ydot: float, *, level: float, windows, window_max: float, v_level: float, dv_max: float) -> dict:
    """The triggers of eq. 19 from the response's scales: ``a``, ``a_widths``, ``v``, ``v_widths``.

    ``a = level * sigma_y`` (rad; the paper's ``a = 2 sigma_Y``) with half-widths
    ``da = windows * window_max * a``; ``v = v_level * sigma_ydot`` (rad/s) with
    ``dv = windows * dv_max * v``. ``windows`` relative, ascending in ``(0, 1]``.
    """
    windows = np.asarray(windows, dtype=np.float64)
    a = level * sigma_y
    v = v_level * sigma_ydot
    return {"a": a, "a_widths": windows * window_max * a, "v": v, "v_widths": windows * dv_max * v}


def trigger_sums(y, *, a, a_widths, v, v_widths, n_lag, dt, both_signs, owned=None, groups=None):
    """Both triggers (eq. 19) on records ``y[..., time]``: sums ``(..., 2, W, 2L+1)``, count
    and skipped ``(..., 2, W)``, triggers in the order of :data:`TRIGGERS`.

    ``a``, ``a_widths``, ``v``, ``v_widths`` as :func:`trigger_levels` gives them; the rest
    as in :func:`extremum_sums` and :func:`crossing_sums`.

    ``groups = (inverse, n_groups)`` sums the series along the first axis within groups
    inside the kernels (series ``j`` into group ``inverse[j]``, ``0 <= inverse < n_groups``):
    the leading shape ``y.shape[:-1]`` becomes ``(n_groups, *y.shape[1:-1])``.
    """
    lead = y.shape[:-1]
    rows_to = None
    if groups is not None:
        inverse, n_groups = groups
        lead = (n_groups, *y.shape[1:-1])
        n_rest = int(np.prod(lead[1:], dtype=np.int64))
        rows_to = (np.asarray(inverse, dtype=np.int64)[:, None] * n_rest + np.arange(n_rest)).reshape(y.shape[:-1])
    sa = extremum_sums(y, a, a_widths, n_lag, both_signs=both_signs, owned=owned, rows_to=rows_to)
    sv = crossing_sums(y, v, v_widths, n_lag, dt, both_signs=both_signs, owned=owned, rows_to=rows_to)
    return (
        np.stack([sa.sum, sv.sum], axis=-3).reshape(lead + (2, *sa.sum.shape[-2:])),
        np.stack([sa.count, sv.count], axis=-2).reshape(lead + (2, sa.count.shape[-1])),
        np.stack([sa.skipped, sv.skipped], axis=-2).reshape(lead + (2, sa.count.shape[-1])),
    )


# --------------------------------------------------------------------------- xarray / Dask


def _cube_packed(x, groups=None, **kw):
    """:func:`trigger_sums` on a Dask array, possibly chunked along time (the last axis), packed.

    Each time chunk is extended by ``depth`` samples from its neighbours (none past the
    record's ends), counts only the triggers at its own samples, and the per-chunk sums
    are added. ``depth`` covers the segment and the incoming-velocity stencil.
    ``groups`` holds one ``(inverse, n_groups)`` of :func:`trigger_sums` per chunk of the
    first axis: each block then sums its series into its own groups. Returns one float64
    array ``(..., 2, W, 2L+3)``: the sums, then count and skipped (exact below 2**53;
    :func:`_unpack` splits it).
    """
    import dask.array as da  # only a Dask input comes here: NumPy callers never load dask.array

    n_lag, n_win = kw["n_lag"], len(kw["a_widths"])
    axis = x.ndim - 1
    depth = max(n_lag, 2) + 1
    if x.shape[axis] <= 2 * depth:  # too short to split: no segment fits anyway
        x = x.rechunk({axis: -1})
    else:
        x = x.rechunk({axis: da.overlap.ensure_minimum_chunksize(depth, x.chunks[axis])})
    n_chunks = len(x.chunks[axis])
    extended = da.overlap.overlap(x, depth={axis: depth}, boundary={axis: "none"}) if n_chunks > 1 else x
    width = 2 * n_lag + 1

    def block(b, block_info=None):
        where = block_info[0]["chunk-location"]
        loc = where[axis]
        lo = 0 if loc == 0 else depth
        hi = b.shape[-1] - (0 if loc == n_chunks - 1 else depth)
        s, c, k = trigger_sums(b, owned=(lo, hi), groups=None if groups is None else groups[where[0]], **kw)
        packed = np.concatenate([s, c[..., None].astype(np.float64), k[..., None].astype(np.float64)], axis=-1)
        return packed[..., None, :, :, :]

    lead_chunks = x.chunks[:axis] if groups is None else (tuple(n for _, n in groups), *x.chunks[1:axis])
    per_chunk = extended.map_blocks(
        block,
        new_axis=[axis + 1, axis + 2, axis + 3],
        chunks=lead_chunks + ((1,) * n_chunks, (2,), (n_win,), (width + 2,)),
        dtype=np.float64,
        meta=np.empty((0,) * (axis + 4)),
    )
    # one time chunk: nothing to add (a Dask sum would add two layers of tasks)
    return per_chunk.sum(axis=axis) if n_chunks > 1 else per_chunk[(slice(None),) * axis + (0,)]


def _unpack(packed):
    """``(sums, count, skipped)`` from a packed array of :func:`_cube_packed`."""
    width = packed.shape[-1] - 2
    return packed[..., :width], packed[..., width].astype(np.int64), packed[..., width + 1].astype(np.int64)


def _cube_time_chunked(x, **kw):
    """:func:`trigger_sums` on a Dask array chunked along time: :func:`_cube_packed`, unpacked."""
    return _unpack(_cube_packed(x, **kw))


def _group_sums(theta: xr.DataArray, group: xr.DataArray, kw: dict):
    """``signature_sum``, ``count`` and ``skipped`` of ``theta``'s series summed within ``group``, and their labels.

    The kernels add each series into its group (``rows_to``), so no per-series sums are
    made. Each block of series -- the whole array, or each Dask chunk along the group's
    dimension -- sums into the groups it holds, in label order. A group that straddles
    chunks has a part in each of them (and labels not sorted along the dimension put the
    parts out of order): the packed parts are then added by label, once for the three
    variables. Exact up to the order of the additions, since signatures pool by adding
    sums and counts. Returns the three DataArrays, ``group`` first as with xarray's
    groupby, and the sorted labels along ``group``.
    """
    import xarray as xr

    dim = group.dims[0] if group.ndim == 1 else None
    if dim is None or dim == "time" or dim not in theta.dims:
        raise ValueError(f"group must be one-dimensional along a dimension of theta other than time; it has {group.dims}")
    theta, group = xr.align(theta, group, join="exact", copy=False)
    labels = np.asarray(group.values)
    x = theta.transpose(dim, ..., "time")
    sizes = (labels.size,) if x.chunks is None else x.chunks[0]
    bounds = np.cumsum((0, *sizes))
    parts = [np.unique(labels[lo:hi], return_inverse=True) for lo, hi in zip(bounds[:-1], bounds[1:])]
    groups = [(inverse, unique.size) for unique, inverse in parts]
    dims = ("group", *x.dims[1:-1])
    if x.chunks is None:  # one block: its groups are all the groups, sorted
        out = trigger_sums(x.values, groups=groups[0], **kw)
    else:
        part_labels = np.concatenate([unique for unique, _ in parts])
        packed = xr.DataArray(
            _cube_packed(x.data, groups=groups, **kw), dims=dims + ("trigger", "window", "packed"), coords={"group": part_labels}
        )
        if np.any(np.diff(part_labels) <= 0):  # parts of one group in several chunks, or unsorted labels
            packed = packed.groupby("group").sum().transpose(*packed.dims)
        out = _unpack(packed.data)
    coords = {name: coord for name, coord in x.coords.items() if not {dim, "time"} & set(coord.dims)}
    core = (("trigger", "window", "lag"), ("trigger", "window"), ("trigger", "window"))
    arrays = tuple(xr.DataArray(data, dims=dims + extra, coords=coords) for data, extra in zip(out, core))
    return arrays, np.unique(labels)


def _sampling_interval(theta: xr.DataArray) -> float:
    """``dt`` in s from ``theta.attrs['dt']`` or a uniform, increasing ``time`` coordinate
    (:func:`rockdec.timeaxis.sampling_step`)."""
    if "dt" in theta.attrs:
        return float(theta.attrs["dt"])
    if "time" in theta.coords:
        return sampling_step(theta["time"].values, "theta's time coordinate")
    raise ValueError("cannot tell the sampling interval: give theta an attribute 'dt' (s) or a uniform 'time' coordinate")


def _finish(sums: xr.Dataset) -> xr.Dataset:
    """Add ``signature`` and ``free_response`` to a Dataset of sums and counts."""
    import xarray as xr

    units = sums["signature_sum"].attrs.get("units", "rad")
    signature = xr.apply_ufunc(
        mean_signature,
        sums["signature_sum"],
        sums["count"],
        input_core_dims=[["trigger", "window", "lag"], ["trigger", "window"]],
        output_core_dims=[["trigger", "window", "lag"]],
        kwargs={"triggers": tuple(sums["trigger"].values), "windows": sums["window"].values},
        dask="parallelized",
        output_dtypes=[np.float64],
    )
    signature.attrs = {"units": units, "long_name": "RDD signature: mean segment over the triggers (eqs. 8, 19)"}
    n_lag = (sums.sizes["lag"] - 1) // 2
    even = xr.apply_ufunc(
        free_response,
        signature.sel(trigger="a", drop=True),
        input_core_dims=[["lag"]],
        output_core_dims=[["lag_pos"]],
        dask="parallelized",
        dask_gufunc_kwargs={"output_sizes": {"lag_pos": n_lag + 1}},
        output_dtypes=[np.float64],
    )
    even.attrs = {"units": units, "long_name": "free-response estimate: even part of D_a (eq. 20)"}
    out = sums.assign(signature=signature, free_response=even)
    return out.assign_coords(lag_pos=("lag_pos", sums["lag"].values[n_lag:], {"units": "s", "long_name": "time lag tau >= 0"}))


def pool(ds: xr.Dataset, dim, by=None, finish: bool = True) -> xr.Dataset:
    """Pool a signature cube over ``dim`` (a name or a list): sum of sums / sum of counts.

    Exact: the pooled signature is the mean over the union of the triggers of the pooled
    series (docs/method.md §4.4). NaN (with a :class:`NoTriggerWarning`) where the pooled count is 0.
    ``by`` (integer labels along the one dimension ``dim``, NumPy) pools within each label
    instead: the result has a ``group`` dimension, one per label >= 0 in ascending order;
    entries labelled -1 are left out. ``finish=False`` (with ``by``): the pooled sums and
    counts only, without ``signature`` and ``free_response``, for a caller that reads
    nothing else (:func:`rockdec.rdd.estimators.window_cube`).
    """
    import xarray as xr

    sums = ds[list(SUM_VARS)]
    if by is None:
        return _finish(sums.sum(dim, keep_attrs=True))
    labels, reduce = _label_reduction(np.asarray(by))
    out = {}
    for name, var in sums.data_vars.items():
        values = reduce(var.values, var.get_axis_num(dim))
        out[name] = (tuple("group" if d == dim else d for d in var.dims), values, var.attrs)
    coords = {name: c for name, c in sums.coords.items() if dim not in c.dims}
    coords["group"] = ("group", labels, {"long_name": "group of series pooled into one signature"})
    pooled = xr.Dataset(out, coords=coords, attrs=ds.attrs)
    return _finish(pooled) if finish else pooled


def _label_reduction(by: np.ndarray):
    """The labels >= 0 of ``by`` in ascending order, and ``reduce(values, axis)``: the sum of
    the entries of each label along ``axis``, in that order, entries labelled -1 left out.

    Each label's entries are added in their order along the axis, so the sums do not depend
    on how they are formed. When every label's entries are one contiguous run (a pass's
    units, :func:`rockdec.pipeline.replicates.pass_units`), each run is summed where it lies
    into its row of the result; otherwise each label's entries are first gathered together
    (a copy of the kept entries).
    """
    runs = np.flatnonzero(np.r_[True, by[1:] != by[:-1]])
    ends = np.r_[runs[1:], by.size]
    kept = np.flatnonzero(by[runs] >= 0)
    kept = kept[np.argsort(by[runs][kept])]
    labels = by[runs][kept]
    if np.any(labels[1:] == labels[:-1]):  # a label in several runs
        entries = np.flatnonzero(by >= 0)
        order = entries[np.argsort(by[entries], kind="stable")]  # each label's entries together, in their order
        starts = np.flatnonzero(np.r_[True, by[order][1:] != by[order][:-1]])
        return by[order][starts], lambda values, axis: np.add.reduceat(np.take(values, order, axis=axis), starts, axis=axis)
    first, last = runs[kept], ends[kept]

    def reduce(values, axis):
        if np.all(last - first == 1):
            return np.take(values, first, axis=axis)
        source = np.moveaxis(values, axis, 0)
        out = np.empty((labels.size, *source.shape[1:]), dtype=source.dtype)
        for row, (lo, hi) in enumerate(zip(first, last)):
            np.add.reduceat(source[lo:hi], [0], axis=0, out=out[row : row + 1])  # in order, as reduceat sums
        return np.moveaxis(out, 0, axis)

    return labels, reduce


def signature_cube(
    theta: xr.DataArray,
    *,
    sigma_y: float,
    sigma_ydot: float,
    level: float = 2.0,
    windows=DEFAULT_WINDOWS,
    window_max: float = 0.28,
    v_level: float = 1.0,
    dv_max: float = 0.28,
    n_periods: float = 2.5,
    g: float | None = None,
    n_lag: int | None = None,
    both_signs: bool = True,
    group: xr.DataArray | None = None,
) -> xr.Dataset:
    """Per-series RDD signatures ``D_a`` and ``D_v`` (eq. 19) of ``theta(seed, time)``.

    Parameters
    ----------
    theta : DataArray with a ``time`` dimension (typically ``(seed, time)``)
        Rocking angle (rad, or ``theta.attrs['units']``); NumPy or Dask, chunked over
        seed and/or time. ``dt`` (s) from ``theta.attrs['dt']`` or the ``time`` coordinate.
    sigma_y, sigma_ydot : float
        One standard deviation of the response and of its velocity for *all* series:
        a per-series level would mix rocking periods in a pooled signature (docs/method.md §4.4).
    level : float
        ``D_a`` trigger level ``a = level * sigma_y`` (paper: ``a = 2 sigma_Y``).
    windows : sequence of float, ascending in ``(0, 1]``
        Window half-widths relative to the largest: ``da = windows * window_max * a``,
        ``dv = windows * dv_max * v``.
    window_max : float
        Largest ``D_a`` half-width relative to ``a`` (paper: ``0.28``).
    v_level : float
        ``D_v`` trigger velocity ``v = v_level * sigma_ydot`` (pre-impact velocity).
    dv_max : float
        Largest ``D_v`` half-width relative to ``v``. Default ``0.28``, the same relative
        window as ``D_a``, so that both triggers make the same bias/variance trade-off;
        it must stay below 1 so that no window reaches velocities of the wrong sign.
    n_periods, g : float
        Lag range: ``L = lag_samples(n_periods, a, g, dt)``, ``n_periods`` rocking periods
        at amplitude ``a`` (eq. 5; about 2.5 reproduces the paper's ``e_g``), ``g`` in
        rad/s^2.
    n_lag : int, optional
        ``L`` in samples, instead of ``n_periods`` and ``g``.
    both_signs : bool
        Also use the mirrored triggers (minima at ``-a``, downward crossings), sign-flipped.
    group : DataArray of int labels along one dimension of ``theta``, optional
        Sum the sums and counts of the series within groups; the output then has a
        ``group`` dimension (first, labels sorted) instead of that one. The kernels add
        each series into its group, per block of series; groups spread over several Dask
        chunks get one part from each, added by label. The labels must be in memory (NumPy).

    Returns
    -------
    Dataset
        ``signature_sum(..., trigger, window, lag)``, ``count`` and ``skipped``
        ``(..., trigger, window)`` (int64), ``signature = sum / count`` (NaN where the
        count is 0) and ``free_response(..., window, lag_pos)`` (even part of ``D_a``).
        Coordinates ``trigger = ["a", "v"]``, ``window`` (relative), ``da``/``dv``
        (absolute half-widths), ``lag`` and ``lag_pos`` (s). Global attributes hold the
        settings: ``level``, ``sigma_y``, ``sigma_ydot``, ``a`` and ``v`` (absolute trigger
        level and velocity), ``window_max`` and ``dv_max`` (relative, as given),
        ``da_max`` (absolute, ``window_max * a``), ``both_signs`` (0/1), ``n_lag`` (with
        ``n_periods`` and ``g`` when they set it), ``dt``.
        Lazy when ``theta`` is: building it computes nothing.

    A :class:`NoTriggerWarning` names each (trigger, window) without a trigger in any
    series (or group) of the cube -- for a lazy cube, of a Dask chunk, when it is
    computed. A window empty in some series only is normal (see ``count``) and not warned
    about; :func:`pool` warns for windows still empty after pooling.
    """
    import xarray as xr

    if "time" not in theta.dims:
        raise ValueError(f"theta must have a 'time' dimension; it has {theta.dims}")
    dt = _sampling_interval(theta)
    windows = np.asarray(windows, dtype=np.float64)
    levels = trigger_levels(sigma_y, sigma_ydot, level=level, windows=windows, window_max=window_max, v_level=v_level, dv_max=dv_max)
    a, v = levels["a"], levels["v"]
    lag_settings = {}
    if n_lag is None:
        if g is None:
            raise ValueError("give g (rad/s^2) to size the lag range from n_periods, or n_lag directly")
        n_lag = lag_samples(n_periods, a, g, dt)
        lag_settings = {"n_periods": float(n_periods), "g": float(g)}
    # series summed at once: the largest Dask block, or the whole array
    sizes = {d: max(c) for d, c in theta.chunksizes.items()} if theta.chunks is not None else dict(theta.sizes)
    block_rows = int(np.prod([n for d, n in sizes.items() if d != "time"]))
    checks.memory(
        sums_nbytes(block_rows, windows.size, n_lag),
        f"the lag range of {n_lag} samples a side ({lag_settings or 'n_lag'})",
        "raise g or lower n_periods (or n_lag), or use smaller chunks of series",
    )
    kw = {
        **levels,
        "n_lag": int(n_lag),
        "dt": dt,
        "both_signs": both_signs,
    }
    width = 2 * kw["n_lag"] + 1
    core_out = [["trigger", "window", "lag"], ["trigger", "window"], ["trigger", "window"]]
    dtypes = [np.float64, np.int64, np.int64]
    chunks = theta.chunksizes.get("time") if theta.chunks is not None else None
    if group is not None:
        (s, c, k), labels = _group_sums(theta, group, kw)
    else:
        if chunks is not None and len(chunks) > 1:
            ufunc_kw = {"dask": "allowed"}
            func = _cube_time_chunked
        else:
            ufunc_kw = {
                "dask": "parallelized",
                "dask_gufunc_kwargs": {"output_sizes": {"trigger": 2, "window": windows.size, "lag": width}},
                "output_dtypes": dtypes,
            }
            func = trigger_sums
        s, c, k = xr.apply_ufunc(
            func, theta, input_core_dims=[["time"]], output_core_dims=core_out, kwargs=kw, keep_attrs=False, **ufunc_kw
        )
    units = theta.attrs.get("units", "rad")
    vel_units = f"{units} s-1"
    lag = np.arange(-kw["n_lag"], kw["n_lag"] + 1) * dt
    sums = xr.Dataset(
        {
            "signature_sum": s.assign_attrs(units=units, long_name="sum of the trigger segments (numerator of eq. 8)"),
            "count": c.assign_attrs(units="1", long_name="number of triggers averaged"),
            "skipped": k.assign_attrs(units="1", long_name="triggers left out because their segment holds NaN"),
        },
        coords={
            "trigger": ("trigger", list(TRIGGERS), {"long_name": "trigger: a = extremum at level a, v = zero crossing at velocity v (eq. 19)"}),
            "window": ("window", windows, {"units": "1", "long_name": "window half-width relative to the largest (da/da_max, dv/dv_max)"}),
            "da": ("window", kw["a_widths"], {"units": units, "long_name": "D_a window half-width"}),
            "dv": ("window", kw["v_widths"], {"units": vel_units, "long_name": "D_v window half-width (pre-impact velocity)"}),
            "lag": ("lag", lag, {"units": "s", "long_name": "time lag tau"}),
        },
    )
    if group is not None:
        sums = sums.assign_coords(group=labels)
        sums["group"].attrs = {**group.attrs, "long_name": "group of series pooled into one signature"}
    sums.attrs = {
        "level": float(level),
        "sigma_y": float(sigma_y),
        "sigma_ydot": float(sigma_ydot),
        "a": float(a),
        "v": float(v),
        "v_level": float(v_level),
        "window_max": float(window_max),
        "da_max": float(window_max * a),
        "dv_max": float(dv_max),
        "both_signs": int(bool(both_signs)),
        "n_lag": int(kw["n_lag"]),
        **lag_settings,
        "dt": float(dt),
        "history": f"signature_cube (rockdec {__version__}): Random Decrement signatures D_a, D_v (eq. 19)",
    }
    return _finish(sums)

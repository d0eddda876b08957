"""A record's own model, measured from the record: sensor noise, load colour, drift, a filter.

:func:`measure` reads what the paper's idealised record lacks, each with a delete-one-block
jackknife error (:data:`JACKKNIFE_BLOCKS`), into the :class:`MeasuredModel` a calibration
simulates. Between impacts the simplified model (eq. 4) moves on parabolas (eqs. 21-24), so
the kept second differences (:func:`second_differences`) are
``d_k = p_k dt - g dt^2 sgn(y[k])``: their side means give ``g``, their autocorrelation
``r(m) = A alpha^m + (1 - A) h(m)/6`` (:func:`mixed_autocovariance`) and structure function
``S(L) = sigma_p^2 dt^2 V_L(alpha) + 6 sigma_n^2`` (:func:`fit_structure`) the sensor noise
``sigma_n`` and the load's pole ``alpha``, its corner ``f_c = -ln(alpha)/(2 pi dt)`` in units
of ``1/T(sigma_Y)`` (eq. 5); the noise-free shape ratio ``Q`` (:func:`shape_ratio`,
:func:`pole_of_shape`) reads the pole beneath noise; von Neumann's ratio of block means the
drift; :func:`rolloff` the spectral slope that shows a low-pass filter after the block.

Explanation: docs/explanation/method/record-model.md; the constants' evidence:
docs/explanation/constants.md; how well it reads: :mod:`rockdec.studies.record_measure_study`,
``benchmarks/colour_detection.py``, ``benchmarks/filter_study.py``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rockdec import validate as checks
from rockdec.physics.models import period_from_g
from rockdec.record import diagnostics

__all__ = [
    "MAX_LAG", "MAX_POLE", "MeasuredModel", "NOISE_FLOOR", "Quantity", "ROLLOFF_FLOOR", "Rolloff",
    "SHAPE_SPANS", "SPANS", "WHITE_SHAPE", "fit_structure", "measure", "mixed_autocovariance",
    "pole_of_shape", "rolloff", "second_differences", "shape_of_pole", "shape_ratio", "span_differences",
    "structure_model",
]

#: Spans ``L`` of the structure function ``S(L)`` that the fit uses.
SPANS = (1, 2, 3, 4, 6, 8)

#: Lags of the second differences' autocovariance that ``S(L)`` needs, ``0..2 max(L) - 2``.
MAX_LAG = 2 * max(SPANS) - 2

#: Lags ``0..DIRECT_LAGS`` of the autocovariance fitted directly beside ``S(L)``.
DIRECT_LAGS = 8

#: Consecutive blocks of the delete-one-block jackknife (over all records together).
JACKKNIFE_BLOCKS = 20

#: Blocks per record of the drift statistic and of the detrending, each of at least
#: ``DRIFT_BLOCK_MIN`` samples (fewer blocks for short records; none below 4).
DRIFT_BLOCKS, DRIFT_BLOCK_MIN = 20, 1000

#: Standard errors above zero at which noise (``1 - A``) or colour (``alpha``) is detected.
DETECT_Z = 4.0

#: Smallest ``sigma_n / sigma_Y`` called noise, whatever its z: above the trace a low-pass
#: load leaves, below the smallest noise studied (docs/explanation/constants.md).
NOISE_FLOOR = 0.002

#: Standard errors by which the shape ratio ``Q`` (:func:`shape_ratio`) must exceed a white
#: load's to be called colour when noise is detected: above its z on noisy white records of
#: the coverage study's design (``benchmarks/colour_detection.py``; docs/explanation/constants.md).
COLOUR_Z_NOISY = 3.0

#: ``drift_z`` above which drift is detected (one-sided).
DRIFT_Z = 3.0

#: The MA(2) autocovariance of second-differenced white noise, ``h(0), h(1), h(2)``.
NOISE_PATTERN = (6.0, -4.0, 1.0)

#: Steps between a kept triple's middle sample and the guard samples that choose it.
GUARD = 2

#: The margin of the guard samples is the larger of ``MARGIN_G g dt^2`` and
#: ``MARGIN_NOISE sigma_n``, both measured on the previous pass; passes after the first
#: without a margin.
MARGIN_G, MARGIN_NOISE, MARGIN_PASSES = 8.0, 3.0, 2

#: Fewest kept triples for a measurement.
MIN_TRIPLES = 1000

#: Largest pole of the fit's search (a corner of ``1e-4`` of the sampling frequency).
MAX_POLE = 1.0 - 1e-4


#: Octaves of the roll-off of the second differences' spectrum (:func:`rolloff`), in rocking frequencies ``1/T(sigma_Y)``
#: (eq. 5): above the block's own resonance, up to where a filter that moves ``e`` sits (a
#: zero-phase Butterworth at 20 rocking frequencies still does: ``benchmarks/filter_study.py``).
ROLLOFF_BANDS = ((5.0, 10.0), (7.0, 14.0), (10.0, 20.0), (14.0, 28.0))

#: A band of :data:`ROLLOFF_BANDS` is read only below this share of the samples per cycle
#: (0.9 of the Nyquist frequency), short of where the window's leakage from beyond it counts.
ROLLOFF_TOP = 0.45

#: Longest Welch segment of the roll-off (samples) and fewest Welch bins in a band.
ROLLOFF_SEGMENT, ROLLOFF_MIN_BINS = 1024, 4

#: A log-log slope of the second differences' spectrum that no unfiltered record reaches
#: (module docstring, "A filter after the block"; the steepest unfiltered records, at high
#: ``e`` under a low-pass load: ``benchmarks/filter_study.py``): a first-order filter adds
#: ``f^-2`` at most, so below it a filter of order two or more shows.
ROLLOFF_FLOOR = -3.0

#: Standard errors below :data:`ROLLOFF_FLOOR` at which the steepest band shows a filter;
#: evidence: its false alarms on unfiltered records, ``benchmarks/filter_study.py``.
ROLLOFF_Z = 3.0

#: Jackknife groups of Welch segments of :func:`rolloff`.
ROLLOFF_GROUPS = 10


def periodic_tukey(size: int, alpha: float = 0.25) -> np.ndarray:
    """The periodic (DFT-even) Tukey window of ``size`` samples with a taper of ``alpha``,
    as ``scipy.signal.windows.tukey(size, alpha, sym=False)`` computes it (``size`` > 1,
    0 < ``alpha`` < 1).

    Examples
    --------
    >>> periodic_tukey(8, 0.5).tolist()
    [0.0, 0.5, 1.0, 1.0, 1.0, 1.0, 1.0, 0.5]
    """
    m = size + 1
    n = np.arange(0, m, dtype=np.float64)
    width = int(math.floor(alpha * (m - 1) / 2.0))
    n1, n2, n3 = n[0 : width + 1], n[width + 1 : m - width - 1], n[m - width - 1 :]
    w1 = 0.5 * (1 + np.cos(np.pi * (-1 + 2.0 * n1 / alpha / (m - 1))))
    w3 = 0.5 * (1 + np.cos(np.pi * (-2.0 / alpha + 1 + 2.0 * n3 / alpha / (m - 1))))
    return np.concatenate((w1, np.ones(n2.shape), w3))[:-1]


def _periodograms(x: np.ndarray, size: int) -> np.ndarray:
    """``(frequency, segment)``: the one-sided density periodograms of ``x`` in segments of
    ``size`` samples overlapping by half, each less its mean and under
    :func:`periodic_tukey` of 0.25: the steps of ``scipy.signal.spectrogram(x,
    nperseg=size, noverlap=size // 2)`` in its order (the same floats), without the import
    of ``scipy.signal``, which takes longer than a warm estimate's analysis."""
    window = periodic_tukey(size)
    segments = np.lib.stride_tricks.sliding_window_view(x, size)[:: size - size // 2]
    segments = segments - np.mean(segments, -1, keepdims=True)
    spectra = np.fft.rfft(window * segments, n=size)
    spectra = np.conjugate(spectra) * spectra
    spectra *= 1.0 / (window * window).sum()
    spectra[..., 1:-1] *= 2
    return np.moveaxis(spectra.real, -1, -2)


def second_difference_spectra(records) -> tuple[np.ndarray, np.ndarray]:
    """``(frequency, spectra)``: the periodograms ``(segment, frequency)`` of the second
    differences of ``records`` (1-D arrays, NaN allowed) in segments overlapping by half,
    each less its mean and under a periodic Tukey window of 0.25 (:func:`_periodograms`,
    ``scipy.signal.spectrogram``'s defaults), each of :data:`ROLLOFF_SEGMENT` samples or, for
    shorter records, the power of two at or below an eighth of the longest (at least 16);
    frequency in cycles per sample. Segments holding a NaN where the window is not 0 are
    left out; records shorter than a segment give none, and none is made when the longest
    has fewer than 66 samples.

    Examples
    --------
    >>> import numpy as np
    >>> walk = np.cumsum(np.cumsum(np.random.default_rng(1).standard_normal(20_000)))
    >>> frequency, spectra = second_difference_spectra([walk])
    >>> spectra.shape, float(frequency[-1])
    ((38, 513), 0.5)
    """
    records = [np.asarray(y, dtype=np.float64).ravel() for y in records]
    longest = max((y.size - 2 for y in records), default=0)
    if longest < 64:
        return np.empty(0), np.empty((0, 0))
    size = int(min(ROLLOFF_SEGMENT, 2 ** int(math.log2(longest / 8)) if longest >= 128 else 16))
    frequency, spectra = np.empty(0), []
    for y in records:
        d = np.diff(y, 2)
        if d.size < size:
            continue
        frequency = np.fft.rfftfreq(size)
        s = _periodograms(np.nan_to_num(d), size)
        gaps = np.lib.stride_tricks.sliding_window_view(np.isnan(d), size)[:: size - size // 2]
        bad = (gaps & (periodic_tukey(size) > 0.0)).any(axis=1)
        spectra.append(s[:, ~bad].T)
    return (frequency, np.concatenate(spectra)) if spectra else (np.empty(0), np.empty((0, 0)))


def band_slopes(frequency: np.ndarray, power: np.ndarray, points_per_cycle: float) -> tuple[tuple, np.ndarray]:
    """``(bands, slopes)``: the least-squares slope of ``log power`` against ``log frequency``
    over each band of :data:`ROLLOFF_BANDS` that can be read at ``points_per_cycle`` samples
    per rocking cycle (below :data:`ROLLOFF_TOP` of them, with at least
    :data:`ROLLOFF_MIN_BINS` bins), for each row of ``power`` (``(..., frequency)``, slopes
    ``(..., band)``; NaN where a bin's power is not positive).

    Examples
    --------
    >>> import numpy as np
    >>> f = np.linspace(0.0, 0.5, 513)
    >>> bands, slopes = band_slopes(f, np.where(f > 0, f, 1.0) ** -3.0, 75.0)
    >>> bands[0], np.round(slopes, 6).tolist()
    ((5.0, 10.0), [-3.0, -3.0, -3.0, -3.0])
    """
    power = np.asarray(power, dtype=float)
    bands, slopes = [], []
    rocking = np.asarray(frequency, dtype=float) * points_per_cycle
    for lo, hi in ROLLOFF_BANDS if points_per_cycle > 0.0 else ():
        pick = (rocking >= lo) & (rocking <= hi)
        if hi > ROLLOFF_TOP * points_per_cycle or pick.sum() < ROLLOFF_MIN_BINS:
            continue
        x = np.log(rocking[pick])
        x = x - x.mean()
        with np.errstate(divide="ignore", invalid="ignore"):
            y = np.log(np.where(power[..., pick] > 0.0, power[..., pick], np.nan))
        bands.append((lo, hi))
        slopes.append(((y - y.mean(axis=-1, keepdims=True)) * x).sum(axis=-1) / (x * x).sum())
    return tuple(bands), (np.stack(slopes, axis=-1) if slopes else np.empty(power.shape[:-1] + (0,)))


@dataclass(frozen=True)
class Rolloff:
    """The roll-off of the records' second differences (:func:`rolloff`): ``slope`` of the
    steepest band (log PSD against log frequency, with its jackknife error), the ``band``
    (rocking frequencies) and ``z`` (its standard errors above :data:`ROLLOFF_FLOOR`; below
    ``-ROLLOFF_Z``: filtered)."""

    slope: Quantity
    band: tuple
    z: float

    @property
    def filtered(self) -> bool:
        """A filter after the block shows: the steepest band lies more than :data:`ROLLOFF_Z`
        standard errors below :data:`ROLLOFF_FLOOR`."""
        return self.z < -ROLLOFF_Z


def rolloff(records, points_per_cycle: float) -> Rolloff | None:
    """The roll-off check (module docstring, "A filter after the block") of ``records`` (1-D
    arrays of one step) read at ``points_per_cycle`` samples per rocking cycle; ``None`` when no
    band of :data:`ROLLOFF_BANDS` can be read (too few samples per cycle, or too short records).

    Examples
    --------
    >>> import numpy as np
    >>> walk = np.cumsum(np.cumsum(np.random.default_rng(1).standard_normal(50_000)))
    >>> r = rolloff(walk, 75.0)  # white second differences: a flat spectrum
    >>> abs(r.slope.value) < 0.2, r.filtered
    (True, False)
    """
    if isinstance(records, np.ndarray) and records.ndim == 1:
        records = [records]
    frequency, spectra = second_difference_spectra(records)
    if not (points_per_cycle > 0.0) or spectra.shape[0] < 2:
        return None
    groups = np.array_split(np.arange(spectra.shape[0]), min(ROLLOFF_GROUPS, spectra.shape[0]))
    sums = np.stack([spectra[g].sum(axis=0) for g in groups])
    total = sums.sum(axis=0)
    bands, whole = band_slopes(frequency, total, points_per_cycle)
    if not np.isfinite(whole).any():
        return None
    _, reps = band_slopes(frequency, total - sums, points_per_cycle)
    se = np.array([_jackknife(whole[b], reps[:, b]).se for b in range(len(bands))])
    z = np.where(se > 0.0, (whole - ROLLOFF_FLOOR) / np.where(se > 0.0, se, 1.0), np.where(whole < ROLLOFF_FLOOR, -math.inf, math.inf))
    k = int(np.nanargmin(np.where(np.isfinite(whole), z, np.inf)))
    return Rolloff(Quantity(float(whole[k]), float(se[k])), bands[k], float(z[k]))


@dataclass(frozen=True)
class Quantity:
    """A measured value and its standard error (same units)."""

    value: float
    se: float

    @property
    def z(self) -> float:
        """``value / se``: standard errors from zero."""
        return self.value / self.se if self.se > 0.0 else math.copysign(math.inf, self.value) if self.value else 0.0


@dataclass(frozen=True)
class MeasuredModel:
    """What :func:`measure` reads off a set of records of one block.

    Units: ``g`` rad/s^2, ``impulse_sd`` (``sigma_p``) rad/s, ``noise_sd`` (``sigma_n``) rad,
    ``sigma_y`` rad, ``corner_hz`` Hz; ``noise_ratio`` is ``sigma_n / sigma_Y``,
    ``corner_ratio`` the corner times ``T(sigma_Y)`` (eq. 5); ``impulse_var``
    (``sigma_p^2 dt^2``, rad^2), ``noise_var`` (``sigma_n^2``, rad^2) and ``pole`` (``alpha``)
    are the fit of the mixed model as fitted, without bounds (module docstring);
    ``asymmetry`` ``(g_+ - g_-) / (g_+ + g_-)``, ``drift_rms`` the rms of the block means
    over the record's rms. ``r`` holds ``r(1..MAX_LAG)`` and ``r_se`` their standard errors.
    A corner is infinite (and its error NaN) when the fitted pole is not in ``(0, 1)``.
    ``shape`` is the shape ratio ``Q`` (:func:`shape_ratio`); on a noisy record ``pole`` and
    the corners are read off it (:func:`pole_of_shape`), else they are the fit's.
    """

    dt: float
    triples: int
    sigma_y: float
    g: Quantity
    asymmetry: Quantity
    impulse_var: Quantity
    noise_var: Quantity
    pole: Quantity
    impulse_sd: Quantity
    noise_sd: Quantity
    noise_ratio: Quantity
    corner_hz: Quantity
    corner_ratio: Quantity
    shape: Quantity
    drift_rms: float
    drift_z: float
    r: tuple
    r_se: tuple

    @property
    def noisy(self) -> bool:
        """Sensor noise detected (:func:`_noisy`)."""
        return _noisy(self.noise_var, self.noise_ratio)

    @property
    def shape_z(self) -> float:
        """Standard errors by which the shape ratio ``Q`` exceeds a white load's
        (:data:`WHITE_SHAPE`)."""
        return Quantity(self.shape.value - WHITE_SHAPE, self.shape.se).z

    def shape_corner_low(self, points_per_cycle: float, z: float) -> float:
        """The lowest corner, in rocking frequencies at ``points_per_cycle`` samples per
        cycle, that the shape ratio allows ``z`` standard errors above its value
        (:func:`pole_of_shape`): 0 when its error is not finite, infinite when that pole is
        not positive."""
        if not math.isfinite(self.shape.value) or not math.isfinite(self.shape.se):
            return 0.0
        pole = float(pole_of_shape(self.shape.value + z * self.shape.se))
        return -math.log(pole) * points_per_cycle / (2.0 * math.pi) if pole > 0.0 else math.inf

    def side_g_share(self, points_per_cycle: float) -> float:
        """``g`` read off the side means over the ``g`` at which a block reads
        ``points_per_cycle`` samples per cycle at :attr:`sigma_y` (eq. 5; the analysis reads it
        off the signature): ``(N dt / T(sigma_Y, g))^2``; 0 when the side means give no
        positive ``g``. Near 1 under a white load; a load slow enough for the block's side to
        follow it holds part of each side's mean and lowers it (module docstring, "The side means' ``g``")."""
        if not self.g.value > 0.0:
            return 0.0
        return float((points_per_cycle * self.dt / period_from_g(self.sigma_y, self.g.value)) ** 2)

    @property
    def coloured(self) -> bool:
        """A low-pass load detected: without noise ``alpha`` is :data:`DETECT_Z` errors above
        0; with noise the shape ratio is :data:`COLOUR_Z_NOISY` errors above a white load's."""
        return self.shape_z > COLOUR_Z_NOISY if self.noisy else self.pole.z > DETECT_Z

    @property
    def drifting(self) -> bool:
        """Drift detected: ``drift_z`` above :data:`DRIFT_Z`."""
        return self.drift_z > DRIFT_Z

    @property
    def kind(self) -> str:
        """``white``, ``noisy``, ``coloured`` or ``both`` (noise and colour)."""
        return {(False, False): "white", (True, False): "noisy", (False, True): "coloured", (True, True): "both"}[
            (self.noisy, self.coloured)
        ]


def _noisy(noise_var: Quantity, noise_ratio: Quantity) -> bool:
    """Sensor noise detected: ``sigma_n^2`` is :data:`DETECT_Z` errors above 0 and
    ``sigma_n / sigma_Y`` above :data:`NOISE_FLOOR`."""
    return noise_var.z > DETECT_Z and noise_ratio.value > NOISE_FLOOR


def mixed_autocovariance(m, impulse_var: float, noise_var: float, pole: float) -> np.ndarray:
    """``gamma(m) = sigma_p^2 dt^2 alpha^|m| + sigma_n^2 h(m)`` (module docstring): the
    autocovariance of the second differences of a record under a first-order low-pass
    load of pole ``alpha`` (``impulse_var = sigma_p^2 dt^2``) plus white sensor noise of
    variance ``noise_var``; ``gamma(m) / gamma(0)`` is ``r(m)``."""
    m = np.abs(np.asarray(m))
    h = np.zeros(m.shape)
    for lag, value in enumerate(NOISE_PATTERN):
        h[m == lag] = value
    return impulse_var * np.power(float(pole), m) + noise_var * h


def _triangle_products(spans=SPANS) -> np.ndarray:
    """``C[L, m] = sum_i w_i w_{i+|m|}`` (``m = 0..2 max(spans) - 2``, doubled for ``m > 0``) of
    the triangle weights ``w = 1, 2, .., L, .., 2, 1`` of ``spans``: ``S(L) = C @ gamma``."""
    out = np.zeros((len(spans), 2 * max(spans) - 1))
    for row, span in enumerate(spans):
        w = span - np.abs(np.arange(-(span - 1), span))
        full = np.correlate(w, w, mode="full")[w.size - 1 :]
        out[row, : full.size] = full * np.where(np.arange(full.size) == 0, 1.0, 2.0)
    return out


_TRIANGLES = _triangle_products()

#: Spans ``L1 < L2 < L3`` of the shape ratio (:func:`shape_ratio`), read off whole windows.
SHAPE_SPANS = (4, 8, 16)

_SHAPE_TRIANGLES = _triangle_products(SHAPE_SPANS)


def shape_ratio(s) -> np.ndarray:
    """``Q = (S(L3) - S(L2)) / (S(L2) - S(L1))`` of the structure function at
    :data:`SHAPE_SPANS` (last axis of ``s``): white sensor noise adds ``6 sigma_n^2`` to every
    span and cancels, so ``Q = (V_L3 - V_L2) / (V_L2 - V_L1)`` depends on the load's pole
    alone (:func:`shape_of_pole`)."""
    s = np.asarray(s, dtype=float)
    return (s[..., 2] - s[..., 1]) / (s[..., 1] - s[..., 0])


def shape_of_pole(pole) -> np.ndarray:
    """``Q(alpha)`` (:func:`shape_ratio`) of a first-order low-pass load of pole ``alpha``:
    7.97 for white impulses (``V_L = L (2 L^2 + 1) / 3``), rising to 16 (``V_L ~ L^4``) as
    ``alpha -> 1``; 9.66 at ``alpha = 0.78``, 12.4 at 0.92."""
    powers = np.power(np.asarray(pole, dtype=float)[..., None], np.arange(_SHAPE_TRIANGLES.shape[1]))
    return shape_ratio(powers @ _SHAPE_TRIANGLES.T)


#: ``Q`` of a white load, the null of :attr:`MeasuredModel.coloured` on a noisy record.
WHITE_SHAPE = float(shape_of_pole(0.0))


def structure_function(gamma: np.ndarray) -> np.ndarray:
    """``S(L) = Var(y[k+L] - 2 y[k] + y[k-L])`` for ``L`` in :data:`SPANS` from the
    autocovariance ``gamma(0..MAX_LAG)`` of the one-step second differences (the span-``L``
    difference is their sum with triangle weights)."""
    return _TRIANGLES @ np.asarray(gamma, dtype=float)


def structure_model(impulse_var: float, noise_var: float, pole: float) -> np.ndarray:
    """``S(L) = sigma_p^2 dt^2 V_L(alpha) + 6 sigma_n^2`` (module docstring) for :data:`SPANS`:
    :func:`structure_function` of :func:`mixed_autocovariance`."""
    return structure_function(mixed_autocovariance(np.arange(MAX_LAG + 1), impulse_var, noise_var, pole))


def _profiler(gammas: np.ndarray):
    """The fit of :func:`fit_structure` profiled over the pole, for each row of ``gammas``
    ``(G, MAX_LAG + 1)``: a function of the poles ``alphas`` ``(G, A)`` that gives the two
    variances in closed form and the residual sum of squares (each ``(G, A)``)."""
    s = gammas @ _TRIANGLES.T
    g0 = gammas[:, :1]
    lags = np.arange(DIRECT_LAGS + 1)
    target = np.concatenate([gammas[:, : DIRECT_LAGS + 1] / g0, np.ones_like(s)], axis=1)
    noise = np.concatenate([mixed_autocovariance(lags, 0.0, 1.0, 0.0)[None, :] / g0, structure_model(0.0, 1.0, 0.0)[None, :] / s], axis=1)
    a22, b2 = np.sum(noise**2, axis=1)[:, None], np.sum(noise * target, axis=1)[:, None]
    exponents = np.arange(MAX_LAG + 1)

    def profile(alphas: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        powers = np.power(alphas[..., None], exponents)
        impulse = np.concatenate([powers[..., : DIRECT_LAGS + 1] / g0[:, None, :], (powers @ _TRIANGLES.T) / s[:, None, :]], axis=2)
        a11, a12, b1 = np.sum(impulse**2, axis=2), np.einsum("gar,gr->ga", impulse, noise), np.einsum("gar,gr->ga", impulse, target)
        det = a11 * a22 - a12**2
        c1, c2 = (a22 * b1 - a12 * b2) / det, (a11 * b2 - a12 * b1) / det
        rss = np.sum((impulse * c1[..., None] + noise[:, None, :] * c2[..., None] - target[:, None, :]) ** 2, axis=2)
        return c1, c2, rss

    return profile


#: Poles of the fit's first search, over ``(-0.9, MAX_POLE)``: even steps up to 0.9, then
#: geometric steps in ``1 - alpha`` towards :data:`MAX_POLE`.
POLE_GRID = np.concatenate([np.linspace(-0.9, 0.9, 91), 1.0 - np.geomspace(0.1, 1.0 - MAX_POLE, 60)])

_SHAPE_CURVE = shape_of_pole(POLE_GRID)


def pole_of_shape(q) -> np.ndarray:
    """The pole ``alpha`` whose :func:`shape_of_pole` is ``q`` (it increases with ``alpha``):
    linear interpolation on :data:`POLE_GRID`, clipped to its ends."""
    return np.interp(q, _SHAPE_CURVE, POLE_GRID)


#: Width to which the golden-section search of :func:`fit_structures` narrows the pole:
#: near the minimum the residual then still changes by more than its rounding, so that
#: records scaled in angle and time take the same path (1e-9 does not).
POLE_TOLERANCE = 1e-8

_GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0


def fit_structures(gammas: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`fit_structure` of each row of ``gammas`` ``(G, MAX_LAG + 1)`` at once: arrays of
    ``(sigma_p^2 dt^2, sigma_n^2, alpha)``.

    ``alpha`` minimises the profiled residual (:func:`_profiler`): the best of
    :data:`POLE_GRID`, then a golden-section search between its two neighbours, run on
    every row together down to :data:`POLE_TOLERANCE`; the search's end replaces the grid
    point only where its residual is not larger. Raises :class:`rockdec.validate.InputError`
    when a row has no finite residual (second differences with no spread).
    """
    gammas = np.atleast_2d(np.asarray(gammas, dtype=float))
    rows = np.arange(gammas.shape[0])
    profile = _profiler(gammas)
    rss = profile(np.broadcast_to(POLE_GRID, (rows.size, POLE_GRID.size)))[2]
    if not np.isfinite(rss).any(axis=1).all():  # a structure function with no spread: nothing to fit a model to
        raise checks.InputError(
            "the second differences of the records have no usable spread (a record at rest, or one that chatters at zero "
            "almost all the time), so their model cannot be measured; declare it (`load`, `sensor_noise`)"
        )
    best = np.nanargmin(rss, axis=1)
    lo, hi = POLE_GRID[np.maximum(best - 1, 0)], POLE_GRID[np.minimum(best + 1, POLE_GRID.size - 1)]

    def f(alpha):
        return profile(alpha[:, None])[2][:, 0]

    c, d = hi - _GOLDEN * (hi - lo), lo + _GOLDEN * (hi - lo)
    fc, fd = f(c), f(d)
    for _ in range(max(0, math.ceil(math.log(POLE_TOLERANCE / max(float(np.max(hi - lo)), POLE_TOLERANCE)) / math.log(_GOLDEN)))):
        left = ~(fd < fc)  # the minimum lies in [lo, d] (NaN residuals count as large)
        lo, hi = np.where(left, lo, c), np.where(left, d, hi)
        new = np.where(left, hi - _GOLDEN * (hi - lo), lo + _GOLDEN * (hi - lo))
        fnew = f(new)
        c, d, fc, fd = np.where(left, new, d), np.where(left, c, new), np.where(left, fnew, fd), np.where(left, fc, fnew)
    x = 0.5 * (lo + hi)
    alpha = np.where(f(x) <= rss[rows, best], x, POLE_GRID[best])
    impulse_var, noise_var, _ = profile(alpha[:, None])
    return impulse_var[:, 0], noise_var[:, 0], alpha


def fit_structure(gamma: np.ndarray) -> tuple[float, float, float]:
    """Least-squares ``(sigma_p^2 dt^2, sigma_n^2, alpha)`` of the mixed model on the
    autocovariance ``gamma(0..MAX_LAG)`` of the second differences.

    The residuals are those of ``gamma(0..DIRECT_LAGS)`` over ``gamma(0)`` (the model of
    :func:`mixed_autocovariance`, which pins a weak colour through ``r(1)``) and those of
    the structure function over itself, ``S_model(L) / S(L) - 1`` (:func:`structure_model`,
    which sums many lags and sees a colour under noise). For fixed ``alpha`` all are linear
    in the two variances, solved in closed form; ``alpha`` minimises the profiled
    residual (:func:`fit_structures`). Neither variance is held positive.
    """
    impulse_var, noise_var, alpha = fit_structures(np.asarray(gamma, dtype=float)[None, :])
    return float(impulse_var[0]), float(noise_var[0]), float(alpha[0])


def second_differences(y: np.ndarray, margin: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """``(d, side)``: ``d[k] = y[k+1] - 2 y[k] + y[k-1]`` where the triple is kept, NaN where
    it is left out; ``side[k]`` is 1 on the positive side, 0 on the negative.

    A triple is kept when its three samples have one sign and the samples
    :data:`GUARD` steps before and after it (``y[k -+ GUARD]``) lie beyond ``margin`` on that
    side; NaN anywhere in those five samples leaves it out. The guard samples carry
    sensor noise independent of the triple's own, so choosing triples by them does not
    select the noise that ``d`` holds; the margin (:func:`measure`: several ``g dt^2``, to
    leave out flights that cross zero and return within the guard, and several
    ``sigma_n``, so that noise cannot hide a crossing) leaves out the chatter near zero.
    """
    d = np.full(y.size, np.nan)
    side = np.zeros(y.size, dtype=np.int8)
    n = y.size - 2 * GUARD
    if n > 0:
        k = slice(GUARD, GUARD + n)
        a, b, c = y[GUARD - 1 : GUARD - 1 + n], y[k], y[GUARD + 1 : GUARD + 1 + n]
        lo, hi = y[:n], y[2 * GUARD :]
        up = (a > 0) & (b > 0) & (c > 0) & (lo > margin) & (hi > margin)  # NaN compares False
        down = (a < 0) & (b < 0) & (c < 0) & (lo < -margin) & (hi < -margin)
        d[k] = np.where(up | down, c - 2.0 * b + a, np.nan)
        side[k] = up
    return d, side


def span_differences(y: np.ndarray, d: np.ndarray, span: int) -> np.ndarray:
    """``y[k+L] - 2 y[k] + y[k-L]`` (``L = span``) where every one-step second difference it
    sums, ``d[k-L+1..k+L-1]`` (:func:`second_differences`, NaN where left out), is kept, so that
    the window holds no impact and lies on one side; NaN elsewhere. Its sensor noise is
    ``n[k+L] - 2 n[k] + n[k-L]`` exactly, of variance ``6 sigma_n^2`` whatever ``L``."""
    out = np.full(y.size, np.nan)
    if y.size > 2 * span:
        gaps = np.concatenate([[0], np.cumsum(~np.isfinite(d))])
        k = np.arange(span, y.size - span)
        whole = gaps[k + span] == gaps[k - span + 1]
        out[k] = np.where(whole, y[k + span] - 2.0 * y[k] + y[k - span], np.nan)
    return out


def _block_starts(offset: int, size: int, total: int, n_blocks: int) -> tuple[np.ndarray, np.ndarray]:
    """``(blocks, starts)``: the jackknife blocks a record of ``size`` samples starting at
    sample ``offset`` of ``total`` overlaps, and the index in the record where each begins
    (sample ``i`` of all records is in block ``i n_blocks // total``)."""
    first, last = offset * n_blocks // total, (offset + size - 1) * n_blocks // total
    blocks = np.arange(first, last + 1)
    starts = np.maximum(-(-blocks * total // n_blocks) - offset, 0)
    return blocks, starts


def _block_sums(records, n_blocks: int, margin: float) -> dict:
    """Per-block sums of every measured quantity (they add over blocks).

    Returns arrays indexed by block: ``n``, ``sy``, ``syy`` (finite samples, after each
    record's mean is removed), ``n_side``, ``s_side`` (count and sum of kept second differences
    per side, ``[:, 0]`` negative side, ``[:, 1]`` positive), ``n_span``, ``s_span``, ``ss_span``
    (count, sum and sum of squares per span of :data:`SHAPE_SPANS` and side, ``[:, span, side]``,
    of the span differences :func:`span_differences`, each in the block of its middle sample),
    and per record its second differences (NaN where left out), their side, and its blocks
    and where they start, for the lag sums.
    """
    total = sum(y.size for y in records)
    out = {k: np.zeros(n_blocks) for k in ("n", "sy", "syy")}
    out.update({k: np.zeros((n_blocks, 2)) for k in ("n_side", "s_side")})
    out.update({k: np.zeros((n_blocks, len(SHAPE_SPANS), 2)) for k in ("n_span", "s_span", "ss_span")})
    out["d"], out["side"], out["blocks"] = [], [], []
    offset = 0
    for y in records:
        if y.size:
            blocks, starts = _block_starts(offset, y.size, total, n_blocks)
            ok = np.isfinite(y)
            y0 = np.where(ok, y, 0.0)
            out["n"][blocks] += np.add.reduceat(ok.astype(float), starts)
            out["sy"][blocks] += np.add.reduceat(y0, starts)
            out["syy"][blocks] += np.add.reduceat(y0 * y0, starts)
            d, side = second_differences(y, margin)
            keep = np.isfinite(d)
            spans = [span_differences(y, d, span) for span in SHAPE_SPANS]
            for s in (0, 1):
                sel = keep & (side == s)
                out["n_side"][blocks, s] += np.add.reduceat(sel.astype(float), starts)
                out["s_side"][blocks, s] += np.add.reduceat(np.where(sel, d, 0.0), starts)
                for j, x in enumerate(spans):
                    sel = np.isfinite(x) & (side == s)
                    x = np.where(sel, x, 0.0)
                    out["n_span"][blocks, j, s] += np.add.reduceat(sel.astype(float), starts)
                    out["s_span"][blocks, j, s] += np.add.reduceat(x, starts)
                    out["ss_span"][blocks, j, s] += np.add.reduceat(x * x, starts)
            out["d"].append(d)
            out["side"].append(side)
            out["blocks"].append((blocks, starts))
        offset += y.size
    return out


def _lag_sums(sums: dict, means: np.ndarray, max_lag: int, n_blocks: int) -> tuple[np.ndarray, np.ndarray]:
    """``sum c_k c_{k+m}`` and pair counts per block and lag ``m = 0..max_lag`` of the
    side-centred second differences ``c`` (pairs within one record, both kept; a pair
    belongs to the block of its first sample)."""
    prod = np.zeros((n_blocks, max_lag + 1))
    count = np.zeros((n_blocks, max_lag + 1))
    for d, side, (blocks, starts) in zip(sums["d"], sums["side"], sums["blocks"]):
        keep = np.isfinite(d)
        c = np.where(keep, d - means[side], 0.0)
        k = keep.astype(float)
        ends = np.append(starts[1:], c.size)
        for b, lo, hi in zip(blocks, starts, ends):
            for m in range(max_lag + 1):
                top = min(hi, c.size - m)
                if top > lo:
                    prod[b, m] += c[lo:top] @ c[lo + m : top + m]
                    count[b, m] += k[lo:top] @ k[lo + m : top + m]
    return prod, count


def _block_means(y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(centres, means)`` of the finite samples of ``y`` cut into up to
    :data:`DRIFT_BLOCKS` consecutive blocks of at least :data:`DRIFT_BLOCK_MIN` samples
    (centres as sample indices); empty when fewer than 4 such blocks fit."""
    where = np.flatnonzero(np.isfinite(y))
    b = min(DRIFT_BLOCKS, where.size // DRIFT_BLOCK_MIN)
    if b < 4:
        return np.empty(0), np.empty(0)
    pieces = np.array_split(where, b)
    return np.array([p.mean() for p in pieces]), np.array([y[p].mean() for p in pieces])


def _detrend(y: np.ndarray) -> np.ndarray:
    """``y`` less the piecewise-linear line through its block means (:func:`_block_means`),
    so that a slow drift does not move the zero the sides are read from."""
    centres, means = _block_means(y)
    return y - np.interp(np.arange(y.size), centres, means) if centres.size else y


def _drift(records, sigma_y: float) -> tuple[float, float]:
    """``(rms of block means / sigma_Y, z)`` of von Neumann's ratio pooled over records
    (module docstring); NaN when no record has 4 blocks."""
    num = den = 0.0
    blocks = 0
    means_all = []
    for y in records:
        _, means = _block_means(y)
        if not means.size:
            continue
        means = means - means.mean()
        num += float(np.sum(np.diff(means) ** 2))
        den += float(np.sum(means**2))
        blocks += means.size
        means_all.append(means)
    if not means_all or den == 0.0:
        return math.nan, math.nan
    eta = num / den
    sd0 = math.sqrt(4.0 * (blocks - 2) / (blocks**2 - 1))
    rms = float(np.sqrt(np.mean(np.concatenate(means_all) ** 2))) / sigma_y
    return rms, (2.0 - eta) / sd0


def _corners(alpha, sigma_y, g, dt) -> tuple[np.ndarray, np.ndarray]:
    """``(corner in Hz, corner in rocking frequencies)`` of poles ``alpha`` (module docstring):
    infinite where ``alpha`` is not in ``(0, 1)``, NaN in rocking frequencies where ``g <= 0``."""
    pole = (0.0 < alpha) & (alpha < 1.0)
    corner = np.where(pole, -np.log(np.where(pole, alpha, 1.0)) / (2.0 * math.pi * dt), math.inf)
    with np.errstate(invalid="ignore"):
        return corner, np.where(g > 0, corner * period_from_g(sigma_y, np.where(g > 0, g, 1.0)), math.nan)


def _quantities(n, sy, syy, n_side, s_side, prod, count, n_span, s_span, ss_span, dt) -> dict:
    """Every measured number from summed statistics, one row per set of sums (all records,
    or all but one block): ``n``, ``sy``, ``syy`` ``(rows,)``, ``n_side``, ``s_side`` ``(rows, 2)``,
    ``prod``, ``count`` ``(rows, lags)``, ``n_span``, ``s_span``, ``ss_span`` ``(rows, spans, 2)``;
    each value an array over the rows (``r`` ``(rows, lags - 1)``). ``pole`` and the corners
    are the fit's; ``shape_pole`` is :func:`pole_of_shape` of ``shape``."""
    sigma2 = syy / n - (sy / n) ** 2
    means = s_side / n_side
    g_minus, g_plus = means[:, 0] / dt**2, -means[:, 1] / dt**2
    gamma = prod / count
    impulse_var, noise_var, alpha = fit_structures(gamma)
    sigma_y = np.sqrt(np.maximum(sigma2 - np.maximum(noise_var, 0.0), 0.0))
    g = 0.5 * (g_minus + g_plus)
    corner_hz, corner_ratio = _corners(alpha, sigma_y, g, dt)
    with np.errstate(divide="ignore", invalid="ignore"):
        sides = n_span > 0  # each side about its own mean; a side without windows adds nothing
        spans = np.sum(np.where(sides, ss_span - s_span**2 / np.where(sides, n_span, 1.0), 0.0), axis=2) / (np.sum(n_span - sides, axis=2))
        shape = shape_ratio(spans)
        return {
            "sigma_y": sigma_y,
            "g": g,
            "impulse_var": impulse_var,
            "noise_var": noise_var,
            "pole": alpha,
            "impulse_sd": np.sqrt(np.maximum(impulse_var, 0.0)) / dt,
            "noise_sd": np.sqrt(np.maximum(noise_var, 0.0)),
            "noise_ratio": np.where(sigma_y > 0.0, np.sqrt(np.maximum(noise_var, 0.0)) / np.where(sigma_y > 0.0, sigma_y, 1.0), math.nan),
            "corner_hz": corner_hz,
            "corner_ratio": corner_ratio,
            "shape": shape,
            "shape_pole": pole_of_shape(shape),
            "r": gamma[:, 1:] / gamma[:, :1],
        }


def _jackknife(whole: float, reps: np.ndarray) -> Quantity:
    """``whole`` with the delete-one-block jackknife standard error of its values ``reps``
    with each block left out in turn (NaN when one is not finite or there are fewer than 2)."""
    jack = reps.size
    if not np.isfinite(reps).all() or jack < 2:
        return Quantity(float(whole), math.nan)
    return Quantity(float(whole), float(math.sqrt((jack - 1) / jack * np.sum((reps - reps.mean()) ** 2))))


def _asymmetry(records, n_blocks: int) -> Quantity:
    """``(g_+ - g_-) / (g_+ + g_-)`` read as the asymmetry check reads it
    (:func:`rockdec.record.diagnostics.asymmetry`): each side's ``g dt^2`` from the mean
    second difference of the triples beyond a guard on that side of each record's impact
    level (:func:`rockdec.record.diagnostics.impact_sides`), summed per block, with its
    jackknife standard error. A push ``b g`` towards the positive side leaves ``g (1 - b)``
    there and ``g (1 + b)`` on the other: ``-b``. About the record's mean instead, a lean
    moves the mean off the impact level and triples across it land on the wrong side, which
    under a low-pass load scatters the reading widely and can flip its sign; about the
    level it reads the lean (``tests/record/test_record_measure.py``)."""
    total = sum(y.size for y in records)
    sums = np.zeros((n_blocks, 4))  # n0, n1, s0, s1 per block
    offset = 0
    for y in records:
        finite = y[np.isfinite(y)]
        level, guard = diagnostics.impact_sides(y, float(np.var(finite)) if finite.size else math.nan)
        if np.isfinite(level):
            blocks, starts = _block_starts(offset, y.size, total, n_blocks)
            for b, lo, hi in zip(blocks, starts, [*starts[1:], y.size]):
                sums[b] += diagnostics.side_sums(y[lo:hi], level, guard)
        offset += y.size

    def value(n0, n1, s0, s1):
        g_minus, g_plus = s0 / n0 if n0 else math.nan, -s1 / n1 if n1 else math.nan
        return (g_plus - g_minus) / (g_plus + g_minus) if g_plus + g_minus > 0.0 else math.nan

    used = np.flatnonzero(sums.any(axis=1))
    total_sums = sums.sum(axis=0)
    return _jackknife(value(*total_sums), np.array([value(*(total_sums - sums[b])) for b in used]))


def measure(records, dt: float, *, n_blocks: int = JACKKNIFE_BLOCKS) -> MeasuredModel:
    """The record's model (module docstring) from ``records`` of one block sampled at ``dt``.

    ``records``: one 1-D array of angles (rad) or a sequence of them, NaN allowed (triples
    and pairs touching a NaN are skipped); each loses its own mean. Raises
    :class:`rockdec.validate.InputError` for a bad ``dt`` or records with fewer than
    :data:`MIN_TRIPLES` usable triples.
    """
    dt = checks.positive(dt, "dt", "give the sampling step in s, > 0")
    if isinstance(records, np.ndarray) and records.ndim == 1:
        records = [records]
    records = [np.asarray(y, dtype=np.float64).ravel() for y in records]
    records = [y - np.nanmean(y) if np.isfinite(y).any() else y for y in records]
    finite = sum(int(np.isfinite(y).sum()) for y in records)
    if finite < MIN_TRIPLES:
        raise checks.InputError(
            f"the records hold {finite} finite samples (at least {MIN_TRIPLES} are needed) to measure their model; give a longer record"
        )
    sigma_raw = math.sqrt(float(np.nanmean(np.concatenate(records) ** 2)))
    drift_rms, drift_z = _drift(records, sigma_raw)
    level = [_detrend(y) for y in records] if drift_z > DRIFT_Z else records
    keys = ("n", "sy", "syy", "n_side", "s_side", "prod", "count", "n_span", "s_span", "ss_span")
    margin = 0.0
    for _ in range(MARGIN_PASSES + 1):
        sums = _block_sums(level, n_blocks, margin)
        triples = int(sums["n_side"].sum())
        if triples < MIN_TRIPLES or (sums["n_side"].sum(axis=0) == 0).any():
            raise checks.InputError(
                f"the records hold {triples} triples of samples on one side of zero (at least {MIN_TRIPLES}, on both "
                "sides, are needed) to measure their model; give a longer record"
            )
        means = sums["s_side"].sum(axis=0) / sums["n_side"].sum(axis=0)
        sums["prod"], sums["count"] = _lag_sums(sums, means, MAX_LAG, n_blocks)
        whole = {k: v[0] for k, v in _quantities(*(sums[k].sum(axis=0)[None] for k in keys), dt).items()}
        margin = max(MARGIN_G * abs(whole["g"]) * dt**2, MARGIN_NOISE * whole["noise_sd"])
    used = np.flatnonzero(sums["n"] > 0)
    reps = _quantities(*(sums[k].sum(axis=0)[None] - sums[k][used] for k in keys), dt)  # each block left out in turn
    jack = used.size

    def q(name):
        return _jackknife(whole[name], reps[name])

    if _noisy(q("noise_var"), q("noise_ratio")):  # beneath the noise the load's pole is read off the shape (module docstring)
        for row in (whole, reps):
            row["pole"] = row["shape_pole"]
            row["corner_hz"], row["corner_ratio"] = _corners(np.asarray(row["pole"]), row["sigma_y"], row["g"], dt)
    r_se = np.sqrt((jack - 1) / jack * np.sum((reps["r"] - reps["r"].mean(axis=0)) ** 2, axis=0))
    names = ("g", "impulse_var", "noise_var", "pole", "impulse_sd", "noise_sd", "noise_ratio", "corner_hz", "corner_ratio", "shape")
    return MeasuredModel(
        dt=dt,
        triples=triples,
        sigma_y=float(whole["sigma_y"]),
        drift_rms=drift_rms,
        drift_z=drift_z,
        r=tuple(float(x) for x in whole["r"]),
        r_se=tuple(float(x) for x in r_se),
        asymmetry=_asymmetry(records, n_blocks),
        **{name: q(name) for name in names},
    )

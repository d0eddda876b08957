"""Records given together that are the same data in disguise: a copy shifted by a constant,
negated, scaled (rad against degrees included), or a stretch of another record (two
overlapping pieces of one record). Pooled, such a copy counts the same triggers twice and
narrows the interval for nothing; :func:`same_data` names the pair in one sentence.

The test is the Pearson correlation of two records at every relative lag, over the samples
they share at that lag: ``b = s a + c`` on the overlap gives ``|r| = 1`` whatever the scale
``s`` (sign included) and offset ``c``. The sums over each overlap come from FFT
correlations of the records, their squares and their masks of valid samples (NaN gaps left
out), so a pair costs ``O(n log n)``.
"""

from __future__ import annotations

import math

import numpy as np

from rockdec.record.records import MIN_SAMPLES

__all__ = ["MIN_OVERLAP", "SAME_CORRELATION", "same_data"]

#: Smallest ``|r|`` over an overlap that marks two records as the same data. Independent
#: records of one block stay well below it at the shortest overlap (``tests/record/test_sameness.py``
#: checks them); a copy with white noise of standard deviation ``q`` (in units of the
#: record's) added reaches ``1/sqrt(1 + q^2)``: 0.99 holds copies noisier by up to 14 %.
SAME_CORRELATION = 0.99

#: Fewest shared samples over which a correlation counts: a record's own minimum
#: (:data:`rockdec.record.records.MIN_SAMPLES`); at a handful of samples any two records correlate.
MIN_OVERLAP = MIN_SAMPLES

#: How the scale between two copies reads: degrees against rad.
DEGREES = 180.0 / math.pi


def _prepared(theta: np.ndarray, size: int):
    """The spectra (length ``size``) of a record standardised by its own mean and std over its
    valid samples, of its square, and of its mask of valid samples; and its mean and std."""
    x = np.asarray(theta, dtype=np.float64)
    valid = np.isfinite(x)
    mean = float(np.mean(x[valid])) if valid.any() else 0.0
    std = float(np.std(x[valid])) if valid.any() else 0.0
    z = np.where(valid, (x - mean) / (std or 1.0), 0.0)
    mask = valid.astype(np.float64)
    return np.fft.rfft(np.stack([z, z * z, mask]), n=size), mean, std


def _best(a_spec, b_spec, size: int, n_a: int, n_b: int, min_overlap: int):
    """``(|r|, r, lag, overlap, slope, intercept)`` at the lag of largest ``|r|`` between two
    prepared records (``lag``: where ``b[0]`` falls in ``a``, negative when ``b`` starts
    before ``a``; ``b = slope a + intercept`` on the overlap, in standard units)."""
    za, za2, ma = a_spec
    zb, zb2, mb = b_spec
    # correlation c[k] = sum_i a[i + k] b[i]: the spectrum of a times the conjugate of b's
    sums = np.fft.irfft(np.stack([za * zb.conj(), za * mb.conj(), ma * zb.conj(), za2 * mb.conj(), ma * zb2.conj(), ma * mb.conj()]), n=size)
    lags = np.r_[np.arange(0, n_a), np.arange(-(n_b - 1), 0)]
    index = np.r_[np.arange(0, n_a), size + np.arange(-(n_b - 1), 0)]
    sab, sa, sb, saa, sbb, m = (s[index] for s in sums)
    m = np.rint(m)
    with np.errstate(invalid="ignore", divide="ignore"):
        cov = m * sab - sa * sb
        var = (m * saa - sa * sa) * (m * sbb - sb * sb)
        r = np.where((m >= min_overlap) & (var > 0), cov / np.sqrt(np.maximum(var, 0.0)), 0.0)
    k = int(np.argmax(np.abs(r)))
    var_a = m[k] * saa[k] - sa[k] ** 2
    slope = float(cov[k] / var_a) if var_a > 0 else math.nan
    intercept = float((sb[k] - slope * sa[k]) / m[k]) if m[k] > 0 else math.nan
    return abs(float(r[k])), float(r[k]), int(lags[k]), int(m[k]), slope, intercept


#: Relative size below which a scale's distance from 1 (or from the degree factor) and an
#: offset (in units of the record's std) are not named: a printed or float32 copy differs so.
NAMED_CHANGE = 1e-3


def _describe(scale: float, offset: float, spread: float) -> str:
    """The transform ``b = scale a + offset`` in words (``spread``: the std of ``b``)."""
    parts = []
    if scale < 0:
        parts.append("negated")
    size = abs(scale)
    for factor, words in ((DEGREES, "in degrees where the other is in rad"), (1 / DEGREES, "in rad where the other is in degrees")):
        if abs(size / factor - 1) < NAMED_CHANGE:
            parts.append(words)
            break
    else:
        if abs(size - 1) >= NAMED_CHANGE:
            parts.append(f"scaled by {size:.4g}")
    if abs(offset) >= NAMED_CHANGE * spread:
        parts.append(f"shifted by {offset:+.3g}")
    return ", ".join(parts) if parts else "a copy"


def same_data(records, sources=None, *, threshold: float = SAME_CORRELATION, min_overlap: int = MIN_OVERLAP) -> str | None:
    """A sentence naming the first pair of ``records`` that are the same data in disguise
    (module docstring), or ``None`` when every pair is distinct.

    Parameters
    ----------
    records : sequence of array_like or of :class:`rockdec.record.records.Record`
        1-D records of one block (NaN: gaps, left out of every sum).
    sources : sequence of str, optional
        Their names (default: a Record's ``source``, else ``record 0``, ``record 1``, ...).
    threshold : float
        Smallest ``|r|`` that marks a pair (:data:`SAME_CORRELATION`).
    min_overlap : int
        Fewest shared samples a lag needs to count (:data:`MIN_OVERLAP`).

    Returns
    -------
    str or None

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> a = np.cumsum(rng.standard_normal(3000))
    >>> same_data([a, -2 * a[1000:] + 0.5], ["a.csv", "b.csv"])
    'b.csv holds the same data as a.csv (negated, scaled by 2, shifted by +0.5, over 2000 shared samples, from sample 1000 of a.csv; correlation -1): give each record once (a copy counts its triggers twice and narrows the interval for nothing).'
    >>> same_data([a, np.cumsum(rng.standard_normal(3000))]) is None
    True
    """
    arrays = [np.asarray(getattr(r, "theta", r), dtype=np.float64).ravel() for r in records]
    if sources is None:
        sources = [getattr(r, "source", f"record {i}") for i, r in enumerate(records)]
    if len(arrays) < 2:
        return None
    size = int(2 ** math.ceil(math.log2(2 * max(a.size for a in arrays))))
    prepared = [_prepared(a, size) for a in arrays]
    for i in range(len(arrays)):
        for j in range(i + 1, len(arrays)):
            if min(arrays[i].size, arrays[j].size) < min_overlap:
                continue
            best, r, lag, overlap, slope, intercept = _best(
                prepared[i][0], prepared[j][0], size, arrays[i].size, arrays[j].size, min_overlap
            )
            if best < threshold:
                continue
            (_, mean_a, std_a), (_, mean_b, std_b) = prepared[i], prepared[j]
            # b_z = slope a_z + intercept in standard units: back to the records' own
            scale = slope * std_b / std_a
            offset = mean_b + std_b * intercept - scale * mean_a
            where = f"from sample {lag} of {sources[i]}" if lag >= 0 else f"{sources[i]} from sample {-lag} of {sources[j]}"
            return (
                f"{sources[j]} holds the same data as {sources[i]} ({_describe(scale, offset, std_b)}, over {overlap} shared samples, "
                f"{where}; correlation {r:.4g}): give each record once (a copy counts its triggers twice and narrows "
                "the interval for nothing)."
            )
    return None

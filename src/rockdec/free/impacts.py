"""Releases and impacts of a free-rocking record: where the block was let go, and each zero
crossing after it (the impacts of eq. 6), to sub-sample precision.

A crossing is found with hysteresis: the side of the block changes only once the angle has
gone :data:`CROSSING_BAND_SIGMAS` sensor-noise standard deviations past zero, so noise near an
impact gives one crossing, not several; its position is the zero of the straight line
between the samples around it (the arc fits of :mod:`rockdec.free.arcs` then refine it).
The record splits into segments between crossings. A segment that rises above the last
fitted arc (more than noise and sampling allow, :data:`GROWTH_RELATIVE`, :data:`GROWTH_SIGMAS`)
holds a release, or else the record is a forced response: free rocking loses energy on
average, so the amplitude can grow beyond one impact's scatter (:data:`IMPACT_GAIN`) only
where a hand lifts the block, after holding it (:data:`RELEASE_LEAD`). A release's sequence runs on, arc by arc, while each arc has at least
``min_arc_samples`` samples and rises :data:`MIN_HEIGHT_SIGMAS` noise standard deviations
above zero; the first arc that does not ends it, with the reason.

Positions are fractional sample indices (``0`` is the first sample); callers turn them into
times.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rockdec.timeaxis import RecordError

__all__ = ["CROSSING_BAND_SIGMAS", "find_crossings", "find_sequences", "noise_std"]

#: Half-band of the crossing detector, in sensor-noise standard deviations: a crossing counts
#: once the angle is this far past zero, so that white noise (a 4-sigma excursion on both
#: sides in a row is rarer than 1 in 10^8 samples) gives no extra crossings at an impact.
CROSSING_BAND_SIGMAS = 4.0

#: Lowest apex of an arc the analysis fits, in sensor-noise standard deviations: lower arcs
#: are not told from noise by the crossing detector (:data:`CROSSING_BAND_SIGMAS`). The
#: per-impact bias and the interval's coverage at this floor: benchmarks/free_coverage.py.
MIN_HEIGHT_SIGMAS = 5.0

#: Growth of a segment's peak over the last fitted arc that is still noise or sampling, not a
#: release: a relative part (beside the sampled apex's miss, :func:`_sampled_share`) and a part in sensor-noise standard deviations
#: (the largest of a few hundred noisy samples exceeds the true apex by up to about 3 of them).
GROWTH_RELATIVE, GROWTH_SIGMAS = 0.02, 6.0

#: Largest ratio of speeds after and before one impact that is still read as an impact of a
#: rocking block rather than a new push: a block whose ``e`` scatters from impact to impact
#: (per-impact ratios above 1 are common in laboratory records) raises its next apex by up
#: to the square of this; a larger rise while the block rocks is a forced response.
IMPACT_GAIN = 1.25

#: Level below the peak, in sensor-noise standard deviations, that still counts as the held
#: block before a release (the noisy hold scatters about 3 of them either way of its level).
HOLD_SIGMAS = 6.0

#: Longest a flight may last, in units of the flight before it (plus two samples for the
#: crossings' own scatter), before its segment is taken to hold later flights that the
#: crossing detector missed (lower than its band): flights shrink by ``e`` (eq. 6). The
#: flight is then closed where its duration, scaled from the one before, ends.
ARC_GROWTH = 1.25

#: How far past the end of the first flight, as a share of its duration, the next crossing
#: may lie and still close it: a flight is symmetric about its apex (eqs. 2, 4), so a later
#: crossing belongs to a later flight, and the first is closed at the mirror image of its start.
ARC_END_TOLERANCE = 0.25

#: Samples before a release inside a record, in its segment, at least this multiple of the
#: samples of its fall: the block rests, is tilted and held before it is let go, where the
#: rise and fall of a flight last the same (eqs. 2, 4). Growth without such a lead is a forced
#: response.
RELEASE_LEAD = 2.0

#: Fewest samples of the fall from the release to the first impact.
MIN_FALL_SAMPLES = 2


def noise_std(theta: np.ndarray) -> float:
    """Standard deviation of white sensor noise on ``theta`` (rad), robustly.

    Third differences remove a parabola exactly (the free flight of eq. 4) and leave white
    noise of standard deviation ``sqrt(20)`` times the sensor's; the median absolute
    deviation ignores the few that straddle an impact or a release.

    Parameters
    ----------
    theta : numpy.ndarray
        The record (rad), 1-D, finite.

    Returns
    -------
    float
        The noise standard deviation (rad); 0 for a noise-free record.

    Examples
    --------
    >>> t = np.linspace(0.0, 1.0, 2001)
    >>> clean = 0.01 - 0.5 * 0.02 * t**2
    >>> noise_std(clean) < 1e-12
    True
    >>> noisy = clean + np.random.default_rng(0).normal(0.0, 1e-4, t.size)
    >>> round(noise_std(noisy) / 1e-4, 1)
    1.0
    """
    d3 = np.diff(np.asarray(theta, dtype=float), 3)
    if d3.size == 0:
        return 0.0
    from scipy.stats import median_abs_deviation

    return float(median_abs_deviation(d3, scale="normal") / np.sqrt(20.0))


@dataclass(frozen=True)
class Crossings:
    """Zero crossings of a record: ``position`` (fractional sample index) and ``side`` (the
    sign of the angle before each crossing)."""

    position: np.ndarray
    side: np.ndarray


def find_crossings(theta: np.ndarray, band: float) -> Crossings:
    """Zero crossings of ``theta`` with hysteresis ``band`` (rad).

    The side changes only where the angle passes ``-band`` coming from above ``+band`` (or
    the reverse); the crossing is placed at the mean of the first and last linear-interpolated
    zeros between the last sample beyond the old band and the first beyond the new one.

    Parameters
    ----------
    theta : numpy.ndarray
        The record (rad), 1-D, finite.
    band : float
        Half-width of the hysteresis band (rad), >= 0.

    Returns
    -------
    Crossings
        Positions (fractional sample indices) and the side before each crossing.

    Examples
    --------
    >>> c = find_crossings(np.array([1.0, 0.5, -0.5, -1.0, 1.0]), 0.0)
    >>> c.position.tolist(), c.side.tolist()
    ([1.5, 3.5], [1, -1])
    """
    theta = np.asarray(theta, dtype=float)
    s = np.where(theta > band, 1, np.where(theta < -band, -1, 0))
    marked = np.flatnonzero(s)
    if marked.size < 2:
        return Crossings(np.empty(0), np.empty(0, dtype=int))
    flips = marked[1:][s[marked[1:]] != s[marked[:-1]]]
    lasts = marked[:-1][s[marked[1:]] != s[marked[:-1]]]
    positions = np.empty(flips.size)
    sides = s[lasts]
    for n, (i, j, old) in enumerate(zip(lasts, flips, sides)):
        v = old * theta[i : j + 1]
        m = np.flatnonzero((v[:-1] > 0.0) & (v[1:] <= 0.0))
        zeros = i + m + v[m] / (v[m] - v[m + 1])
        positions[n] = 0.5 * (zeros[0] + zeros[-1])
    return Crossings(positions, sides.astype(int))


@dataclass(frozen=True)
class Sequence:
    """One release and the impacts after it, as positions in the record (fractional samples).

    ``side``: the sign of the release angle; ``start``: the first sample of the fit (the held
    block just before the release); ``release``: where the fall seems to start (a first
    guess, refined by the fit); ``crossings``: the impacts that bound the fitted arcs, the
    last one closing the last arc; ``peaks``: the largest sample of each arc (the fall
    first); ``stop``: why no further arc is fitted (a sentence, with
    ``{time}`` standing for the time the caller formats).
    """

    side: int
    start: int
    release: float
    crossings: np.ndarray
    peaks: np.ndarray
    stop: str
    stop_position: float


def _segments(theta: np.ndarray, crossings: Crossings):
    """Sample ranges ``[lo, hi)`` between crossings, the side of each and its peak (rad)."""
    edges = np.concatenate([[-0.5], crossings.position, [theta.size - 0.5]])
    sides = np.concatenate([crossings.side, [-crossings.side[-1]]])
    out = []
    for k in range(edges.size - 1):
        lo, hi = int(np.floor(edges[k])) + 1, int(np.floor(edges[k + 1])) + 1
        lo, hi = max(lo, 0), min(hi, theta.size)
        seg = sides[k] * theta[lo:hi]
        out.append((lo, hi, int(sides[k]), float(seg.max()) if seg.size else 0.0))
    return out


def find_sequences(theta: np.ndarray, noise: float, min_arc_samples: int) -> list[Sequence]:
    """The releases of a record and the impacts of each that the arcs can be fitted between.

    Parameters
    ----------
    theta : numpy.ndarray
        The record (rad), 1-D, finite.
    noise : float
        Sensor-noise standard deviation (rad, :func:`noise_std`).
    min_arc_samples : int
        Fewest samples of a fitted arc between two impacts.

    Returns
    -------
    list of Sequence
        In the order of the record; empty when no segment before a crossing is tall enough
        to be a release.

    Raises
    ------
    rockdec.timeaxis.RecordError
        When the amplitude grows while the block is still rocking (a forced, random
        response: free rocking only loses energy).

    Examples
    --------
    >>> from rockdec.physics.simulate import simulate_model
    >>> theta = simulate_model("simplified", [0], 400, dt=0.01, g=1.0, e=0.8, sigma_p=0.0, theta0=0.01)[0][0]
    >>> seq = find_sequences(theta, 0.0, 4)[0]
    >>> seq.side, seq.start, len(seq.crossings)
    (1, 0, 10)
    """
    crossings = find_crossings(theta, CROSSING_BAND_SIGMAS * noise)
    if crossings.position.size == 0:
        return []
    segments = _segments(theta, crossings)
    min_height = MIN_HEIGHT_SIGMAS * noise
    sequences: list[Sequence] = []
    current: dict | None = None
    reference = np.inf  # the highest apex any later free flight can have: that of the last fitted arc
    for k, (lo, hi, side, peak) in enumerate(segments):
        grew = peak > reference * IMPACT_GAIN**2 * (1.0 + GROWTH_RELATIVE) + GROWTH_SIGMAS * noise
        last = k == len(segments) - 1
        if grew and not last and k > 0:
            release = _release(theta, lo, hi, side, peak, noise, crossings.position[k])
            if release is None or release["lead"] < RELEASE_LEAD * release["fall"]:
                raise RecordError(
                    f"the amplitude grows at sample {lo} with no hold before it, so this is a forced (random) response, "
                    "not free rocking; give a record of a released block, or estimate e from it as a random response."
                )
            if current is not None:
                sequences.append(Sequence(current["side"], current["start"], current["release"], np.asarray(current["crossings"]),
                                          np.asarray(current["peaks"]), "the block is tilted and released again after the impact at {time}",
                                          float(lo)))
            current = release if peak >= min_height else None
            reference = peak
        elif current is not None:
            start, bounds = crossings.position[k - 1], current["crossings"]
            if len(bounds) >= 2:  # a flight lasts e times the one before it (eq. 6), and D ~ sqrt(h) (eq. 4)
                previous = bounds[-1] - bounds[-2]
                end = start + previous * min(1.0, math.sqrt(peak / current["peaks"][-1]))
                open_arc = last or crossings.position[k] - start > ARC_GROWTH * previous + 2.0
            else:  # the first flight: the release time is too rough a guess to scale from
                end = _symmetric_end(theta, lo, hi, side, peak, start)
                open_arc = last or crossings.position[k] - end > max(ARC_END_TOLERANCE * (end - start), 2.0)
            stop = None
            if peak < min_height or peak <= 0.0:
                stop = (f"the arc after the impact at {{time}} rises only {peak / noise if noise > 0 else 0.0:.3g} noise "
                        f"standard deviations (fewer than {MIN_HEIGHT_SIGMAS:g})")
            elif min(hi, int(np.floor(end)) + 1) - lo < min_arc_samples:
                stop = f"the arc after the impact at {{time}} has {min(hi, int(np.floor(end)) + 1) - lo} samples (fewer than min_arc_samples = {min_arc_samples})"
            elif open_arc and np.isfinite(end) and end < theta.size - 1:
                current["crossings"].append(end)
                current["peaks"].append(peak)
                stop = (f"the arc after the impact at {{time}} does not pass {CROSSING_BAND_SIGMAS:g} noise standard deviations, "
                        "so the block comes to rest")
                lo = int(np.floor(end)) + 1
            elif open_arc:
                stop = "the record ends while the block still rocks"
            if stop is None:
                current["crossings"].append(crossings.position[k])
                current["peaks"].append(peak)
                reference = peak / _sampled_share(hi - lo)
            else:
                sequences.append(Sequence(current["side"], current["start"], current["release"], np.asarray(current["crossings"]),
                                          np.asarray(current["peaks"]), stop, float(lo)))
                current = None
        elif k == 0:
            reference = peak
            if not last and peak > 0.0 and peak >= min_height:
                current = _release(theta, lo, hi, side, peak, noise, crossings.position[k])
    return sequences


def _sampled_share(n: int) -> float:
    """Least share of its apex that the largest of ``n >= 3`` samples of a flight reaches:
    the sample nearest the apex is within half a step of it, and the flight lasts more than
    ``n - 1`` steps, so the parabola (eq. 4) keeps ``1 - 1/(n - 1)^2`` of its height there."""
    return 1.0 - 1.0 / (n - 1) ** 2


def _symmetric_end(theta, lo, hi, side, peak, start) -> float:
    """The end of the arc that starts at ``start`` and fills ``[lo, hi)``: the mirror image of
    the start about the centroid of the part above half its peak (a flight is symmetric about
    its apex, eqs. 2, 4); NaN without such a part."""
    seg = side * theta[lo:hi] - 0.5 * peak
    top = np.flatnonzero(seg > 0.0)
    if top.size == 0:
        return np.nan
    # The run above half the peak that holds the peak: other runs belong to later arcs or to noise.
    breaks = np.flatnonzero(np.diff(top) > 1)
    first, last = np.concatenate([[0], breaks + 1]), np.concatenate([breaks, [top.size - 1]])
    at = int(np.argmax(seg))
    which = int(np.flatnonzero((top[first] <= at) & (at <= top[last]))[0])
    run = top[first[which] : last[which] + 1]
    centre = lo + float(np.sum(run * seg[run]) / np.sum(seg[run]))
    return 2.0 * centre - start


def _release(theta, lo, hi, side, peak, noise, crossing) -> dict | None:
    """A sequence opened at the segment ``[lo, hi)`` that ends at ``crossing``: the release is
    the last sample still at the held level, the fit starts as many samples before it as the
    fall lasts (while the block is still held)."""
    seg = side * theta[lo:hi]
    level = peak - HOLD_SIGMAS * noise - 1e-9 * peak
    held = np.flatnonzero(seg >= level)
    release = lo + int(held[-1])
    fall = int(np.floor(crossing)) - release + 1
    if fall < MIN_FALL_SAMPLES:
        return None
    start = release
    while start > lo and release - start < fall and side * theta[start - 1] >= level:
        start -= 1
    return {"side": side, "start": start, "release": float(release), "crossings": [crossing], "peaks": [peak], "lead": release - lo,
            "fall": fall}

"""``e`` from free-rocking records: the one entry point :func:`analyse_free_rocking`.

Per impact (eq. 6): ``e_i = |omega_after| / |omega_before|``, the speeds of the fitted arcs
either side of the impact (:mod:`rockdec.free.arcs`), with the standard error of the fit.

Pooled over the impacts: ``log e_k = log S_k - log S_(k-1)``, the steps between the log
impact speeds of neighbouring arcs, scatter about the block's ``mu = log e`` by the arcs'
fit errors (neighbouring arcs share an impact time, so the steps are correlated: covariance
``D C D^T`` of each release's log speeds ``C``) and by the block's own impact-to-impact
spread ``tau`` (its ``e`` varies from impact to impact: each impact draws anew, so the log
speeds walk). ``mu`` is their generalised least-squares mean under the covariance
``D C D^T + tau^2 I``, with ``tau^2`` where the generalised Q statistic equals its degrees of
freedom (Paule-Mandel) and the 95 % interval of ``tau`` where Q meets the chi-square
quantiles (the Q-profile). With ``tau = 0`` this is the line of log speeds
``log S_k = a + k log e`` (one intercept per release), the efficient combination of the
impacts, which ``e`` keeps (its interval widened by the Birge ratio ``sqrt(Q(0)/dof)`` above
1) unless ``Q(0)`` passes its chi-square test (:data:`SCATTER_LEVEL`); past it, ``e = exp(mu)``
under the spread, with Student's ``t`` quantile. The impacts' spread is reported as ``e tau`` (the standard deviation of the
per-impact ``e``). Per-impact ratios above 1 are kept and counted. Coverage and per-impact
bias: :mod:`rockdec.studies.free_coverage` (benchmarks/free_coverage.py).

A valid record that gives no ``e`` (fewer than :data:`MIN_IMPACTS` impacts) returns a result
whose ``e`` is NaN and whose ``reason`` says why; a record that is not a free-rocking record
raises :class:`rockdec.timeaxis.RecordError` in one sentence.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from typing import NamedTuple

import numpy as np
from scipy import optimize, stats

from rockdec import validate as checks
from rockdec.free import arcs, flight_loss
from rockdec.free.impacts import CROSSING_BAND_SIGMAS, find_crossings, find_sequences, noise_std
from rockdec.physics.models import MODEL_TOLERANCE, MODELS, amplitude_limit
from rockdec.timeaxis import RecordError, sampling_step

__all__ = ["FreeRockingFit", "ImpactMean", "analyse_free_rocking", "impact_mean", "load_covariance", "pooled_mean"]

#: Confidence level of the intervals.
CONFIDENCE = 0.95

#: Fewest impacts that give a pooled ``e``. With one, the interval rests on the fit alone
#: (no degree of freedom is left to measure the impacts' scatter, the Birge ratio); a note
#: says so.
MIN_IMPACTS = 1

#: Default fewest samples of a fitted arc between impacts (each arc has two parameters, its
#: impact times, shared with its neighbours). Per-impact bias and coverage at this floor:
#: benchmarks/free_coverage.py.
MIN_ARC_SAMPLES = 4

#: Fewest samples of a record.
MIN_SAMPLES = 8

#: Samples in a row, equal to the record's largest or smallest value inside a flight, that
#: mark a clipped sensor (a free flight has one apex, never a flat top).
CLIP_RUN = 3

#: A record that ends while the block still rocks above this fraction of its release angle
#: has not shown the block coming to rest (about ``1 - 0.5^2`` of the energy left).
REST_FRACTION = 0.5

#: A record that ends beyond this multiple of its largest release angle, having risen there
#: after its last impact, shows a block that fell over.
OVERTURN_FACTOR = 2.0

#: Relative precision of a record's numbers (to its largest angle) below which its samples'
#: scatter is never taken to be, and the relative standard error of ``e`` is never taken to
#: be: a simulated record's arithmetic drifts by about this over thousands of steps, and a
#: noise-free record's interval would otherwise be a few units of the last place of ``e``.
#: Float32 records are held to their own rounding (``eps/sqrt(12)``).
SAMPLE_PRECISION = 1e-12

#: Level of the chi-square test of the impacts' scatter over their fit errors (``Q(0)``,
#: module docstring) beyond which ``e`` is the mean of a walk of log speeds (``tau > 0``)
#: rather than the line of log speeds: a spread the fits explain keeps the line's efficient
#: weighting, which a chance ``tau`` of the size of the fit errors would undo.
SCATTER_LEVEL = 0.95

#: Widest half-width of the 95 % interval of ``log e`` that is reported: past it (``e`` known
#: to a factor of 7 either way) the impacts give no usable ``e``, and the record is refused.
WIDEST_LOG_HALF_WIDTH = 2.0

#: ``z`` of the pooled loss in flight ``c`` (the score test, one-sided) beyond which the arcs
#: are fitted with it (:mod:`rockdec.free.flight_loss`) and ``e`` is the impacts' share: an
#: ideal block's ``c`` passes it by chance on about 2.5 % of records (tests/free/test_flight_loss.py).
LOSS_Z = 1.96

#: A trend of ``e`` with the impact speed this many standard errors from zero is noted: both
#: models hold ``e`` constant, so a trend is the block's own (or a model that misses).
TREND_Z = 3.0

#: Residual scatter about the arcs, in units of the sensor noise, above which a note says
#: the arcs do not follow the model's free flight.
MISFIT_RATIO = 2.0


def _nan_to_none(value):
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _plain(value):
    """``value`` as JSON-ready Python: lists of floats, ``None`` for NaN."""
    if isinstance(value, np.ndarray):
        return [_plain(v) for v in value.tolist()]
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, (np.floating, float)):
        return _nan_to_none(float(value))
    if isinstance(value, np.integer):
        return int(value)
    return value


@dataclass(frozen=True)
class FreeRockingFit:
    """What a free-rocking analysis found (:func:`analyse_free_rocking`).

    Pooled: ``e`` with its ``e_interval`` (low, high) at ``confidence_level``, the standard
    error of ``log e`` (``log_e_se``, with the impacts' spread in its weights), the scatter
    of the impacts over their fit errors alone (``scatter_ratio``, 1 when the fits explain
    it) and the degrees of freedom (``dof``, impacts less one); the impacts' spread
    ``e_spread`` (the standard deviation of the per-impact ``e``) with its
    ``e_spread_interval``, and ``impacts_above_one`` (ratios above 1, kept); the loss in
    flight ``flight_loss`` (``c`` of ``theta'' = -g sign(theta) - c theta'``, 1/s) with its
    ``flight_loss_interval``, and ``loss_in_flight``: whether the arcs were fitted with it
    (its score test passed :data:`LOSS_Z`; else ``c`` is the test's one-step reading and
    ``e`` is the one-``e`` model's); ``g`` (rad/s^2) and ``nu``
    (rad/s, NaN without ``theta_cr``) read from the arcs with their intervals; ``reason``:
    why there is no ``e`` (``None`` when there is one).

    Per impact (arrays of equal length): ``impact_time`` (s, on the record's time axis),
    ``impact_record``, ``impact_release`` (index of the release among all), the apex of the
    arc before (``amplitude_before``, rad), the signed angular velocities just before and
    after (rad/s) with their standard errors, ``e_impact`` and ``e_impact_se``.

    Per release: ``release_time`` (s), ``release_angle`` (rad, signed), ``release_record``,
    ``release_g`` (the fitted ``g`` of that release), ``stop_time`` (s, where the analysis
    stopped) and ``stop_reason`` (a sentence), ``residual_std`` (rad); the fitted impact
    times ``fitted_times`` (release time first) and ``fitted_q`` (``g`` or ``nu``) from which
    :meth:`curve` redraws the arcs. Per record: ``noise_std`` (rad). ``e`` against the impact
    speed, ``log e_i = log e_reference + e_trend log(S_i/reference_speed)``: ``e_trend`` (per
    unit of log speed, both models predict 0) with its standard error ``e_trend_se``, and
    ``e_reference`` with its ``e_reference_interval`` at ``reference_speed`` (rad/s, the
    impacts' geometric mean landing speed). ``notes``: sentences for the reader.
    """

    model: str
    theta_cr: float | None
    e: float
    e_interval: tuple[float, float]
    confidence_level: float
    log_e_se: float
    scatter_ratio: float
    dof: int
    g: float
    g_interval: tuple[float, float]
    nu: float
    nu_interval: tuple[float, float]
    reason: str | None
    impact_time: np.ndarray
    impact_record: np.ndarray
    impact_release: np.ndarray
    amplitude_before: np.ndarray
    omega_before: np.ndarray
    omega_before_se: np.ndarray
    omega_after: np.ndarray
    omega_after_se: np.ndarray
    e_impact: np.ndarray
    e_impact_se: np.ndarray
    release_time: np.ndarray
    release_angle: np.ndarray
    release_record: np.ndarray
    release_g: np.ndarray
    stop_time: np.ndarray
    stop_reason: tuple[str, ...]
    residual_std: np.ndarray
    fitted_times: tuple[np.ndarray, ...]
    fitted_q: np.ndarray
    noise_std: np.ndarray
    e_trend: float = math.nan
    e_trend_se: float = math.nan
    e_reference: float = math.nan
    e_reference_interval: tuple[float, float] = (math.nan, math.nan)
    reference_speed: float = math.nan
    e_spread: float = math.nan
    e_spread_interval: tuple[float, float] = (math.nan, math.nan)
    impacts_above_one: int = 0
    flight_loss: float = math.nan
    flight_loss_interval: tuple[float, float] = (math.nan, math.nan)
    loss_in_flight: bool = False
    notes: tuple[str, ...] = field(default=())

    @property
    def n_impacts(self) -> int:
        """Impacts with an ``e`` each."""
        return int(self.e_impact.size)

    def curve(self, release: int, t) -> np.ndarray:
        """The fitted angle (rad) of release ``release`` at times ``t`` (s), held angle before
        the release, flights up to its last fitted impact (eqs. 2, 4)."""
        side = int(np.sign(self.release_angle[release]))
        fit = arcs.SequenceFit(self.fitted_times[release], float(self.fitted_q[release]), np.empty((0, 0)), 0.0, 0, side,
                               self.model, self.theta_cr)
        return fit.curve(t)

    def to_dict(self) -> dict:
        """Every field as plain Python (floats, ints, strings, lists; ``None`` for NaN)."""
        return {f.name: _plain(getattr(self, f.name)) for f in fields(self)}


def _records(theta, dt) -> list[tuple[np.ndarray, float, float, float]]:
    """``(angles, step, first time, precision)`` of each record, checked."""
    many = isinstance(theta, (list, tuple)) and len(theta) > 0 and all(np.ndim(r) >= 1 for r in theta)
    records = list(theta) if many else [theta]
    if many and isinstance(dt, (list, tuple)) and len(dt) > 0 and all(np.ndim(d) >= 1 or checks.is_number(d) for d in dt):
        if len(dt) != len(records):
            raise RecordError(f"`dt` has {len(dt)} entries for {len(records)} records; give one step (or time axis) per record, or one step for all.")
        steps = list(dt)
    else:
        steps = [dt] * len(records)
    out = []
    for n, (record, step) in enumerate(zip(records, steps)):
        name = f"theta[{n}]" if many else "theta"
        out.append(_checked_record(record, step, name))
    return out


def _checked_record(record, step, name: str) -> tuple[np.ndarray, float, float, float]:
    try:
        raw = np.asarray(record)
        y = raw.astype(float)
    except (TypeError, ValueError):
        raise RecordError(f"{name}: not an array of numbers; give the rocking angle in rad as a 1-D array.") from None
    if y.ndim != 1:
        raise RecordError(f"{name}: an array of shape {y.shape}, not one record; give a 1-D array (or a list of 1-D arrays).")
    if y.size < MIN_SAMPLES:
        raise RecordError(f"{name}: {y.size} samples, too short for a free-rocking analysis; give at least {MIN_SAMPLES} samples from the release to rest.")
    bad = np.flatnonzero(~np.isfinite(y))
    if bad.size:
        raise RecordError(f"{name}: sample {bad[0]} is {y[bad[0]]}; cut the record to its finite part or fill the gap before the analysis.")
    if np.ptp(y) == 0.0:
        raise RecordError(f"{name}: every sample is {y[0]:g}, a constant record with no rocking; give the record of a released block.")
    if np.ndim(step) == 0:
        t0, dt = 0.0, checks.positive(step, "dt", "give the sampling step in s, > 0")
    else:
        times = np.asarray(step)
        if times.shape != y.shape:
            raise RecordError(f"{name}: {y.size} samples but {times.size} time stamps; give one time stamp per sample.")
        dt = sampling_step(times, name, MIN_SAMPLES)
        t0 = float(np.asarray(times, dtype=float)[0]) if not np.issubdtype(times.dtype, np.datetime64) else 0.0
    relative = max(SAMPLE_PRECISION, np.finfo(raw.dtype).eps / math.sqrt(12.0)) if raw.dtype.kind == "f" else SAMPLE_PRECISION
    return y, dt, t0, relative * float(np.max(np.abs(y)))


def _check_overturn(y, noise, sequences, theta_cr, name):
    """Refuse a block that reaches ``theta_cr``, or that rises after its last impact to
    :data:`OVERTURN_FACTOR` times its largest release angle and stays there."""
    if theta_cr is not None and np.max(np.abs(y)) >= theta_cr:
        k = int(np.flatnonzero(np.abs(y) >= theta_cr)[0])
        raise RecordError(f"{name}: the angle reaches theta_cr = {theta_cr:g} rad at sample {k}, so the block overturns; "
                          "give the record of a block that rocks down to rest.")
    crossings = find_crossings(y, CROSSING_BAND_SIGMAS * noise)
    if not sequences or crossings.position.size == 0:
        return
    released = max(s.peaks[0] for s in sequences)
    tail = np.abs(y[int(np.floor(crossings.position[-1])) + 1 :])
    if tail.size and tail.max() > OVERTURN_FACTOR * released and tail[-1] > released:
        raise RecordError(f"{name}: after its last impact the angle rises to {tail.max():.3g} rad, beyond {OVERTURN_FACTOR:g} times the "
                          f"release angle ({released:.3g} rad), so the block overturns; give the record of a block that rocks down to rest.")


def _check_clipping(y, sequences, name):
    """Refuse a flat top at the record's extreme inside a flight (a clipped sensor)."""
    for value in (y.max(), y.min()):
        at = np.concatenate([[False], y == value, [False]]).astype(np.int8)
        starts, stops = np.flatnonzero(np.diff(at) == 1), np.flatnonzero(np.diff(at) == -1)
        for a, b in zip(starts, stops):
            inside = any(s.crossings[0] < a and b - 1 < s.crossings[-1] for s in sequences)
            if b - a >= CLIP_RUN and inside:
                raise RecordError(f"{name}: samples {a}-{b - 1} sit flat at {value:g} rad inside a flight, a clipped sensor; "
                                  "record with a range wider than the release angle.")


def _check_rest(y, sequences, name):
    """Refuse a record whose last release still rocks at its end above :data:`REST_FRACTION`."""
    last = sequences[-1]
    if last.stop.startswith("the record ends") and last.peaks[-1] > REST_FRACTION * last.peaks[0]:
        raise RecordError(f"{name}: the record ends while the block still rocks at {last.peaks[-1] / last.peaks[0]:.0%} of its "
                          "release angle, so it never comes to rest; record until the block is at rest.")


def _first_guess(sequence, y, dt, t0, model, theta_cr) -> tuple[np.ndarray, float]:
    """First guesses of the release and impact times (s) and of ``g`` (or ``nu``).

    ``g`` is the median of ``8 h/D^2`` over the flights (eq. 4: apex ``h``, duration ``D``
    between crossings), or ``2 h/D^2`` of the fall without a flight. The release is placed
    the model's fall time (eq. 4, or eq. 2 from rest) before the first impact, from the mean
    of the held samples, which the noise moves far less than the last sample still held.
    """
    crossings = t0 + sequence.crossings * dt
    held = np.abs(y[sequence.start : int(sequence.release) + 1])
    level = float(held.mean()) if held.size else float(sequence.peaks[0])
    flights = [8.0 * h / d**2 for h, d in zip(sequence.peaks[1:], np.diff(crossings))]
    fall = (sequence.crossings[0] - sequence.release) * dt
    g = float(np.median(flights)) if flights else 2.0 * level / max(fall, dt) ** 2
    if model == "simplified":
        q, fall = g, math.sqrt(2.0 * level / g)
    else:
        q = math.sqrt(g / theta_cr)
        fall = math.acosh(theta_cr / (theta_cr - level)) / q if level < theta_cr else fall
    return np.concatenate([[crossings[0] - fall], crossings]), q


def _interval(centre, se, log=False, z=None):
    """The :data:`CONFIDENCE` interval ``centre +- z se`` (``z`` the normal quantile unless
    given), exponentiated if ``log``."""
    if not (math.isfinite(centre) and math.isfinite(se)):
        return (math.nan, math.nan)
    z = stats.norm.ppf(0.5 + CONFIDENCE / 2) if z is None else z
    lo, hi = centre - z * se, centre + z * se
    return (math.exp(lo), math.exp(hi)) if log else (lo, hi)


def pooled_mean(values, ses):
    """Weighted mean of ``values`` and its standard error, widened by the Birge ratio."""
    values, ses = np.asarray(values), np.asarray(ses)
    ok = np.isfinite(values) & np.isfinite(ses) & (ses > 0)
    if not ok.any():
        return (float(values[0]), math.nan) if values.size else (math.nan, math.nan)
    w = 1.0 / ses[ok] ** 2
    mean = float(np.sum(w * values[ok]) / np.sum(w))
    se = float(1.0 / math.sqrt(np.sum(w)))
    if ok.sum() > 1:
        birge = math.sqrt(float(np.sum(w * (values[ok] - mean) ** 2)) / (ok.sum() - 1))
        se *= max(1.0, birge)
    return mean, se


def analyse_free_rocking(theta, dt, *, model: str = "simplified", theta_cr: float | None = None,
                         min_arc_samples: int = MIN_ARC_SAMPLES, load_noise=None) -> FreeRockingFit:
    """The coefficient of restitution from free-rocking records (paper §2: eqs. 2, 4, 6).

    Finds each release and each impact (zero crossing) of the record, fits the flight
    arcs between them with the model's closed-form free flight, and reads ``e`` per impact
    (eq. 6, the speeds of the arcs either side) and pooled over all impacts of all releases
    (the line of log speeds, :mod:`rockdec.free.analysis`), with 95 % intervals, and ``g``
    (or ``nu``) from the arcs. A release's analysis stops at the first arc with fewer than
    ``min_arc_samples`` samples, or too low to tell from the sensor noise; the result says
    where and why.

    Parameters
    ----------
    theta : array_like or list of array_like
        The rocking angle (rad), 1-D; or several records of one block (pooled). A record may
        hold several releases, each after the block came to rest.
    dt : float, array_like or list
        The sampling step (s); or the time stamps of the record (uniform, s); or one of
        either per record.
    model : {"simplified", "housner"}
        The flight between impacts: a parabola (eq. 4) or the linearised Housner solution
        (eq. 2, needs ``theta_cr``).
    theta_cr : float, optional
        The critical (overturning) angle (rad). Required by ``"housner"``; with either
        model it also gives ``nu = sqrt(g/theta_cr)`` and refuses a record that reaches it.
    min_arc_samples : int
        Fewest samples of a fitted arc between two impacts (>= 3).
    load_noise : float or list of float, optional
        A residual random load still acting on the block (a shake table that has not quite
        stopped): its intensity per record in units of the block's ``g^2`` (s; white
        acceleration of variance ``sigma^2 g^2`` sampled every ``dt`` has ``sigma^2 dt``).
        Its effect on the impact steps (:func:`load_covariance`) enters their covariance.

    Returns
    -------
    FreeRockingFit
        Per-impact table, pooled ``e`` with its interval, ``g``/``nu``, releases and where
        each analysis stopped; ``e`` NaN with ``reason`` set when fewer than
        :data:`MIN_IMPACTS` impacts can be fitted.

    Raises
    ------
    rockdec.validate.InputError
        For an unknown ``model``, a missing or invalid ``theta_cr``, ``dt`` or
        ``min_arc_samples``.
    rockdec.timeaxis.RecordError
        For a record that is not a free-rocking record: NaN or infinite samples, too short,
        constant, non-uniform time stamps, no release, a forced (random) response, a block
        that never comes to rest or overturns, a clipped sensor.

    Examples
    --------
    >>> from rockdec.physics.simulate import simulate_model
    >>> theta = simulate_model("simplified", [0], 600, dt=0.005, g=1.0, e=0.9, sigma_p=0.0, theta0=0.01)[0][0]
    >>> fit = analyse_free_rocking(theta, 0.005)
    >>> round(fit.e, 6), round(fit.g, 6), fit.n_impacts > 5
    (0.9, 1.0, True)
    """
    if model not in MODELS:
        raise checks.InputError(f"`model` {model!r}: not a rocking model; use {' or '.join(repr(m) for m in MODELS)}.")
    if theta_cr is not None:
        theta_cr = checks.positive(theta_cr, "`theta_cr`", "give the critical angle in rad, > 0")
    elif model == "housner":
        raise checks.InputError("`model` 'housner' needs `theta_cr`; give the critical angle in rad, or use the simplified model.")
    min_arc_samples = checks.integer(min_arc_samples, "`min_arc_samples`", 3)
    records = _records(theta, dt)
    many = len(records) > 1
    if load_noise is not None:
        load_noise = list(load_noise) if isinstance(load_noise, list | tuple) else [load_noise] * len(records)
        if len(load_noise) != len(records) or not all(math.isfinite(v) and v >= 0 for v in load_noise):
            raise checks.InputError(f"`load_noise` {load_noise!r}: give one finite intensity >= 0 per record, or one for all.")
    limit = amplitude_limit(MODEL_TOLERANCE)

    fits, seq_meta, notes, noises, scores = [], [], [], [], []
    for r, (y, step, t0, precision) in enumerate(records):
        name = f"theta[{r}]" if many else "theta"
        noise = noise_std(y)
        noises.append(noise)
        if theta_cr is not None:
            _check_overturn(y, noise, [], theta_cr, name)
        if find_crossings(y, CROSSING_BAND_SIGMAS * noise).position.size == 0:
            raise RecordError(f"{name}: no release found, the angle never swings past the noise band (+-{CROSSING_BAND_SIGMAS * noise:.3g} rad, "
                              f"{CROSSING_BAND_SIGMAS:g} noise standard deviations) on both sides of zero; give a record of a block "
                              "released from a tilt, sampled finely enough to show it rock.")
        try:
            sequences = find_sequences(y, noise, min_arc_samples)
        except RecordError as err:
            raise RecordError(f"{name}: {err}") from None
        if not sequences:
            raise RecordError(f"{name}: no release found, no fall from a held angle ends in an impact; give a record of a block released from a tilt.")
        _check_overturn(y, noise, sequences, None, name)
        _check_clipping(y, sequences, name)
        _check_rest(y, sequences, name)
        for seq in sequences:
            stop_time = t0 + seq.stop_position * step
            impact = seq.crossings[-1]
            reason = seq.stop.replace("{time}", f"{t0 + impact * step:.6g} s")
            last = int(np.floor(impact))
            t = t0 + step * np.arange(seq.start, last + 1)
            times0, q0 = _first_guess(seq, y, step, t0, model, theta_cr)
            try:
                fit = arcs.fit_sequence(t, y[seq.start : last + 1], side=seq.side, times0=times0, q0=q0, model=model,
                                        theta_cr=theta_cr, floor=precision)
            except ValueError:
                notes.append(f"{name}: the release at {times0[0]:.6g} s has too few samples to fit; left out.")
                continue
            if not (np.all(np.diff(fit.times) > 0) and fit.q > 0 and np.all(np.isfinite(fit.covariance))):
                notes.append(f"{name}: the fit of the release at {times0[0]:.6g} s did not converge; left out.")
                continue
            if noise > 0 and fit.residual_std > MISFIT_RATIO * noise:
                notes.append(f"{name}: the arcs after the release at {fit.times[0]:.6g} s scatter {fit.residual_std / noise:.3g} times the "
                             f"sensor noise about the {model} model's free flight; the pooled interval widens with the impacts' scatter (scatter_ratio)"
                             + ("; model='housner' may fit better." if model == "simplified" else "."))
            ratio = seq.peaks[0] / theta_cr if theta_cr else 0.0
            if model == "simplified" and ratio > limit:
                notes.append(f"{name}: the release at {fit.times[0]:.6g} s is {ratio:.2g} of theta_cr, where the periods of eqs. 3 and 5 "
                             f"differ by more than {MODEL_TOLERANCE:.0%}; model='housner' follows the flights there.")
            fits.append(fit)
            seq_meta.append((r, stop_time, reason))
            if model == "simplified":
                fitted = y[seq.start : last + 1]
                scores.append((t, fitted, precision, *flight_loss.loss_score(t, fitted, fit, precision)))
    loss, loss_se = pooled_mean([c for *_, c, _ in scores], [se for *_, se in scores]) if scores else (math.nan, math.nan)
    damped = None
    if loss > LOSS_Z * loss_se:  # the score test finds a loss in flight: the arcs are fitted with it
        damped = [flight_loss.fit_sequence(t, y_fit, fit, floor=precision, c0=c) for (t, y_fit, precision, c, _), fit in zip(scores, fits)]
    return _result(fits, seq_meta, notes, noises, model, theta_cr, damped, (loss, loss_se), load_noise)


def _impact_steps(fit, damped):
    """Of one release: each impact's ``log e``, their covariance, and the speeds landing
    before and leaving after each impact with their standard errors; from the arcs without
    loss (``damped`` None: neighbouring arcs' log speeds, ``D C D^T``) or with it
    (:func:`rockdec.free.flight_loss.log_ratios`)."""
    if damped is None:
        logs, cov = arcs.log_speeds(fit)
        speed, sd = np.exp(logs), np.sqrt(np.clip(np.diag(cov), 0.0, None))
        steps_cov = np.diff(np.diff(cov, axis=0), axis=1)
        return np.diff(logs), steps_cov, speed[:-1], speed[:-1] * sd[:-1], speed[1:], speed[1:] * sd[1:]
    steps, steps_cov = flight_loss.log_ratios(damped)
    landing, leaving = flight_loss.impact_speeds(damped)
    se = np.sqrt(np.clip(np.diag(steps_cov), 0.0, None))  # the step's error, shared by its two speeds
    return steps, steps_cov, landing, landing * se / math.sqrt(2.0), leaving, leaving * se / math.sqrt(2.0)


def load_covariance(fit, intensity: float) -> np.ndarray:
    """The covariance a residual random load adds to one release's impact steps (``log e``).

    A white load of ``intensity`` ``q`` (rad^2/s^3: the variance of the angular acceleration
    it adds times the step it is sampled at) moves the block's speed as a random walk,
    ``Var B(t) = q t``. The fitted arc's speed reads the mean of that walk over its flight
    (its duration sets the speed, eqs. 4, 6): off the speed it left with by the walk's mean
    ``Ī``, and off the speed it lands with by ``B(T) - Ī``, each of variance ``q T / 3``,
    their covariance ``q T / 6``; the fall from release is off by ``B(H)``, variance ``q H``.
    An impact step compares the landing of one arc with the leaving of the next, so
    neighbouring steps share an arc: relative to the arc's speed ``S``, the step's variance
    is ``q T/(3 S^2)`` of each arc and the covariance of neighbours ``-q T/(6 S^2)``.

    Examples
    --------
    >>> fit = arcs.SequenceFit(np.array([0.0, 1.0, 2.6, 3.9]), 2.0, np.zeros((5, 5)), 0.0, 10, 1, "simplified", None)
    >>> extra = load_covariance(fit, 0.01)
    >>> extra.shape, bool(extra[0, 1] < 0 < extra[0, 0])
    ((2, 2), True)
    """
    H = fit.half_durations
    speed = arcs.speed(H, fit.q, fit.model, fit.theta_cr)
    per_arc = intensity * 2.0 * H / (3.0 * speed**2)  # Var of the leaving and of the landing error, full flights
    landing = per_arc.copy()
    landing[0] = intensity * H[0] / speed[0] ** 2  # the fall from release
    n = H.size - 1
    out = np.diag(landing[:-1] + per_arc[1:])
    shared = -0.5 * per_arc[1:-1]
    out[np.arange(n - 1), np.arange(1, n)] = shared
    out[np.arange(1, n), np.arange(n - 1)] = shared
    return out


def _loss_in_flight(damped) -> tuple[float, float]:
    """The block's loss in flight ``c`` (1/s) pooled over the releases' fits with it, and its
    standard error."""
    c = np.array([d.c for d in damped])
    c_se = np.array([math.sqrt(max(d.covariance[-1, -1], 0.0)) for d in damped])
    return pooled_mean(c, c_se)


def _result(fits, seq_meta, notes, noises, model, theta_cr, damped, score, load_noise=None) -> FreeRockingFit:
    """Per-impact table and the pooled estimates of the fitted releases: from their fits
    with a loss in flight (``damped``, when the score test found one) or without; ``score``
    is the score test's pooled ``c`` and its standard error; ``load_noise``: per record, the
    intensity of a residual load in units of ``g^2`` (:func:`load_covariance`)."""
    with_loss = damped is not None
    loss, loss_se = _loss_in_flight(damped) if with_loss else score
    if with_loss:
        notes.append(f"the block loses speed in flight as well as at its impacts (theta'' = -g sign(theta) - c theta', c = {loss:.3g} "
                     f"+- {loss_se:.2g} per s): e is the impacts' share, flight_loss the flight's.")
    cols = {k: [] for k in ("time", "record", "release", "amp", "wb", "wb_se", "wa", "wa_se", "e", "e_se")}
    blocks, ys = [], []
    for s, (fit, (r, _, _)) in enumerate(zip(fits, seq_meta)):
        steps, steps_cov, landing, landing_se, leaving, leaving_se = _impact_steps(fit, damped[s] if with_loss else None)
        if load_noise is not None and load_noise[r] > 0:
            steps_cov = steps_cov + load_covariance(fit, load_noise[r] * fit.q**2)
        amp = arcs.shape(0.0, fit.half_durations, fit.q, model, theta_cr)[0]
        for i in range(steps.size):
            before_sign = -fit.side * (1.0 if i % 2 == 0 else -1.0)
            e_i = float(np.exp(steps[i]))
            cols["time"].append(fit.times[i + 1])
            cols["record"].append(r)
            cols["release"].append(s)
            cols["amp"].append(amp[i])
            cols["wb"].append(before_sign * landing[i])
            cols["wb_se"].append(landing_se[i])
            cols["wa"].append(before_sign * leaving[i])
            cols["wa_se"].append(leaving_se[i])
            cols["e"].append(e_i)
            cols["e_se"].append(e_i * math.sqrt(max(steps_cov[i, i], 0.0)))
        blocks.append(steps_cov)
        ys.append(steps)
    n_impacts = len(cols["e"])
    e, log_se, birge, dof, interval, reason = math.nan, math.nan, math.nan, 0, (math.nan, math.nan), None
    spread, spread_interval = math.nan, (math.nan, math.nan)
    if n_impacts < MIN_IMPACTS:
        reason = (f"only {n_impacts} impact{'s' if n_impacts != 1 else ''} could be fitted, fewer than the {MIN_IMPACTS} a pooled e "
                  "with an interval needs; record more samples per cycle, a larger release angle or more releases.")
    else:
        pooled = impact_mean(ys, blocks)
        e, birge, dof = math.exp(pooled.mu), pooled.scatter, pooled.dof
        log_se = max(pooled.se, SAMPLE_PRECISION)
        if not pooled.quantile * log_se <= WIDEST_LOG_HALF_WIDTH:  # NaN too
            reason = (f"the {n_impacts} impacts' e scatter too widely for an interval (log e known to +-{pooled.quantile * log_se:.3g}); "
                      "record more samples per cycle or more releases, or look for a release that is not free.")
        else:
            interval = _interval(pooled.mu, log_se, log=True, z=pooled.quantile)
        spread, spread_interval = e * pooled.tau, tuple(e * t for t in pooled.tau_interval)
        if dof == 0:
            notes.append("one impact only: its interval rests on the fit alone, with no check of the impacts' scatter.")
    above = np.asarray(cols["e"]) > 1.0
    for s in range(len(fits)):
        mine = above[np.asarray(cols["release"], dtype=int) == s]
        if mine.size >= 2 and mine.mean() > 0.5:
            notes.append(f"release {s + 1}: {int(mine.sum())} of its {mine.size} impacts return more speed than they receive "
                         "(ratio above 1), which a free block cannot do on average: a bounce, a second contact or the sensor; "
                         "look at this release's record.")
    trend, trend_se, at_reference, at_reference_se, reference_speed = _trend(ys, blocks, cols["wb"])
    e_reference = math.exp(at_reference) if math.isfinite(at_reference) else math.nan
    e_reference_interval = _interval(at_reference, at_reference_se, log=True)
    if abs(trend) > TREND_Z * trend_se:
        notes.append(f"e changes with the impact speed: e = {e_reference:.4f} [{e_reference_interval[0]:.4f}, {e_reference_interval[1]:.4f}] "
                     f"at {reference_speed:.3g} rad/s (the impacts' geometric mean speed), and log e changes by {trend:.3g} +- {trend_se:.2g} "
                     f"per unit of log speed, where the {model} model holds it constant; the pooled e is the impacts' mean.")
    if with_loss:  # g is the second-last parameter of a fit with c
        q, q_var = np.array([d.g for d in damped]), np.array([d.covariance[-2, -2] for d in damped])
    else:
        q, q_var = np.array([f.q for f in fits]), np.array([f.covariance[-1, -1] for f in fits])
    q_se = np.sqrt(np.clip(q_var, 0.0, None))
    q_mean, q_mean_se = pooled_mean(q, q_se) if fits else (math.nan, math.nan)
    q_interval = _interval(q_mean, q_mean_se)
    if model == "simplified":
        g, g_interval = q_mean, q_interval
        root = (lambda v: math.sqrt(v / theta_cr) if v > 0 else 0.0) if theta_cr else (lambda v: math.nan)
        nu, nu_interval = root(g) if math.isfinite(g) else math.nan, tuple(root(v) if math.isfinite(v) else math.nan for v in g_interval)
        release_g = q
    else:
        nu, nu_interval = q_mean, q_interval
        g = nu**2 * theta_cr
        g_interval = tuple(max(v, 0.0) ** 2 * theta_cr for v in nu_interval)
        release_g = q**2 * theta_cr
    return FreeRockingFit(
        model=model, theta_cr=theta_cr, e=e, e_interval=interval, confidence_level=CONFIDENCE, log_e_se=log_se,
        scatter_ratio=birge, dof=dof, g=g, g_interval=tuple(g_interval), nu=nu, nu_interval=tuple(nu_interval), reason=reason,
        impact_time=np.array(cols["time"]), impact_record=np.array(cols["record"], dtype=int),
        impact_release=np.array(cols["release"], dtype=int), amplitude_before=np.array(cols["amp"]),
        omega_before=np.array(cols["wb"]), omega_before_se=np.array(cols["wb_se"]), omega_after=np.array(cols["wa"]),
        omega_after_se=np.array(cols["wa_se"]), e_impact=np.array(cols["e"]), e_impact_se=np.array(cols["e_se"]),
        release_time=np.array([f.times[0] for f in fits]),
        release_angle=np.array([f.side * arcs.shape(0.0, f.half_durations[0], f.q, model, theta_cr)[0] for f in fits]),
        release_record=np.array([m[0] for m in seq_meta], dtype=int), release_g=np.asarray(release_g, dtype=float),
        stop_time=np.array([m[1] for m in seq_meta]), stop_reason=tuple(m[2] for m in seq_meta),
        residual_std=np.array([f.residual_std for f in fits]), fitted_times=tuple(f.times for f in fits), fitted_q=q,
        noise_std=np.array(noises), e_trend=trend, e_trend_se=trend_se, e_reference=e_reference,
        e_reference_interval=e_reference_interval, reference_speed=reference_speed, e_spread=spread, e_spread_interval=tuple(spread_interval),
        impacts_above_one=int(above.sum()), flight_loss=loss, flight_loss_interval=_interval(loss, loss_se),
        loss_in_flight=with_loss, notes=tuple(notes),
    )


def _block_diagonal(blocks) -> np.ndarray:
    """The block-diagonal matrix of square ``blocks``."""
    size = sum(b.shape[0] for b in blocks)
    out = np.zeros((size, size))
    at = 0
    for b in blocks:
        out[at : at + b.shape[0], at : at + b.shape[0]] = b
        at += b.shape[0]
    return out


def _gls(y, X, V):
    """Generalised least squares of ``y`` on ``X`` with covariance ``V``: the coefficients,
    their covariance and the chi-square of the residuals. ``V`` is whitened through its
    eigen-decomposition, with eigenvalues held above ``1e-14`` of the largest (a noise-free
    record's covariance is near-singular)."""
    w, U = np.linalg.eigh(V)
    floor = max(w.max(), np.finfo(float).tiny) * 1e-14
    scale = 1.0 / np.sqrt(np.maximum(w, floor))
    Xw, yw = scale[:, None] * (U.T @ X), scale * (U.T @ y)
    beta, *_ = np.linalg.lstsq(Xw, yw, rcond=None)
    return beta, np.linalg.pinv(Xw.T @ Xw), float(np.sum((yw - Xw @ beta) ** 2))


class ImpactMean(NamedTuple):
    """The pooled ``mu = log e`` of the impacts (module docstring): its standard error, the
    scatter of the steps over their fit errors alone (``sqrt(Q(0)/dof)``), the degrees of
    freedom, the impacts' spread ``tau`` of ``log e`` with its 95 % interval, and the
    quantile of the interval of ``mu`` (normal with ``tau = 0``, Student's ``t`` otherwise)."""

    mu: float
    se: float
    scatter: float
    dof: int
    tau: float
    tau_interval: tuple[float, float]
    quantile: float


def impact_mean(steps, covariances) -> ImpactMean:
    """Each release's impacts' ``log e`` (``steps``, covariances ``covariances``: ``D C D^T``
    without loss in flight) pooled into one ``mu`` under the covariance plus ``tau^2 I``,
    ``tau^2`` by Paule-Mandel and its interval by the Q-profile (module docstring). Each
    release's covariance is diagonalised once, its eigenvalues held above ``1e-14`` of the
    largest (a noise-free record's covariance is near-singular), so ``Q(tau^2)`` costs a sum."""
    parts = []
    for d, c in zip(steps, covariances):
        if d.size >= 1:
            w, U = np.linalg.eigh(c)
            parts.append((U.T @ d, U.sum(axis=0), w))
    floor = max(max(float(w.max()) for _, _, w in parts), np.finfo(float).tiny) * 1e-14

    def weighted(tau2):
        inv = [1.0 / np.maximum(w + tau2, floor) for _, _, w in parts]
        a = sum(float(o @ (i * o)) for (_, o, _), i in zip(parts, inv))
        mu = sum(float(o @ (i * d)) for (d, o, _), i in zip(parts, inv)) / a
        q = sum(float(np.sum(i * (d - mu * o) ** 2)) for (d, o, _), i in zip(parts, inv))
        return mu, 1.0 / math.sqrt(a), q

    dof = sum(d.size for d, _, _ in parts) - 1
    steps = np.concatenate([d for d, _, _ in parts])
    q0 = weighted(0.0)[2]

    def tau2_at(target):  # Q falls as tau^2 grows: the tau^2 where it meets target (0 if below already)
        if not q0 > target:
            return 0.0
        high = max(float(np.var(steps)), floor)
        while weighted(high)[2] > target:
            high *= 4.0
        return optimize.brentq(lambda t2: weighted(t2)[2] - target, 0.0, high, xtol=1e-14 * high, rtol=1e-12)

    if dof < 1:
        mu, se, _ = weighted(0.0)
        return ImpactMean(mu, se, math.nan, dof, math.nan, (math.nan, math.nan), stats.norm.ppf(0.5 + CONFIDENCE / 2))
    tau2 = tau2_at(dof)
    low, high = (math.sqrt(tau2_at(stats.chi2.ppf(p, dof))) for p in (0.5 + CONFIDENCE / 2, 0.5 - CONFIDENCE / 2))
    if q0 > stats.chi2.ppf(SCATTER_LEVEL, dof):  # the impacts scatter beyond their fits: the log speeds walk
        mu, se, _ = weighted(tau2)
        quantile = stats.t.ppf(0.5 + CONFIDENCE / 2, dof)
    else:  # the line of log speeds, widened by the Birge ratio where it exceeds 1
        mu, se, _ = weighted(0.0)
        se *= max(1.0, math.sqrt(q0 / dof))
        quantile = stats.norm.ppf(0.5 + CONFIDENCE / 2)
    return ImpactMean(mu, se, math.sqrt(q0 / dof), dof, math.sqrt(tau2), (low, high), float(quantile))


def _trend(steps, covariances, speeds) -> tuple[float, float, float, float, float]:
    """``log e_i = a + b log(S_i/S_ref)``, the impacts' ``log e`` on the log of the speed
    landing at each impact about its geometric mean ``S_ref``, by GLS (standard errors
    widened by the Birge ratio above 1): ``(b, se of b, a, se of a, S_ref)``; ``b`` NaN with
    fewer than three impacts or one speed. ``steps`` and ``covariances`` are each release's
    ``log e_i`` and their covariance (neighbours are correlated: ``D C D^T`` of the log speeds)."""
    y = np.concatenate(steps) if steps else np.empty(0)
    covs = [c for c in covariances if c.size]
    x = np.log(np.abs(np.asarray(speeds, dtype=float)))
    if y.size < 3 or not np.all(np.isfinite(x)) or np.ptp(x) == 0.0:
        return math.nan, math.nan, math.nan, math.nan, math.nan
    reference = float(np.mean(x))
    beta, cov, chi2 = _gls(y, np.column_stack([np.ones_like(x), x - reference]), _block_diagonal(covs))
    widen = max(1.0, math.sqrt(chi2 / (y.size - 2)))
    return (float(beta[1]), float(math.sqrt(max(cov[1, 1], 0.0)) * widen), float(beta[0]),
            float(math.sqrt(max(cov[0, 0], 0.0)) * widen), math.exp(reference))

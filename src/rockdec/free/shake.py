"""A shake-table test: ``e`` from the free-decay tails after the shaking stops.

The base acceleration is read as the simplified rocking equation's load against the uplift
level (``g tan(alpha)`` in m/s^2, or the block's ``g`` in rad/s^2): below it a block at rest
stays at rest. The shaking ends after 95 % of the base's Arias intensity and after the last
sample above :data:`QUIET` of the uplift level; every stretch as quiet as that, at least
:data:`MIN_TAIL` s long, after the base first could lift the block, is a free-decay tail,
analysed by :func:`rockdec.free.analysis.analyse_free_rocking`: the tails of one record
together, and the records of one block pooled by their errors (as the forced reading pools
them, :func:`rockdec.free.analysis.pooled_mean`), since one impact spread for every record
would weigh a precise record down by a noisy one. A tail whose base still moves (a cut by hand) is refused with that
reason, never fitted as if free. Beside the tails, each whole record is read with the base as
a known load in its arcs (:mod:`rockdec.free.forced`, the simplified model), its impacts
pooled over the records. Entry point: :func:`analyse_shake_table`.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from scipy import stats

from rockdec import validate as checks
from rockdec.free.analysis import FreeRockingFit, analyse_free_rocking, pooled_mean
from rockdec.free.forced import ForcedFit, analyse_forced, pool_forced
from rockdec.free.impacts import CROSSING_BAND_SIGMAS, find_crossings, noise_std
from rockdec.timeaxis import RecordError

__all__ = ["BASE_UNITS", "BASE_UNIT_NAMES", "ShakeTableFit", "analyse_shake_table", "base_units_named", "load_intensity", "shaking_end",
           "uplift_ratio"]

#: Fraction of the uplift level below which the base counts as quiet (its load then moves a
#: rocking block's impact speeds by well under the sensor's resolution of them).
QUIET = 0.05

#: Share of the base's Arias intensity after which the shaking may end.
ARIAS = 0.95

#: Fewest seconds of a free-decay tail.
MIN_TAIL = 1.0

#: Standard gravity, m/s^2.
G0 = 9.80665

BASE_UNITS = ("m/s2", "g", "rad/s2")

#: Other spellings of :data:`BASE_UNITS` a file's or a DataArray's ``units`` may carry.
BASE_UNIT_NAMES = {"m s-2": "m/s2", "m/s^2": "m/s2", "m/s**2": "m/s2", "rad s-2": "rad/s2", "rad/s^2": "rad/s2"}

#: Seconds over which the base's residual motion in a tail is integrated to read its
#: intensity (:func:`load_intensity`).
LOAD_WINDOW = 0.5


@dataclass(frozen=True)
class ShakeTableFit:
    """What :func:`analyse_shake_table` found: the pooled free-rocking ``fit`` of the
    accepted tails (``None`` when none), ``shaking_end`` per record (s, NaN when it never
    ends), ``tails`` (record, start s, stop s) accepted with their ``tail_fits`` and the base's
    residual motion in each (``tail_loads``, :func:`load_intensity`), ``refused``
    (record, start s, reason) and ``reason`` (why there is no ``e``; ``None`` when there is);
    ``forced``: each record read with the base as a known load
    (:func:`rockdec.free.forced.analyse_forced`) and ``forced_pooled`` their impacts together
    (empty and ``None`` under the Housner model, which it does not fit); ``record_fits``: with
    tails in more than one record, each record's tails analysed together, whose ``e`` pooled
    by their errors is the tails' ``e`` (:attr:`e`)."""

    fit: FreeRockingFit | None
    shaking_end: tuple[float, ...]
    tails: tuple[tuple[int, float, float], ...]
    tail_fits: tuple[FreeRockingFit, ...]
    tail_loads: tuple[float, ...]
    refused: tuple[tuple[int, float, str], ...]
    reason: str | None
    forced: tuple[ForcedFit, ...] = ()
    forced_pooled: ForcedFit | None = None
    record_fits: tuple[FreeRockingFit, ...] = ()

    @property
    def e(self) -> float:
        """The tails' ``e`` (NaN without one): :attr:`fit`'s, or with tails in several records
        theirs pooled by their errors (:attr:`log_e_se`)."""
        return self._tails[0]

    @property
    def e_interval(self) -> tuple[float, float]:
        """Its interval at the tails' ``confidence_level`` (95 %): Student's ``t`` at the
        records' degrees of freedom summed."""
        return self._tails[1]

    @property
    def log_e_se(self) -> float:
        """The standard error of the tails' ``log e``, widened by the records' scatter beyond
        their errors (the Birge ratio) when several are pooled."""
        return self._tails[2]

    @functools.cached_property
    def _tails(self) -> tuple[float, tuple[float, float], float]:
        none = (math.nan, (math.nan, math.nan), math.nan)
        if self.fit is None or self.fit.reason:
            return none
        answered = [f for f in self.record_fits if f.reason is None and math.isfinite(f.e) and math.isfinite(f.log_e_se)]
        if len(answered) < 2:
            return self.fit.e, self.fit.e_interval, self.fit.log_e_se
        mu, se = pooled_mean([math.log(f.e) for f in answered], [f.log_e_se for f in answered])
        half = float(stats.t.ppf(0.5 + self.fit.confidence_level / 2, sum(f.dof for f in answered))) * se
        return math.exp(mu), (math.exp(mu - half), math.exp(mu + half)), se

    @property
    def answer(self) -> tuple[str | None, float, tuple[float, float]]:
        """The test's ``e``: of the tails' (``"impacts"``) and every impact's with the base a
        known load (``"forced"``), the one with the narrower interval, as ``(source, e,
        interval)``; ``(None, nan, (nan, nan))`` when neither answers."""
        readings = [("impacts", self.e, self.e_interval)]
        if self.forced_pooled is not None and self.forced_pooled.reason is None:
            readings.append(("forced", self.forced_pooled.e, self.forced_pooled.e_interval))
        answered = [r for r in readings if math.isfinite(r[1])]
        if not answered:
            return None, math.nan, (math.nan, math.nan)
        return min(answered, key=lambda r: r[2][1] - r[2][0])


def base_units_named(units) -> str:
    """The :data:`BASE_UNITS` spelling of a stated ``units`` attribute (as given when unknown).

    Examples
    --------
    >>> base_units_named(" m s-2"), base_units_named("g"), base_units_named("furlong")
    ('m/s2', 'g', 'furlong')
    """
    text = str(units).strip()
    return BASE_UNIT_NAMES.get(text, text)


def uplift_ratio(base, *, base_units: str = "m/s2", g_block: float | None = None, theta_cr: float | None = None) -> np.ndarray:
    """The base acceleration over the uplift level (``|ratio| > 1`` can lift the block).

    ``base_units`` "m/s2" or "g" need the critical angle ``theta_cr`` (level ``g tan(alpha)``);
    "rad/s2" (the load of the simplified rocking equation) needs the block's ``g_block``.

    Examples
    --------
    >>> uplift_ratio([0.0, 2.0, -4.0], base_units="rad/s2", g_block=2.0).tolist()
    [0.0, 1.0, -2.0]
    """
    if base_units not in BASE_UNITS:
        raise checks.InputError(f"`base_units` {base_units!r} is not one of {', '.join(BASE_UNITS)}; declare the base record's units.")
    a = np.asarray(base, dtype=float)
    if base_units == "rad/s2":
        if g_block is None:
            raise checks.InputError("a base in rad/s2 needs `g_block`, the block's g in rad/s^2; give it, or the base in m/s2 with the block.")
        return a / checks.positive(g_block, "`g_block`", "give the block's g in rad/s^2")
    if theta_cr is None:
        raise checks.InputError(f"a base in {base_units} needs the block's critical angle; give block=(H, B) or theta_cr in rad.")
    level = math.tan(checks.positive(theta_cr, "`theta_cr`", "give the critical angle in rad")) * (G0 if base_units == "m/s2" else 1.0)
    return a / level


def shaking_end(ratio, dt: float, *, quiet: float = QUIET, arias: float = ARIAS) -> int:
    """Index of the first sample after the shaking: past ``arias`` of the Arias intensity and
    past the last sample above ``quiet`` of the uplift level (``len(ratio)`` if it never ends).

    Examples
    --------
    >>> shaking_end([0, 2, -2, 0.01, 0.0, 0.0], 0.01)
    3
    """
    r = np.asarray(ratio, dtype=float)
    energy = np.cumsum(r * r)
    i_arias = int(np.searchsorted(energy, arias * energy[-1])) + 1 if energy[-1] > 0 else 0
    loud = np.flatnonzero(np.abs(r) > quiet)
    return max(i_arias, int(loud[-1]) + 1 if loud.size else 0)


def load_intensity(ratio, dt: float, window: float = LOAD_WINDOW) -> float:
    """The intensity (s) of the base's residual motion ``ratio`` (in units of the uplift
    level, its mean taken out): the mean square of its integral over windows of ``window`` s,
    per second; for white noise of variance ``sigma^2`` sampled every ``dt``, ``sigma^2 dt``.

    Examples
    --------
    >>> r = np.random.default_rng(0).standard_normal(200_000) * 0.01
    >>> round(load_intensity(r, 0.005) / (0.01**2 * 0.005), 1)
    1.0
    """
    r = np.asarray(ratio, dtype=float)
    r = r - r.mean()
    n = max(1, min(r.size, int(round(window / dt))))
    sums = r[: r.size // n * n].reshape(-1, n).sum(axis=1) * dt
    return float(np.mean(sums**2) / (n * dt))


def _quiet_runs(r, quiet, n_min):
    """``(start, stop)`` of each run of ``|r| <= quiet`` at least ``n_min`` long after the first uplift."""
    lifted = np.flatnonzero(np.abs(r) > 1.0)
    if lifted.size == 0:
        return []
    calm = np.abs(r) <= quiet
    calm[: lifted[0] + 1] = False
    edges = np.flatnonzero(np.diff(np.concatenate([[0], calm.astype(np.int8), [0]])))
    return [(int(a), int(b)) for a, b in zip(edges[::2], edges[1::2]) if b - a >= n_min]


def first_impact(theta, i0: int, i1: int) -> int:
    """The first sample after the first impact (zero crossing, :func:`rockdec.free.impacts.find_crossings`)
    of ``theta[i0:i1]``, ``i0`` when it has none: a tail that starts as the block falls holds
    the end of an arc whose apex it never saw, so the arcs after it would seem to grow.

    Examples
    --------
    >>> t = np.arange(400) * 0.01
    >>> first_impact(0.01 * np.cos(2 * np.pi * t), 0, 400)  # falling from the start, the impact at 0.25 s
    26
    """
    y = np.asarray(theta[i0:i1], dtype=float)
    crossings = find_crossings(y, CROSSING_BAND_SIGMAS * noise_std(y)) if y.size >= 8 else None
    return i0 + int(np.floor(crossings.position[0])) + 1 if crossings is not None and crossings.position.size else i0


def analyse_shake_table(theta, base, dt, *, base_units: str = "m/s2", g_block: float | None = None,
                        theta_cr: float | None = None, model: str = "simplified", start: float | None = None,
                        quiet: float = QUIET, min_tail: float = MIN_TAIL) -> ShakeTableFit:
    """``e`` from shake-table records: the free-decay tails after the shaking, pooled.

    Parameters
    ----------
    theta, base : array_like or list of array_like
        The block's angle (rad) and the base acceleration (``base_units``), one sample each
        per step; a list of records of one block is pooled.
    dt : float or list of float
        The sampling step (s), or one per record.
    base_units, g_block, theta_cr
        As :func:`uplift_ratio`.
    model : {"simplified", "housner"}
        The free flight the tails are fitted with (:func:`rockdec.free.analysis.analyse_free_rocking`).
    start : float, optional
        A tail cut by hand (s from each record's start) instead of the quiet stretches; refused
        if the base still moves after it.
    quiet, min_tail
        :data:`QUIET` and :data:`MIN_TAIL`.

    Examples
    --------
    >>> from rockdec.physics.simulate import simulate_model
    >>> free = simulate_model("simplified", [0], 2000, dt=0.005, g=2.0, e=0.9, sigma_p=0.0, theta0=0.01)[0][0]
    >>> theta = np.concatenate([np.zeros(400), free])
    >>> base = np.concatenate([np.where(np.arange(400) % 2, 3.0, -3.0), np.zeros(2000)])
    >>> res = analyse_shake_table(theta, base, 0.005, base_units="rad/s2", g_block=2.0)
    >>> round(res.e, 6), res.shaking_end
    (0.9, (2.0,))
    """
    many = isinstance(theta, (list, tuple)) and len(theta) > 0 and np.ndim(theta[0]) == 1
    thetas, bases = (list(theta), list(base)) if many else ([theta], [base])
    if len(thetas) != len(bases):
        raise RecordError(f"{len(thetas)} records but {len(bases)} base records; give one base acceleration per record.")
    per_record = list(dt) if isinstance(dt, (list, tuple)) else [dt] * len(thetas)
    if len(per_record) != len(thetas):
        raise RecordError(f"{len(thetas)} records but {len(per_record)} steps `dt`; give one step, or one per record.")
    ends, tails, pieces, steps, fits, refused, loads, forced = [], [], [], [], [], [], [], []
    for k, (y, b, dt) in enumerate(zip(thetas, bases, per_record)):
        dt = checks.positive(dt, "`dt`", "give the sampling step in s, > 0")
        name = f"record {k}" if many else "the record"
        y, b = np.asarray(y, dtype=float), np.asarray(b, dtype=float)
        if b.ndim != 1 or b.size != y.size:
            raise RecordError(f"{name}: the base has {b.size} samples for {y.size} angles; give the base sampled with the angle, one value per sample.")
        if not np.all(np.isfinite(b)):
            raise RecordError(f"{name}: the base acceleration has a NaN or infinite sample ({int(np.flatnonzero(~np.isfinite(b))[0])}); fill or cut it.")
        r = uplift_ratio(b, base_units=base_units, g_block=g_block, theta_cr=theta_cr)
        if model == "simplified":
            forced.append(analyse_forced(y, r, dt) if np.all(np.isfinite(y)) else ForcedFit.none("the angle has a NaN or infinite sample"))
        end = shaking_end(r, dt, quiet=quiet)
        n_min = max(int(round(min_tail / dt)), 8)
        ends.append(end * dt if y.size - end >= n_min else math.nan)
        if start is not None:
            i0 = int(round(checks.positive(start, "`start`", "give the tail's start in s") / dt))
            peak = float(np.max(np.abs(r[i0:]))) if i0 < y.size else 0.0
            if peak > 1.0:
                refused.append((k, i0 * dt, f"the base still moves above the uplift level after {i0 * dt:.6g} s (up to {peak:.3g} times it); "
                                            "the tail is not a free decay: cut it after the shaking ends"))
                continue
            if peak > quiet:
                refused.append((k, i0 * dt, f"the base still moves after {i0 * dt:.6g} s ({peak:.2g} of the uplift level), which rocks the block; "
                                            "cut the tail after the shaking ends"))
                continue
            runs = [(i0, y.size)]
        else:
            runs = _quiet_runs(r, quiet, n_min)
            if not runs:
                refused.append((k, 0.0, "the base never lifts the block" if not np.any(np.abs(r) > 1.0) else
                                f"the shaking never stops: the base never stays below {quiet:g} of the uplift level for {min_tail:g} s"))
                continue
        for quiet_start, i1 in runs:
            i0 = first_impact(y, quiet_start, i1)
            t = dt * np.arange(i0, i1)
            load = load_intensity(r[i0:i1], dt)
            try:
                fit = analyse_free_rocking(y[i0:i1], t, model=model, theta_cr=theta_cr, load_noise=load)
            except RecordError as err:
                refused.append((k, i0 * dt, str(err).removeprefix("theta: ")))
                continue
            if fit.reason:
                refused.append((k, i0 * dt, fit.reason))
                continue
            tails.append((k, i0 * dt, i1 * dt))
            loads.append(load)
            pieces.append(y[i0:i1])
            steps.append(t)
            fits.append(fit)
    pooled = None
    if pieces:
        pooled = analyse_free_rocking(pieces if len(pieces) > 1 else pieces[0], steps if len(steps) > 1 else steps[0], model=model,
                                      theta_cr=theta_cr, load_noise=loads)
    owners = [k for k, _, _ in tails]
    record_fits = []
    if len(set(owners)) > 1:
        for k in sorted(set(owners)):
            mine = [j for j, owner in enumerate(owners) if owner == k]
            record_fits.append(fits[mine[0]] if len(mine) == 1 else
                               analyse_free_rocking([pieces[j] for j in mine], [steps[j] for j in mine], model=model, theta_cr=theta_cr,
                                                    load_noise=[loads[j] for j in mine]))
    if pooled is not None:
        reason = pooled.reason
    else:
        reason = "no free-decay tail gives an e: " + "; ".join(f"{'record %d at ' % k if many else ''}{s:.6g} s: {why}" for k, s, why in refused)
    return ShakeTableFit(pooled, tuple(ends), tuple(tails), tuple(fits), tuple(loads), tuple(refused), reason, tuple(forced),
                         pool_forced(forced) if forced else None, tuple(record_fits))

"""Exact event-driven simulation of the simplified rocking model (paper eqs. 4, 6, 21-24).

``theta'' = -g sign(theta) + F(t)`` with ``g = nu^2 theta_cr`` (eq. 4), the angular velocity
multiplied by ``e`` at every zero crossing (eq. 6), the load velocity impulses
``p_n ~ N(0, sigma_p^2)`` at the end of every step (white, low-pass or of a spectrum:
:func:`rockdec.physics.loading.draw_impulses`), so between impulses the motion is a parabola,
integrated exactly (eqs. 21-24). :func:`flight` also handles what the printed scheme leaves
out: several crossings in one step, the chattering limit in closed form, a crossing root that
never cancels, ``e = 1`` and ``e = 0``. Sampling: ``theta[n]`` is the angle at ``t = n dt``,
``theta_dot[n]`` the velocity just after the impulse applied then (eq. 21).

:func:`integrate` and :func:`simulate_block` run series, :func:`simulate_model` the model a
run names, :func:`simulation_dataset` adds labels and Dask; :func:`calibrate_dt` and
:func:`secant_step` are the step search (its constants here and in
:mod:`rockdec.physics.models`), :func:`default_burn_in` the burn-in.

Explanation: docs/explanation/method/simulation.md (§3.2-3.4).
"""

from __future__ import annotations

import math

import numba
import numpy as np
import xarray as xr

from rockdec.physics.fixed_step import step as grid_step
from rockdec.physics.housner import simulate_block_housner
from rockdec import validate as checks
from rockdec.physics.loading import add_sensor_noise, check_load, check_seeds, draw_impulses, draw_series, series_rng, stream_words
from rockdec.physics.models import SCALE_CONSTANT_GUESS, check_finite_series, check_run, period_from_g, scale_constant, step_for_density

__all__ = [
    "PILOT_POINTS", "PILOT_SEED_OFFSET", "PILOT_SERIES", "STATISTICS_PILOT_SERIES", "STEP_ITERATIONS",
    "calibrate_dt", "default_burn_in", "flight", "integrate", "pilot_statistics", "secant_step",
    "simulate_block", "simulate_model", "simulation_dataset",
]

#: Largest number of correction steps when the closed-form flight count is off by rounding.
_COUNT_FIX = 4

#: Passes of the flight loop before giving up with NaN. A valid state needs at most three
#: (crossing, closed-form bounces, last arc); only NaN or overflow could loop for ever.
_MAX_PASSES = 64

#: Pilot runs draw seeds from here on, apart from any scene's seeds.
PILOT_SEED_OFFSET = 2**62

#: Pilot of the step search (:func:`calibrate_dt`): series and points. The response is
#: heavy-tailed, so the pilot is large (how closely it pins ``sigma_Y``:
#: docs/explanation/constants.md).
PILOT_SERIES, PILOT_POINTS = 256, 40_000

#: Updates of the step in :func:`calibrate_dt`, per load kind: under white noise the scale law
#: converges in 3; a coloured load's exponent is measured from the pilots (:func:`secant_step`).
STEP_ITERATIONS = {"white": 3, "lowpass": 12, "spectrum": 12}

#: Pilots whose least-squares slope gives the exponent of :func:`secant_step`, and the range
#: the exponent is held to: with the corner at the rocking frequency the pilot's samples per
#: cycle scatter at one step, and the slope of the last two pilots alone can send the step
#: far off (docs/explanation/constants.md).
SECANT_POINTS, SECANT_EXPONENTS = 3, (1.0, 10.0)

#: Series of the pilot that measures the statistics at a given step, or under a model other
#: than the one the step search ran (:func:`rockdec.physics.run.from_scene`), of :data:`PILOT_POINTS`.
STATISTICS_PILOT_SERIES = 64

#: Largest default burn-in, in steps; beyond it the caller must choose one.
MAX_DEFAULT_BURN_IN = 10**7

#: The ``time`` coordinate of a simulation: seconds from the end of the burn-in. CF 1.10
#: (section 4.4) asks a time coordinate for a reference date; the epoch stands for that
#: instant, so xarray reads ``time`` as dates from 1970-01-01 (``time - time[0]`` in s). The
#: proleptic Gregorian calendar: the ``standard`` one draws a CF note, its 1582 switch unused.
TIME_ATTRS = {
    "units": "seconds since 1970-01-01 00:00:00",
    "calendar": "proleptic_gregorian",
    "standard_name": "time",
    "long_name": "time since the end of the burn-in",
}

#: Longest record, in s, whose times still decode as dates (NumPy ``datetime64[ns]`` ends
#: in 2262): a longer one would make the file unreadable to a plain ``xarray.open_dataset``.
MAX_RECORD_SECONDS = 9.2e9


@numba.njit(nogil=True, cache=True, forceinline=True)
def flight(theta, omega, duration, g, e):
    """Advance ``(theta, omega)`` by ``duration`` seconds of free rocking (no load).

    Exact for the simplified model (eqs. 4, 6, 22-24), any number of impacts, the rest
    state included. Returns the new ``(theta, omega)``; ``(nan, nan)`` for a state or
    step that is NaN (the loop is bounded by :data:`_MAX_PASSES`). Numba compiles it once;
    LLVM inlines it into its callers (``forceinline``), so the integrator's loop runs it
    without a call and numba never types it a second time inside a caller.
    """
    remaining = duration
    if remaining != remaining:  # a NaN step: NaN, whatever the state (even at rest)
        return math.nan, math.nan
    for _ in range(_MAX_PASSES):
        if theta == 0.0 and omega == 0.0:
            return 0.0, 0.0
        if theta > 0.0 or (theta == 0.0 and omega > 0.0):
            side = 1.0
        else:
            side = -1.0
        h = side * theta  # height above zero, >= 0
        u = side * omega  # speed away from zero
        h_end = h + remaining * (u - 0.5 * g * remaining)
        if h_end > 0.0 or remaining <= 0.0:
            return side * h_end, side * (u - g * remaining)
        # A crossing inside the interval (the concave parabola stays below zero after it).
        sq = math.sqrt(u * u + 2.0 * g * h)  # impact speed
        if u >= 0.0:
            t_cross = (u + sq) / g
        else:
            t_cross = 2.0 * h / (sq - u)
        if t_cross > remaining:  # rounding: h_end <= 0 says the crossing is inside
            t_cross = remaining
        remaining -= t_cross
        w = e * sq  # speed after the impact, now on the other side
        side = -side
        if w == 0.0:
            return 0.0, 0.0
        f1 = 2.0 * w / g  # duration of the first bounce
        if f1 > remaining:
            theta = 0.0
            omega = side * w
            continue
        # Whole bounces that fit: k with S_k = f1 (1 - e^k)/(1 - e) <= remaining.
        if e < 1.0:
            if f1 <= remaining * (1.0 - e):  # the whole geometric series fits: rest
                return 0.0, 0.0
            k = math.floor(math.log1p(-remaining * (1.0 - e) / f1) / math.log(e))
        else:
            k = math.floor(remaining / f1)
        k = max(k, 1.0)
        for _ in range(_COUNT_FIX):
            if _bounce_time(f1, e, k) > remaining and k > 1.0:
                k -= 1.0
            elif _bounce_time(f1, e, k + 1.0) <= remaining:
                k += 1.0
            else:
                break
        remaining = max(remaining - _bounce_time(f1, e, k), 0.0)
        w = w * e**k
        if k % 2.0 == 1.0:
            side = -side
        if w == 0.0:
            return 0.0, 0.0
        theta = 0.0
        omega = side * w
    return math.nan, math.nan


@numba.njit(nogil=True, cache=True)
def _bounce_time(f1, e, k):
    """Total duration of ``k`` successive bounces, the first lasting ``f1``."""
    if e < 1.0:
        return f1 * -math.expm1(k * math.log(e)) / (1.0 - e) if e > 0.0 else f1
    return f1 * k


def integrate(impulses, dt, g, e, theta0, omega0, burn_in, theta_out, omega_out, grid_impacts=False):
    """Integrate one series (eqs. 21-24) and write the recorded part.

    ``impulses`` holds ``burn_in + n - 1`` velocity impulses (rad/s); the first ``burn_in``
    steps are discarded, then ``n = len(theta_out)`` samples are written, the first one
    being the state after the burn-in. ``grid_impacts`` swaps the exact flight for the
    fixed-step integrator (:func:`rockdec.physics.fixed_step.step`, what most public rocking
    codes do). The scalars go to the kernel :func:`_integrate` as float64 and int64 and the
    series as its one row, with no seeds to draw from, so it compiles once for each of the
    two steps (:func:`simulate_block`'s calls, which draw, are signatures of their own).
    """
    _integrate(impulses, None, 0.0, None, float(dt), float(g), float(e), float(theta0), float(omega0), int(burn_in), theta_out[None],
               omega_out[None], True if grid_impacts else None)


@numba.njit(nogil=True, cache=True)
def _integrate(impulses, words, sigma_p, pole, dt, g, e, theta0, omega0, burn_in, theta_out, omega_out, grid):
    """:func:`integrate`'s loop over the rows of ``theta_out`` and ``omega_out``: one unloaded
    step and the impulse per step. ``words`` None: ``impulses`` as given (one row); else each
    row's impulses first drawn into the scratch ``impulses`` from its row of ``words`` (the
    seeds' :func:`rockdec.physics.loading.stream_words`: :func:`rockdec.physics.loading.draw_series`,
    ``sigma_p``, ``pole`` None for white noise), so that :func:`simulate_block` draws and
    integrates a block with no Python between series. ``grid`` None: the exact :func:`flight`;
    True: the grid-impact step. None is a type of its own to numba, which drops the other
    branch before typing it, so each choice compiles only its own code."""
    for row in range(theta_out.shape[0]):
        if words is not None:
            draw_series(words[row], impulses, sigma_p, pole)
        thetas, omegas = theta_out[row], omega_out[row]
        theta = theta0
        omega = omega0
        if burn_in == 0:
            thetas[0] = theta
            omegas[0] = omega
        for i in range(burn_in + thetas.shape[0] - 1):
            if grid is None:
                theta, omega = flight(theta, omega, dt, g, e)
            else:
                theta, omega = grid_step(theta, omega, dt, g, e)
            omega += impulses[i]
            j = i + 1 - burn_in  # the sample this step reaches; the burn-in's are not written
            if j >= 0:
                thetas[j] = theta
                omegas[j] = omega


def simulate_block(seeds, n_points, *, dt, g, e, sigma_p, theta0=0.0, theta_dot0=0.0, burn_in=0, grid_impacts=False, pole=0.0,
                   spectrum=None, out=None):
    """Simulate one series per seed; returns ``(theta, theta_dot)``, each ``(len(seeds), n_points)``.

    Kernel entry point (NumPy in, NumPy out). ``sigma_p`` is the standard deviation of the
    velocity impulses in rad/s; ``sigma_p = 0`` gives the free response from
    ``(theta0, theta_dot0)``. ``grid_impacts=True``: the fixed-step integrator instead of the
    exact one (same load, same seed). ``pole``: low-pass filtered load
    (:func:`rockdec.physics.loading.draw_impulses`), 0 for white noise; ``spectrum``: a load of that
    spectrum instead (:class:`rockdec.physics.loading.ImpulseSpectrum`, cycles per step;
    :meth:`rockdec.physics.record_model.Load.draw_options` gives either). A white or low-pass
    load is drawn and integrated in one numba call over the seeds (:func:`_integrate`),
    a spectrum load series by series. ``out``: a float64 array ``(2, len(seeds), n_points)``
    to write ``theta`` and ``theta_dot`` into (returned as its two halves). Inputs outside the
    model (NaN, infinities, ``e`` outside ``[0, 1]``, a negative seed, ...) and series that
    overflow raise :class:`rockdec.validate.InputError`.
    """
    check_run(dt=dt, e=e, sigma_p=sigma_p, theta0=theta0, theta_dot0=theta_dot0, burn_in=burn_in, n_points=n_points)
    checks.positive(g, "g", "give the restoring acceleration nu^2 theta_cr in rad/s^2, > 0")
    check_load(pole, spectrum)
    seeds = check_seeds(seeds)
    n_steps = burn_in + n_points - 1
    if out is None:
        out = np.empty((2, seeds.size, n_points))
    theta, theta_dot = out[0], out[1]
    impulses = np.empty(n_steps)
    if spectrum is None:
        _integrate(impulses, stream_words(seeds), float(sigma_p), float(pole) if pole > 0.0 else None, float(dt), float(g), float(e),
                   float(theta0), float(theta_dot0), int(burn_in), theta, theta_dot, True if grid_impacts else None)
    else:
        for row, seed in enumerate(seeds):
            draw_impulses(series_rng(seed), impulses, sigma_p, pole, spectrum)
            integrate(impulses, dt, g, e, theta0, theta_dot0, burn_in, theta[row], theta_dot[row], grid_impacts)
    check_finite_series(np.stack([theta[:, -1], theta_dot[:, -1]]), f"the simulation at dt = {dt}, g = {g}, sigma_p = {sigma_p}")
    return theta, theta_dot


def default_burn_in(e: float, points_per_cycle: float, relaxations: float = 20.0) -> int:
    """Steps to discard so that a series started at rest is stationary.

    The energy lost per cycle is the fraction ``1 - e^4`` (eq. 7), so the energy relaxes
    over about ``1/(1 - e^4)`` cycles; ``relaxations`` of those cycles, at
    ``points_per_cycle`` steps each, are discarded. Refuses ``e = 1`` (nothing relaxes).
    """
    checks.in_range(e, "e", 0.0, 1.0, "give the coefficient of restitution in [0, 1]")
    checks.positive(points_per_cycle, "points_per_cycle")
    loss = 1.0 - e**4
    if loss <= 0.0:
        raise checks.InputError("e = 1 dissipates no energy, so no stationary state exists: give `burn_in` explicitly")
    steps = relaxations * points_per_cycle / loss
    if steps > MAX_DEFAULT_BURN_IN:
        raise checks.InputError(
            f"e = {e} loses only {loss:.2g} of the energy per cycle, so reaching the stationary state "
            f"takes about {steps:.3g} steps; give `burn_in` (and `dt`) explicitly"
        )
    return int(math.ceil(steps))


def calibrate_dt(
    *,
    e: float,
    g: float,
    sigma_p: float,
    points_per_cycle: float = 75.0,
    pilot_seeds: int = PILOT_SERIES,
    pilot_points: int = PILOT_POINTS,
    iterations: int = STEP_ITERATIONS["white"],
    pole: float = 0.0,
    spectrum=None,
) -> dict:
    """Time step giving ``points_per_cycle`` samples per cycle at amplitude ``sigma_Y`` (eq. 5).

    Under the scale law ``sigma_Y = c S^2/g^3`` (:func:`rockdec.physics.models.scale_constant`)
    the step is :func:`rockdec.physics.models.step_for_density` of ``c``; ``c`` is measured by
    pilot runs (:data:`PILOT_SERIES` x :data:`PILOT_POINTS`, seeds of their own, burn-in
    discarded) and the step updated ``iterations`` times, from the step of
    :data:`rockdec.physics.models.SCALE_CONSTANT_GUESS`.

    Returns a dict with ``dt``, ``burn_in``, and the statistics of the pilot at that step:
    ``sigma_y``, ``sigma_ydot`` (of the sampled slope ``diff(theta)/dt``, what a measured
    record gives) and the achieved ``points_per_cycle``. Refuses ``e >= 1``. ``pole``:
    a low-pass filtered load, ``spectrum``: a load of that spectrum
    (:func:`rockdec.physics.loading.draw_impulses`); under either the step follows :func:`secant_step`
    and the pilot that came closest to ``points_per_cycle`` (in ``log``) is returned.
    """
    checks.in_range(e, "e", 0.0, 1.0, "give the coefficient of restitution in [0, 1]")
    checks.positive(g, "g", "give the restoring acceleration nu^2 theta_cr in rad/s^2, > 0")
    checks.positive(sigma_p, "sigma_p", "give the impulse standard deviation in rad/s, > 0", allow_zero=True)
    checks.in_range(points_per_cycle, "points_per_cycle", 2.0, lo_open=True, fix="give more than 2 samples per cycle")
    checks.integer(pilot_seeds, "pilot_seeds", 1)
    checks.integer(pilot_points, "pilot_points", 2)
    checks.integer(iterations, "iterations", 1)
    if e >= 1.0:
        raise checks.InputError(
            "e = 1 dissipates no energy, so the response never becomes stationary and "
            "sigma_Y does not exist: give the time step explicitly (`dt`) instead of "
            "`points_per_cycle`"
        )
    if sigma_p <= 0.0:
        raise checks.InputError("time-step calibration needs noise: sigma_p must be > 0 (or give `dt`)")
    burn_in = default_burn_in(e, points_per_cycle)
    seeds = np.arange(pilot_seeds) + PILOT_SEED_OFFSET
    dt = step_for_density(SCALE_CONSTANT_GUESS, sigma_p, g, points_per_cycle)
    outside = checks.InputError(
        f"the time-step calibration at g = {g}, sigma_p = {sigma_p} leaves the floating-point range; "
        "give the time step explicitly (`dt`)"
    )
    history: list[tuple[float, float]] = []
    coloured = not (pole == 0.0 and spectrum is None)
    closest = None
    pilot = np.empty((2, seeds.size, pilot_points))  # every pilot's series, in the same memory
    for i in range(iterations):
        if not (0.0 < dt < math.inf and 0.0 < g * dt * dt < math.inf):
            raise outside
        theta, _ = simulate_block(seeds, pilot_points, dt=dt, g=g, e=e, sigma_p=sigma_p, burn_in=burn_in, pole=pole,
                                  spectrum=spectrum, out=pilot)
        stats = pilot_statistics(theta, dt, g)
        miss = abs(math.log(stats["points_per_cycle"] / points_per_cycle)) if stats["points_per_cycle"] > 0 else math.inf
        if coloured and (closest is None or miss < closest[0]):
            closest = (miss, {"dt": dt, "burn_in": burn_in, **stats})
        if i < iterations - 1:
            try:
                if not coloured:
                    c = scale_constant(stats["sigma_y"], dt, g, sigma_p)
                    dt = step_for_density(c, sigma_p, g, points_per_cycle)
                else:
                    dt = secant_step(history, dt, stats["points_per_cycle"], points_per_cycle)
            except (OverflowError, ZeroDivisionError):  # float ** raises where * gives inf
                raise outside from None
    return closest[1] if coloured and math.isfinite(closest[0]) else {"dt": dt, "burn_in": burn_in, **stats}


def secant_step(history: list, dt: float, achieved: float, target: float) -> float:
    """Next step of a step search under a coloured load, low-pass or of a spectrum
    (:func:`calibrate_dt`, :func:`rockdec.calibrate.calibration.step_for`).

    The load's correlation time is a fixed number of steps (its spectrum is placed in cycles
    per step), so it scales with ``dt`` and the white law ``points_per_cycle ~ dt^-2`` no
    longer holds: near a corner at the rocking frequency the load acts like a force that
    must exceed ``g`` to lift the block, and the samples per cycle fall steeply with ``dt``
    (the more so the higher ``e``), so an extrapolated exponent overshoots and the search
    oscillates. ``history`` holds every pilot ``(ln dt, ln N)``
    (appended to here). Once pilots lie on both sides of the target, the next step
    interpolates (in logs) between the nearest step below and the nearest above, kept
    inside the middle 80 % of that bracket, which shrinks it at every pilot like a
    bisection. Before that, the exponent ``k`` is the least-squares slope of ``ln N`` on
    ``ln dt`` over the last :data:`SECANT_POINTS` pilots (2 at first), held to
    :data:`SECANT_EXPONENTS`, and ``dt <- dt (N_achieved / N_target)^(1/k)``. Points per
    cycle fall as ``dt`` grows, so a pilot above the target is a step too short.
    """
    history.append((math.log(dt), math.log(achieved)))
    y_t = math.log(target)
    short = [x for x, y in history if y > y_t]  # steps too short: more samples per cycle than wanted
    long = [x for x, y in history if y < y_t]
    if short and long and max(short) < min(long):
        lo, hi = max(short), min(long)
        y_lo, y_hi = (next(y for x, y in reversed(history) if x == b) for b in (lo, hi))
        x = lo + (y_t - y_lo) * (hi - lo) / (y_hi - y_lo) if y_hi != y_lo else 0.5 * (lo + hi)
        return math.exp(min(max(x, lo + 0.1 * (hi - lo)), hi - 0.1 * (hi - lo)))
    k = 2.0
    points = history[-SECANT_POINTS:]
    if len(points) >= 2:
        mx = sum(x for x, _ in points) / len(points)
        my = sum(y for _, y in points) / len(points)
        sxx = sum((x - mx) ** 2 for x, _ in points)
        if sxx > 0.0:
            slope = sum((x - mx) * (y - my) for x, y in points) / sxx
            k = min(max(-slope, SECANT_EXPONENTS[0]), SECANT_EXPONENTS[1])
    return dt * (achieved / target) ** (1.0 / k)


def _finite_mean(x: np.ndarray) -> float:
    """``np.nanmean(x)``; without a NaN in ``x``, ``np.mean(x)``, which sums the same values
    in the same order (so the same bits) without ``nanmean``'s copy of ``x``."""
    return np.nanmean(x) if np.isnan(x).any() else np.mean(x)


def pilot_statistics(theta: np.ndarray, dt: float, g: float | None = None) -> dict:
    """Stationary statistics of series ``theta(seed, time)``: ``sigma_y``, ``sigma_ydot`` (of
    ``diff(theta)/dt``) and, given ``g``, samples per cycle at ``sigma_y`` (eq. 5); NaN
    samples left out. For C-ordered float64 series (the simulators') the squares and the slopes share
    one scratch array, the slopes divided and squared in place: the values of ``theta**2``
    and ``(diff(theta)/dt)**2``, averaged as contiguous arrays of the same shapes (so the same
    bits), without a fresh array of the record's size for each step of the arithmetic (a
    pilot of :func:`calibrate_dt` is 80 MB a step)."""
    theta = np.asarray(theta)
    if theta.dtype == np.float64 and theta.flags.c_contiguous:
        scratch = np.empty(theta.size)
        squares = np.square(theta, out=scratch.reshape(theta.shape))
        sigma_y = float(np.sqrt(_finite_mean(squares)))
        later, earlier = theta[..., 1:], theta[..., :-1]
        slopes = np.subtract(later, earlier, out=scratch[: later.size].reshape(later.shape))
        slopes /= dt
        slopes **= 2
    else:  # a record in its own arithmetic and memory order (float32 stays float32)
        sigma_y = float(np.sqrt(_finite_mean(theta**2)))
        slopes = (np.diff(theta, axis=-1) / dt) ** 2
    sigma_ydot = float(np.sqrt(_finite_mean(slopes)))
    out = {"sigma_y": sigma_y, "sigma_ydot": sigma_ydot}
    if g is not None:
        out["points_per_cycle"] = float(period_from_g(sigma_y, g) / dt)
    return out


def simulate_model(model: str, seeds, n_points: int, *, dt, g, e, sigma_p, theta_cr=None, pole=0.0, theta0=0.0, theta_dot0=0.0,
                   burn_in=0, spectrum=None, out=None) -> tuple[np.ndarray, np.ndarray]:
    """``(theta, theta_dot)`` of one series per seed under ``model``: the one dispatch on a model name.

    ``"simplified"`` (eq. 4, :func:`simulate_block`), ``"housner"`` (eq. 2,
    :func:`rockdec.physics.housner.simulate_block_housner` with ``nu = sqrt(g/theta_cr)``; a series
    that overturns is NaN from the fall on) or ``"fixed_step"`` (eq. 4 with the grid-impact
    integrator of :mod:`rockdec.physics.fixed_step`, for the speed/accuracy study). ``pole``,
    ``spectrum``: the load (:meth:`rockdec.physics.record_model.Load.draw_options`; 0, None: white).
    ``out``: an array ``(2, len(seeds), n_points)`` that receives ``theta`` and ``theta_dot``
    (:func:`simulate_block`'s), which are then its two halves.
    """
    common = dict(dt=dt, e=e, sigma_p=sigma_p, theta0=theta0, theta_dot0=theta_dot0, burn_in=burn_in, pole=pole, spectrum=spectrum)
    if model == "simplified":
        return simulate_block(seeds, n_points, g=g, out=out, **common)
    if model == "fixed_step":  # not a model: the grid-impact integrator of rockdec.physics.fixed_step
        return simulate_block(seeds, n_points, g=g, grid_impacts=True, out=out, **common)
    if model == "housner":
        if theta_cr is None:
            raise ValueError("the Housner model needs theta_cr")
        theta, theta_dot, _ = simulate_block_housner(seeds, n_points, nu=math.sqrt(g / theta_cr), theta_cr=theta_cr, **common)
        if out is None:
            return theta, theta_dot
        out[0], out[1] = theta, theta_dot
        return out[0], out[1]
    raise ValueError(f"unknown model '{model}'; use simplified or housner")


def simulation_dataset(
    seeds,
    n_points: int,
    *,
    dt: float,
    g: float,
    e: float,
    sigma_p: float,
    theta0: float = 0.0,
    theta_dot0: float = 0.0,
    burn_in: int = 0,
    chunk_seeds: int = 100,
    model: str = "simplified",
    theta_cr: float | None = None,
    pole: float = 0.0,
    spectrum=None,
    sensor_std: float = 0.0,
) -> xr.Dataset:
    """Lazy Dataset ``theta(seed, time)``, ``theta_dot(seed, time)`` (float64, Dask chunks over seed).

    Nothing is simulated until the values are asked for; each chunk calls
    :func:`simulate_model` (numba, ``nogil``), so Dask's threads run chunks in parallel. A
    series depends on its seed only, so any chunking gives the same numbers, bit for bit.
    ``pole``, ``spectrum``: the load (0, None: white; the attribute ``load_pole`` is NaN
    for a spectrum, whose table :meth:`rockdec.physics.run.Run.dataset` names); ``sensor_std`` (rad): white sensor noise added to
    the recorded angle (:func:`rockdec.physics.loading.add_sensor_noise`; ``theta_dot`` stays the
    model's).
    """
    import dask.array as da  # the lazy dataset only: simulate_block's callers never load dask.array

    seeds = np.atleast_1d(np.asarray(seeds, dtype=np.int64))
    seed_chunks = da.from_array(seeds, chunks=chunk_seeds)
    if model not in ("simplified", "housner", "fixed_step"):
        raise ValueError(f"unknown model '{model}'; use simplified or housner")
    if model == "housner" and theta_cr is None:
        raise ValueError("the Housner model needs theta_cr")
    common = dict(dt=dt, g=g, e=e, sigma_p=sigma_p, theta_cr=theta_cr, pole=pole, theta0=theta0, theta_dot0=theta_dot0, burn_in=burn_in,
                  spectrum=spectrum)

    def block(chunk):
        both = np.empty((2, chunk.size, n_points))  # theta and theta_dot written in place: no stacking copy
        add_sensor_noise(simulate_model(model, chunk, n_points, out=both, **common)[0], chunk, sensor_std)
        return both

    both = da.map_blocks(
        block, seed_chunks, new_axis=[0, 2], chunks=((2,), seed_chunks.chunks[0], (n_points,)), dtype=np.float64
    )
    time = np.arange(n_points) * dt
    if time[-1] > MAX_RECORD_SECONDS:
        raise checks.InputError(
            f"dt {dt:g} s x {n_points} points spans {time[-1]:.3g} s, longer than the {MAX_RECORD_SECONDS:.3g} s whose "
            "times a NetCDF reader can decode; choose a smaller time step or fewer points"
        )
    ds = xr.Dataset(
        {
            "theta": (("seed", "time"), both[0], {"units": "rad", "long_name": "rocking angle"}),
            "theta_dot": (
                ("seed", "time"),
                both[1],
                {"units": "rad s-1", "long_name": "rocking angular velocity just after the impulse"},
            ),
        },
        coords={
            "seed": ("seed", seeds, {"long_name": "NumPy SeedSequence entropy of the series"}),
            "time": ("time", time, TIME_ATTRS),
        },
    )
    ds.attrs.update(
        {"model": model, "dt": dt, "g": g, "e": e, "sigma_p": sigma_p, "burn_in": burn_in, "theta0": theta0, "theta_dot0": theta_dot0,
         "load_pole": math.nan if spectrum is not None else pole, "sensor_noise_rad": sensor_std}
    )
    return ds

"""The run contract: everything that fixes a scene's simulated series, built once and passed on.

A :class:`Run` holds the rocking system (``e``, ``nu``, ``theta_cr``; eqs. 2, 4, 6), the load
(``sigma_p``, eqs. 21-24, and its spectrum, :class:`rockdec.physics.record_model.Load`), the sensor
noise, the sampling (``dt``, ``burn_in``), the initial state, the model that runs and the
stationary statistics measured at that step (``sigma_y``, ``sigma_ydot``, samples per
cycle at ``sigma_Y``, eq. 5); :attr:`Run.record_model` gives its record model. Given a seed it determines the
series bit for bit (:meth:`Run.dataset`), and its statistics set the trigger levels of
every signature of the scene (one level for all series, docs/method.md §4.4).

Every path builds it once, by :func:`calibrate` (step search included): the workflow's rule
``calibrate`` (written as ``run.json``), the command line, the trade-off and amplitude studies; it
travels as NetCDF attributes (:meth:`Run.to_attrs`, :meth:`Run.from_attrs`) in every file
made from it. The kernels and their Dask wrapper stay in :mod:`rockdec.physics.simulate`.
"""

from __future__ import annotations

import dataclasses
import json
import math
import warnings
from pathlib import Path

import numpy as np
import xarray as xr

from rockdec.physics import simulate
from rockdec import validate as checks
from rockdec.warning_types import ModelValidityWarning
from rockdec.physics.housner import choose_model
from rockdec.physics.models import MODEL_PEAK_SIGMAS, period_from_g, restoring_acceleration
from rockdec.physics.record_model import (
    NO_NOISE,
    WHITE,
    Load,
    RecordModel,
    SensorNoise,
    load_attrs,
    load_from_attrs,
    sensor_attrs,
    sensor_from_attrs,
)

__all__ = [
    "DEFAULTS", "PILOT", "PPC_TOLERANCE", "Run", "from_scene", "model_for", "overturned", "points_per_cycle_shortfall", "search",
    "simulation_report", "with_model",
]

#: Pilot sizes of the step search (:func:`rockdec.physics.simulate.calibrate_dt`), the defaults of
#: :func:`search`'s ``pilot``.
PILOT = {"pilot_seeds": simulate.PILOT_SERIES, "pilot_points": simulate.PILOT_POINTS}


@dataclasses.dataclass(frozen=True)
class Run:
    """One simulated run: what a seed needs to become a series, and the scene's statistics.

    ``model``: ``"simplified"`` (eq. 4), ``"housner"`` (eq. 2) or ``"fixed_step"`` (eq. 4
    with the grid-impact integrator of :mod:`rockdec.physics.fixed_step`); ``e`` (eq. 6), ``nu``
    (rad/s), ``theta_cr`` (rad), ``sigma_p`` (rad/s, std of the velocity impulses),
    ``dt`` (s), ``burn_in`` (steps discarded), ``theta0``/``theta_dot0`` (state at the start
    of the burn-in); ``sigma_y`` (rad), ``sigma_ydot`` (rad/s, of the sampled slope) and
    ``points_per_cycle`` (samples per cycle at ``sigma_Y``, eq. 5) measured by a pilot at
    ``dt`` (NaN for a free response); ``points_per_cycle_target`` (what set ``dt``) and
    ``model_reason`` (why this model) say how it was chosen; ``load``: the impulses' spectrum
    (its corner or its table placed at ``points_per_cycle_target``, :attr:`load_options`); ``sensor``: white noise
    added to the recorded angle (the statistics are the model's response without it).
    """

    model: str
    e: float
    nu: float
    theta_cr: float
    sigma_p: float
    dt: float
    burn_in: int
    sigma_y: float
    sigma_ydot: float
    points_per_cycle: float
    points_per_cycle_target: float = math.nan
    model_reason: str = "requested"
    theta0: float = 0.0
    theta_dot0: float = 0.0
    load: Load = WHITE
    sensor: SensorNoise = NO_NOISE

    @property
    def g(self) -> float:
        """The restoring acceleration ``nu^2 theta_cr`` of eq. 4, in rad/s^2."""
        return restoring_acceleration(self.nu, self.theta_cr)

    @property
    def pole(self) -> float:
        """The load filter's pole (:meth:`rockdec.physics.record_model.Load.pole` at the target density; 0: white;
        NaN: a spectrum load, which has none)."""
        return self.load.pole(self.points_per_cycle_target)

    @property
    def load_options(self) -> dict:
        """The load as the simulators' keywords (``pole`` or ``spectrum``) at the target density
        (:meth:`rockdec.physics.record_model.Load.draw_options`)."""
        return self.load.draw_options(self.points_per_cycle_target)

    @property
    def sensor_std(self) -> float:
        """The sensor noise's standard deviation in rad (0 without noise)."""
        return self.sensor.std_rad(self.sigma_y) if self.sensor.std > 0.0 else 0.0

    @property
    def record_model(self) -> RecordModel:
        """The run's record model: its rocking model (the fixed-step integrator runs eq. 4), load and sensor."""
        return RecordModel("housner" if self.model == "housner" else "simplified", self.load, self.sensor)

    def to_attrs(self) -> dict:
        """The run as NetCDF attributes (numbers and strings): every field, the load and the
        sensor noise flattened (:mod:`rockdec.physics.record_model`), ``g`` and ``load_pole`` added for readers."""
        fields = {f.name: getattr(self, f.name) for f in dataclasses.fields(self) if f.name not in ("load", "sensor")}
        return {**fields, **load_attrs(self.load), **sensor_attrs(self.sensor), "g": self.g, "load_pole": self.pole}

    @classmethod
    def from_attrs(cls, attrs) -> "Run":
        """The run described by ``attrs`` (as :meth:`to_attrs` wrote them; others ignored)."""
        kinds = {f.name: f.type for f in dataclasses.fields(cls)}
        missing = [name for name, f in _required().items() if name not in attrs]
        if missing:
            raise checks.InputError(
                f"the attributes do not describe a rockdec run: {', '.join(missing)} missing; "
                "use a file written by the workflow or by 'rockdec simulate'"
            )
        cast = {"str": str, "int": int, "float": float}
        plain = {name: cast[kinds[name]](attrs[name]) for name in kinds if name in attrs and kinds[name] in cast}
        return cls(**plain, load=load_from_attrs(attrs), sensor=sensor_from_attrs(attrs))

    def dataset(self, seeds, n_points: int, chunk_seeds: int = 100) -> xr.Dataset:
        """Lazy ``theta(seed, time)``, ``theta_dot(seed, time)`` of ``seeds`` under this run
        (:func:`rockdec.physics.simulate.simulation_dataset`), its attributes :meth:`to_attrs`."""
        ds = simulate.simulation_dataset(
            seeds, n_points, dt=self.dt, g=self.g, e=self.e, sigma_p=self.sigma_p, theta0=self.theta0,
            theta_dot0=self.theta_dot0, burn_in=self.burn_in, chunk_seeds=chunk_seeds, model=self.model,
            theta_cr=self.theta_cr, sensor_std=self.sensor_std, **self.load_options,
        )
        ds.attrs = self.to_attrs()
        return ds

    def write(self, path) -> Path:
        """Write the run as JSON (the product of rule ``calibrate``)."""
        path = Path(path)
        path.write_text(json.dumps(self.to_attrs(), indent=2, sort_keys=True) + "\n")
        return path

    @classmethod
    def read(cls, path) -> "Run":
        """The run of a ``run.json`` written by :meth:`write`."""
        path = Path(path)
        try:
            attrs = json.loads(path.read_text())
        except (OSError, ValueError) as exc:
            raise checks.InputError(f"'{path}' is not a readable run file ({exc}); rerun rule calibrate") from None
        return cls.from_attrs(attrs)


def _required() -> dict:
    return {f.name: f for f in dataclasses.fields(Run) if f.default is dataclasses.MISSING}


#: The defaults of a run's settings, as the scenes' schema gives them (src/rockdec/scene_schema.yaml;
#: tests/physics/test_run_settings.py holds the two equal): model, ``nu`` (rad/s), ``theta_cr`` (rad),
#: ``sigma_p`` (rad/s) and the samples per cycle at ``sigma_Y`` (eq. 5).
DEFAULTS = {"model": "auto", "nu": 2.0, "theta_cr": 0.25, "sigma_p": 0.003, "points_per_cycle": 75.0}


def from_scene(scene: dict, amplitude: float = 0.0, theta0: float = 0.0, theta_dot0: float = 0.0, pilot: dict | None = None) -> Run:
    """The run of a validated scene's ``model``, ``system`` and ``excitation`` sections
    (:func:`rockdec.pipeline.config.validate_scene`): :func:`search` of their settings."""
    system, exc = scene["system"], scene["excitation"]
    return search(e=system["e"], model=scene["model"], nu=system["nu"], theta_cr=system["theta_cr"], sigma_p=exc["sigma_p"],
                  points_per_cycle=exc["points_per_cycle"], dt=exc["dt"], burn_in=exc["burn_in"], load=Load.from_dict(exc.get("load")),
                  sensor=SensorNoise.from_dict(exc.get("sensor_noise")), amplitude=amplitude, theta0=theta0, theta_dot0=theta_dot0,
                  pilot=pilot)


def search(*, e: float, model: str = DEFAULTS["model"], nu: float = DEFAULTS["nu"], theta_cr: float = DEFAULTS["theta_cr"],
           sigma_p: float = DEFAULTS["sigma_p"], points_per_cycle: float = DEFAULTS["points_per_cycle"], dt: float | None = None,
           burn_in: int | None = None, load: Load = WHITE, sensor: SensorNoise = NO_NOISE, amplitude: float = 0.0,
           theta0: float = 0.0, theta_dot0: float = 0.0, pilot: dict | None = None) -> Run:
    """The :class:`Run` of these settings (checked by the caller): the one way from settings
    (a scene, the library's :func:`rockdec.simulate`, a command line) to a run.

    ``dt`` as given or from the step search :func:`rockdec.physics.simulate.calibrate_dt`
    under ``load`` (``pilot``: its sizes, :data:`PILOT`); the burn-in as given or
    :func:`rockdec.physics.simulate.default_burn_in`. Stationary statistics are measured by a
    pilot at that step, with the model that runs (``auto`` chooses by the amplitude,
    :func:`model_for`; :func:`with_model`). Without noise (``sigma_p = 0``, a free response
    from ``theta0``) there is no ``sigma_Y``: the step then gives ``points_per_cycle``
    samples per cycle at ``amplitude`` (eq. 5), no burn-in. ``model`` may also be
    ``"fixed_step"`` (the grid-impact integrator, for the speed/accuracy study).

    Examples
    --------
    >>> run = search(e=0.85, sigma_p=0.0, theta0=0.01, amplitude=0.01)
    >>> run.model, run.burn_in, round(run.g, 6)
    ('simplified', 0, 1.0)
    """
    g = restoring_acceleration(nu, theta_cr)
    pilot = {**PILOT, **(pilot or {})}
    draw = load.draw_options(points_per_cycle)
    if sigma_p == 0.0:
        if dt is None and amplitude <= 0.0:
            raise checks.InputError("a free response (sigma_p = 0) needs `theta0` > 0 to set the step, or `dt`")
        step = dt if dt is not None else float(period_from_g(abs(amplitude), g)) / points_per_cycle
        nan = math.nan
        cal = {"dt": step, "burn_in": 0, "sigma_y": nan, "sigma_ydot": nan, "points_per_cycle": nan}
    elif dt is None:
        cal = simulate.calibrate_dt(
            e=e, g=g, sigma_p=sigma_p, points_per_cycle=points_per_cycle, **draw,
            iterations=simulate.STEP_ITERATIONS[load.kind], **pilot,
        )
    else:
        burn = burn_in if burn_in is not None else simulate.default_burn_in(e, points_per_cycle)
        theta, _ = simulate.simulate_block(
            _statistics_seeds(pilot), pilot["pilot_points"], dt=dt, g=g, e=e, sigma_p=sigma_p, burn_in=burn, **draw
        )
        cal = {"dt": dt, "burn_in": burn, **simulate.pilot_statistics(theta, dt, g)}
    if burn_in is not None:
        cal["burn_in"] = burn_in
    chosen, reason = model_for(model, cal["sigma_y"], theta_cr)
    simplified = Run(
        model="simplified", e=e, nu=nu, theta_cr=theta_cr, sigma_p=sigma_p, dt=cal["dt"],
        burn_in=int(cal["burn_in"]), sigma_y=cal["sigma_y"], sigma_ydot=cal["sigma_ydot"],
        points_per_cycle=cal["points_per_cycle"], points_per_cycle_target=float(points_per_cycle),
        model_reason=reason, theta0=float(theta0), theta_dot0=float(theta_dot0), load=load, sensor=sensor,
    )
    return with_model(simplified, chosen, pilot)


def _statistics_seeds(pilot: dict) -> np.ndarray:
    """Seeds of the pilot that measures the statistics at a given step (:data:`rockdec.physics.simulate.STATISTICS_PILOT_SERIES`)."""
    return np.arange(min(simulate.STATISTICS_PILOT_SERIES, pilot["pilot_seeds"])) + simulate.PILOT_SEED_OFFSET


def with_model(run: Run, model: str, pilot: dict | None = None) -> Run:
    """``run`` under ``model`` at the same step, its statistics re-measured by a pilot of that
    model: the trigger level and the sampling follow the model that runs. A block that
    overturns in most pilot series (Housner) has no stationary rocking: refused.
    """
    if model == run.model or not run.sigma_p > 0.0:
        return dataclasses.replace(run, model=model)
    pilot = {**PILOT, **(pilot or {})}
    theta, _ = simulate.simulate_model(
        model, _statistics_seeds(pilot), pilot["pilot_points"], dt=run.dt, g=run.g, e=run.e, sigma_p=run.sigma_p,
        theta_cr=run.theta_cr, burn_in=run.burn_in, **run.load_options,
    )
    standing = np.all(np.isfinite(theta), axis=1)
    if standing.mean() < 0.5:
        raise checks.InputError(
            f"the block overturns in {1 - standing.mean():.0%} of the pilot series ({MODEL_PEAK_SIGMAS:g} sigma_Y/theta_cr = "
            f"{MODEL_PEAK_SIGMAS * run.sigma_y / run.theta_cr:.2g}): no stationary rocking exists; lower sigma_p"
        )
    return dataclasses.replace(run, model=model, **simulate.pilot_statistics(theta[standing], run.dt, run.g))


def model_for(requested: str, sigma_y: float, theta_cr: float) -> tuple[str, str]:
    """The model a scene runs, and why: as requested, or for ``auto`` by the amplitude.

    ``auto`` judges the amplitude by ``3 sigma_Y / theta_cr`` (:data:`rockdec.physics.models.
    MODEL_PEAK_SIGMAS`) with :func:`rockdec.physics.housner.choose_model`: the simplified model
    while the periods of eqs. 3 and 5 agree within 2 % (:data:`rockdec.physics.models.
    MODEL_TOLERANCE`), Housner beyond. A requested model is kept, with a warning in the
    reason when it leaves its validity.
    """
    ratio = MODEL_PEAK_SIGMAS * sigma_y / theta_cr if np.isfinite(sigma_y) else 0.0
    chosen, why = choose_model(ratio)
    if requested == "auto":
        return chosen, f"auto: {why}"
    if requested == "simplified" and chosen == "housner":
        warnings.warn(f"the simplified model is outside its validity region: {why}", ModelValidityWarning, stacklevel=3)
        return requested, f"requested; outside its validity: {why}"
    return requested, "requested"


#: Largest relative miss of the achieved samples per cycle at ``sigma_Y`` (eq. 5) from the
#: requested ones that :func:`simulation_report` lets pass unsaid: the width of the bins in
#: which the analysis treats samples per cycle as one (``rockdec.calibrate.calibration.PPC_BIN``).
PPC_TOLERANCE = 0.1


@dataclasses.dataclass(frozen=True)
class Overturned:
    """Series of a simulation that overturned (Housner's model, eq. 2: NaN from the fall on).

    ``count`` of ``series``; ``worst``: the largest fraction of one series that is NaN;
    ``seeds``: the seeds of the overturned series (their indices when none are given).
    """

    count: int
    series: int
    worst: float
    seeds: tuple


def overturned(theta, seeds=None) -> Overturned:
    """Count the series of ``theta(seed, time)`` that hold NaN: under Housner's model (eq. 2)
    the block overturns and its series is NaN from the fall on; the other models give none.

    Parameters
    ----------
    theta : array_like, xarray.DataArray or Dask array
        Series by rows (a 1-D array is one series). A lazy array is computed: pass the values
        already computed (or read back from their file) to avoid simulating them again.
    seeds : array_like, optional
        The seed of each row (default: the ``seed`` coordinate of a DataArray, else the row index).

    Returns
    -------
    Overturned

    Examples
    --------
    >>> theta = np.array([[0.1, -0.1, 0.1, 0.2], [0.1, 0.2, np.nan, np.nan]])
    >>> overturned(theta, seeds=[7, 8])
    Overturned(count=1, series=2, worst=0.5, seeds=(8,))
    """
    if seeds is None and hasattr(theta, "coords") and "seed" in theta.coords:
        seeds = theta["seed"].values
    data = getattr(theta, "data", theta)
    data = data if hasattr(data, "compute") else np.asarray(data)
    if data.ndim == 1:
        data = data[None, :]
    fraction = np.isnan(data).mean(axis=-1)
    if hasattr(fraction, "compute"):
        fraction = fraction.compute()
    fraction = np.asarray(fraction, dtype=np.float64)
    fallen = np.flatnonzero(fraction > 0)
    seeds = np.arange(fraction.size) if seeds is None else np.asarray(seeds).ravel()
    return Overturned(int(fallen.size), int(fraction.size), float(fraction.max(initial=0.0)), tuple(int(s) for s in seeds[fallen]))


def points_per_cycle_shortfall(contract: Run) -> str | None:
    """A sentence when the samples per cycle at ``sigma_Y`` (eq. 5) the run's pilot achieved
    miss the requested ones by more than :data:`PPC_TOLERANCE` (relative), else ``None``: a
    step set by ``dt``, or a step search that could not reach the target (a Housner scene
    under a low-pass load, whose period and load both move with the step).

    Parameters
    ----------
    contract : Run
        The run (:func:`calibrate`).

    Returns
    -------
    str or None

    Examples
    --------
    >>> r = Run(model="housner", e=0.85, nu=2.0, theta_cr=0.25, sigma_p=0.003, dt=0.01, burn_in=0, sigma_y=0.01,
    ...         sigma_ydot=0.1, points_per_cycle=25.9, points_per_cycle_target=75.0)
    >>> points_per_cycle_shortfall(r)
    'the series have about 25.9 samples per rocking cycle at sigma_Y (eq. 5), not the 75 requested (65% fewer; the housner model at dt = 0.01 s): give dt for the sampling you need, or read the series at the sampling they have'
    """
    got, want = contract.points_per_cycle, contract.points_per_cycle_target
    if not (np.isfinite(got) and np.isfinite(want) and want > 0) or abs(got / want - 1.0) <= PPC_TOLERANCE:
        return None
    side = f"{1 - got / want:.0%} fewer" if got < want else f"{got / want - 1:.0%} more"
    return (
        f"the series have about {got:.3g} samples per rocking cycle at sigma_Y (eq. 5), not the {want:g} requested ({side}; "
        f"the {contract.model} model at dt = {contract.dt:.4g} s): give dt for the sampling you need, or read the series "
        "at the sampling they have"
    )


def simulation_report(theta, contract: Run, seeds=None, *, step_given: bool = False) -> list[str]:
    """What a simulation made that its caller should tell (or refuse): series that overturned
    (:func:`overturned`) and samples per cycle that miss the requested ones
    (:func:`points_per_cycle_shortfall`); one sentence each, none when all went as asked.

    Parameters
    ----------
    theta : array_like, xarray.DataArray or Dask array
        The simulated angles ``theta(seed, time)`` (computed values: a lazy array is simulated again).
    contract : Run
        The run that made them.
    seeds : array_like, optional
        Their seeds (default: the DataArray's ``seed`` coordinate, else row indices).
    step_given : bool
        The caller set the step itself (``dt``): no samples per cycle were requested.

    Returns
    -------
    list of str

    Examples
    --------
    >>> r = Run(model="housner", e=0.85, nu=2.0, theta_cr=0.25, sigma_p=0.003, dt=0.01, burn_in=0, sigma_y=0.01,
    ...         sigma_ydot=0.1, points_per_cycle=74.0, points_per_cycle_target=75.0)
    >>> simulation_report(np.array([[0.1, 0.2], [0.3, np.nan]]), r, seeds=[13, 14])
    ['1 of 2 series overturned (the housner model, eq. 2) and are NaN from the fall on (up to 50% of a series; seeds 14): lower sigma_p, or use them only up to the fall']
    """
    out = []
    fell = overturned(theta, seeds)
    if fell.count:
        listed = ", ".join(map(str, fell.seeds[:10])) + (", ..." if fell.count > 10 else "")
        out.append(
            f"{fell.count} of {fell.series} series overturned (the {contract.model} model, eq. 2) and are NaN from the fall on "
            f"(up to {fell.worst:.0%} of a series; seeds {listed}): lower sigma_p, or use them only up to the fall"
        )
    shortfall = None if step_given else points_per_cycle_shortfall(contract)
    if shortfall:
        out.append(shortfall)
    return out

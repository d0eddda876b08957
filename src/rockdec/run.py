"""The run contract: everything that fixes a scene's simulated series, built once and passed on.

A :class:`Run` holds the rocking system (``e``, ``nu``, ``theta_cr``; eqs. 2, 4, 6), the load
(``sigma_p``, eqs. 21-24), the sampling (``dt``, ``burn_in``), the initial state, the model
that runs and the stationary statistics measured at that step (``sigma_y``,
``sigma_ydot``, samples per cycle at ``sigma_Y``, eq. 5). Given a seed it determines the
series bit for bit (:meth:`Run.dataset`), and its statistics set the trigger levels of
every signature of the scene (one level for all series, docs/method.md §4.4).

Every path builds it once: the workflow's rule ``calibrate`` (:func:`calibrate`, written
as ``run.json``), the command line, the coverage, trade-off and amplitude studies; it
travels as NetCDF attributes (:meth:`Run.to_attrs`, :meth:`Run.from_attrs`) in every file
made from it. The kernels and their Dask wrapper stay in :mod:`rockdec.simulate`.
"""

from __future__ import annotations

import dataclasses
import json
import math
import warnings
from pathlib import Path

import numpy as np
import xarray as xr

from rockdec import simulate
from rockdec import validate as checks
from rockdec.housner import choose_model, simulate_block_housner
from rockdec.models import MODEL_PEAK_SIGMAS, period_from_g, restoring_acceleration

#: Series and points of the pilot that measures the statistics at a given step.
PILOT_SERIES, PILOT_POINTS = 64, 40_000


@dataclasses.dataclass(frozen=True)
class Run:
    """One simulated run: what a seed needs to become a series, and the scene's statistics.

    ``model``: ``"simplified"`` (eq. 4), ``"housner"`` (eq. 2) or ``"fixed_step"`` (eq. 4
    with the grid-impact integrator of :mod:`rockdec.fixed_step`); ``e`` (eq. 6), ``nu``
    (rad/s), ``theta_cr`` (rad), ``sigma_p`` (rad/s, std of the velocity impulses),
    ``dt`` (s), ``burn_in`` (steps discarded), ``theta0``/``theta_dot0`` (state at the start
    of the burn-in); ``sigma_y`` (rad), ``sigma_ydot`` (rad/s, of the sampled slope) and
    ``points_per_cycle`` (samples per cycle at ``sigma_Y``, eq. 5) measured by a pilot at
    ``dt`` (NaN for a free response); ``points_per_cycle_target`` (what set ``dt``) and
    ``model_reason`` (why this model) say how it was chosen.
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

    @property
    def g(self) -> float:
        """The restoring acceleration ``nu^2 theta_cr`` of eq. 4, in rad/s^2."""
        return restoring_acceleration(self.nu, self.theta_cr)

    def to_attrs(self) -> dict:
        """The run as NetCDF attributes (numbers and strings), ``g`` added for readers."""
        return {**dataclasses.asdict(self), "g": self.g}

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
        return cls(**{name: cast[kinds[name]](attrs[name]) for name in kinds if name in attrs})

    def dataset(self, seeds, n_points: int, chunk_seeds: int = 100) -> xr.Dataset:
        """Lazy ``theta(seed, time)``, ``theta_dot(seed, time)`` of ``seeds`` under this run
        (:func:`rockdec.simulate.simulation_dataset`), its attributes :meth:`to_attrs`."""
        ds = simulate.simulation_dataset(
            seeds, n_points, dt=self.dt, g=self.g, e=self.e, sigma_p=self.sigma_p, theta0=self.theta0,
            theta_dot0=self.theta_dot0, burn_in=self.burn_in, chunk_seeds=chunk_seeds, model=self.model,
            theta_cr=self.theta_cr,
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


def calibrate(scene: dict, amplitude: float = 0.0, theta0: float = 0.0, theta_dot0: float = 0.0) -> Run:
    """The run of a scene's ``model``, ``system`` and ``excitation`` sections.

    ``dt`` comes from the scene or from :func:`rockdec.simulate.calibrate_dt`; the burn-in
    from the scene or :func:`rockdec.simulate.default_burn_in`. Stationary statistics are
    measured by a pilot at that step, with the model that runs (``auto`` chooses by the
    amplitude, :func:`model_for`). Without noise (``sigma_p = 0``, a free response from
    ``theta0``) there is no ``sigma_Y``: the step then gives ``points_per_cycle`` samples
    per cycle at ``amplitude`` (eq. 5), no burn-in.
    """
    system, exc = scene["system"], scene["excitation"]
    g = restoring_acceleration(system["nu"], system["theta_cr"])
    e, sigma_p = system["e"], exc["sigma_p"]
    if sigma_p == 0.0:
        if exc["dt"] is None and amplitude <= 0.0:
            raise checks.InputError("a free response (sigma_p = 0) needs --theta0 > 0 to set the step, or --dt")
        dt = exc["dt"] if exc["dt"] is not None else float(period_from_g(abs(amplitude), g)) / exc["points_per_cycle"]
        nan = math.nan
        cal = {"dt": dt, "burn_in": 0, "sigma_y": nan, "sigma_ydot": nan, "points_per_cycle": nan}
    elif exc["dt"] is None:
        cal = simulate.calibrate_dt(e=e, g=g, sigma_p=sigma_p, points_per_cycle=exc["points_per_cycle"])
    else:
        burn_in = exc["burn_in"] if exc["burn_in"] is not None else simulate.default_burn_in(e, exc["points_per_cycle"])
        theta, _ = simulate.simulate_block(
            np.arange(PILOT_SERIES) + simulate.PILOT_SEED_OFFSET, PILOT_POINTS, dt=exc["dt"], g=g, e=e, sigma_p=sigma_p,
            burn_in=burn_in,
        )
        cal = {"dt": exc["dt"], "burn_in": burn_in, **simulate.pilot_statistics(theta, exc["dt"], g)}
    if exc["burn_in"] is not None:
        cal["burn_in"] = exc["burn_in"]
    model, reason = model_for(scene["model"], cal["sigma_y"], system["theta_cr"])
    if model == "housner" and sigma_p > 0.0:
        # the trigger level and sampling follow the model that runs: re-measure the pilot
        theta, _, _ = simulate_block_housner(
            np.arange(PILOT_SERIES) + simulate.PILOT_SEED_OFFSET, PILOT_POINTS, dt=cal["dt"], nu=system["nu"],
            theta_cr=system["theta_cr"], e=e, sigma_p=sigma_p, burn_in=cal["burn_in"],
        )
        standing = np.all(np.isfinite(theta), axis=1)
        if standing.mean() < 0.5:
            raise checks.InputError(
                f"the block overturns in {1 - standing.mean():.0%} of the pilot series ({MODEL_PEAK_SIGMAS:g} sigma_Y/theta_cr = "
                f"{MODEL_PEAK_SIGMAS * cal['sigma_y'] / system['theta_cr']:.2g}): no stationary rocking exists; lower sigma_p"
            )
        cal.update(simulate.pilot_statistics(theta[standing], cal["dt"], g))
    return Run(
        model=model, e=e, nu=system["nu"], theta_cr=system["theta_cr"], sigma_p=sigma_p, dt=cal["dt"],
        burn_in=int(cal["burn_in"]), sigma_y=cal["sigma_y"], sigma_ydot=cal["sigma_ydot"],
        points_per_cycle=cal["points_per_cycle"], points_per_cycle_target=float(exc["points_per_cycle"]),
        model_reason=reason, theta0=float(theta0), theta_dot0=float(theta_dot0),
    )


def model_for(requested: str, sigma_y: float, theta_cr: float) -> tuple[str, str]:
    """The model a scene runs, and why: as requested, or for ``auto`` by the amplitude.

    ``auto`` judges the amplitude by ``3 sigma_Y / theta_cr`` (:data:`rockdec.models.
    MODEL_PEAK_SIGMAS`) with :func:`rockdec.housner.choose_model`: the simplified model
    while the periods of eqs. 3 and 5 agree within 2 % (:data:`rockdec.models.
    MODEL_TOLERANCE`), Housner beyond. A requested model is kept, with a warning in the
    reason when it leaves its validity.
    """
    ratio = MODEL_PEAK_SIGMAS * sigma_y / theta_cr if np.isfinite(sigma_y) else 0.0
    chosen, why = choose_model(ratio)
    if requested == "auto":
        return chosen, f"auto: {why}"
    if requested == "simplified" and chosen == "housner":
        warnings.warn(f"the simplified model is outside its validity region: {why}", RuntimeWarning, stacklevel=3)
        return requested, f"requested; outside its validity: {why}"
    return requested, "requested"

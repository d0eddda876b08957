"""The file steps of ``rockdec signatures`` and ``rockdec estimates``: a series file in,
signature sums out (eq. 19); signature sums in, every estimator extrapolated to a zero
window out (eqs. 25-27). Messages name the Python parameters in backquotes."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import xarray as xr

from rockdec import io
from rockdec import validate as checks
from rockdec.physics import simulate
from rockdec.pipeline import replicates
from rockdec.rdd import signatures
from rockdec.record import records

__all__ = ["MIN_LAGS", "estimate_file", "signature_file"]

#: Fewest lags on each side of a signature for the fits of the estimators.
MIN_LAGS = 8


def _series(source, variable: str) -> tuple[xr.DataArray, dict]:
    """``variable`` of the file ``source`` as ``(seed, time)`` in rad with its step as the
    attribute ``dt`` (from the file's ``dt`` attribute, else its time coordinate), and the
    file's attributes; refuses infinite values and constant series."""
    with io.open_dataset(source) as src:
        if variable not in src:
            raise checks.InputError(f"{source} has no variable '{variable}'; name it with `variable`.")
        theta = src[variable].load()
        attrs = dict(src.attrs)
    if theta.ndim == 1:
        theta = theta.expand_dims(seed=[0])
    if set(theta.dims) != {"seed", "time"}:
        raise checks.InputError(f"'{variable}' must have dimensions (seed, time) or (time); it has {theta.dims}.")
    theta = theta.transpose("seed", "time").astype(float)
    theta = theta.copy(data=theta.values * records.angle_factor(theta.attrs.get("units"), source, variable))
    if "dt" in attrs:
        try:
            (step,) = np.asarray(attrs["dt"], dtype=np.float64).ravel()
        except (TypeError, ValueError):
            raise checks.InputError(f"{source}: its attribute dt {attrs['dt']!r} is not a number of seconds; fix it.") from None
        theta.attrs["dt"] = checks.positive(step, f"the attribute dt of {source}", "fix it (the sampling step in s)")
    elif "time" in theta.coords:
        theta.attrs["dt"] = records.sampling_step(theta["time"].values, f"{source}: '{variable}'") * records.time_factor(
            theta["time"].attrs.get("units"), source, "time"
        )
    else:
        raise checks.InputError(f"{source}: '{variable}' has no time coordinate and the file no 'dt' attribute; add either.")
    if np.isinf(theta.values).any():
        raise checks.InputError(f"{source}: '{variable}' holds infinite values; remove them or mark them as gaps (NaN).")
    with np.errstate(invalid="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # an all-NaN series is refused just below
        still = ~(np.nanmax(theta.values, axis=1) > np.nanmin(theta.values, axis=1))
    if still.any():
        k = int(np.flatnonzero(still)[0])
        raise checks.InputError(f"{source}: series {k} of '{variable}' is constant (or all NaN), so it has no trigger; a rocking record must move.")
    return theta, attrs


def signature_file(source, out: Path, settings: dict, *, variable: str = "theta", g: float | None = None,
                   group_size: int | None = None, overwrite: bool = False) -> dict:
    """Signature sums (eq. 19) of the series in ``source`` written to ``out``; returns the
    triggers per window, ``{"a": ..., "v": ...}``.

    ``settings``: the scene's ``signatures`` section (validated); ``g`` (rad/s^2): the
    restoring acceleration that sizes the lag range (else the file's attribute ``g``);
    ``group_size``: series pooled per signature (``None``: all). The trigger levels come
    from the file's ``sigma_y``/``sigma_ydot`` attributes, else one pass over the series.
    """
    theta, attrs = _series(source, variable)
    scales = {name: attrs.get(name) for name in ("sigma_y", "sigma_ydot")}
    missing = [name for name, value in scales.items() if value is None or not np.isfinite(value)]
    if missing:  # the file's stationary statistics, else measured (one pass over the record)
        measured = simulate.pilot_statistics(theta.values, theta.attrs["dt"])
        scales.update({name: measured[name] for name in missing})
    stats = {**{name: float(value) for name, value in scales.items()}, "g": g if g is not None else attrs.get("g")}
    if stats["g"] is None:
        raise checks.InputError(f"{source} does not say g (rad/s^2): give `g` to size the lag range in rocking periods.")
    g_name = "`g`" if g is not None else f"the attribute g of {source}"
    stats["g"] = checks.positive(stats["g"], g_name, "give `g`, the restoring acceleration nu^2 theta_cr in rad/s^2")
    n_series = theta.sizes["seed"]
    if group_size is not None:
        checks.integer(group_size, "`group_size`", 1, "give at least 1 series per signature (or leave it out: all)")
        if group_size > n_series:
            raise checks.InputError(
                f"`group_size` {group_size}: more than the {n_series} series in {source}; give at most {n_series} (or leave it out: all)."
            )
    size = group_size or n_series
    n_lag = signatures.lag_samples(settings["n_periods"], settings["level"] * stats["sigma_y"], stats["g"], theta.attrs["dt"])
    if n_lag < MIN_LAGS:
        raise checks.InputError(
            f"{g_name} {checks.show(stats['g'])} with `n_periods` {checks.show(settings['n_periods'])} gives a lag range of {n_lag} "
            f"samples, fewer than the {MIN_LAGS} the fits need; give the right g, or `n_periods` near 2.5 (the default)."
        )
    signatures.check_lag_range(
        n_lag, theta.sizes["time"], n_series, len(settings["windows"]),
        f"{g_name} {checks.show(stats['g'])} with `n_periods` {checks.show(settings['n_periods'])}",
        "raise `g` or lower `n_periods` (or pool fewer series with `group_size`)",
    )
    if size == 1:  # one signature per series: the cube keeps the seed dimension
        cube = replicates.scene_signatures(theta, settings, **stats, group=None, replicate_of_group=np.zeros(n_series, dtype=int))
    else:
        group = np.arange(n_series) // size
        cube = replicates.scene_signatures(theta, settings, **stats, group=group, replicate_of_group=np.arange(group.max() + 1))
    cube.attrs.update(io.provenance("signatures", settings, inputs=[source]))
    io.write_netcdf(cube, out, overwrite=overwrite)
    counts = cube["count"].sum(replicates.series_dim(cube))
    return {trigger: counts.sel(trigger=trigger).values for trigger in ("a", "v")}


def estimate_file(source, out: Path, *, fit_points: int, weights: str, overwrite: bool = False) -> xr.Dataset:
    """Every estimator of ``e`` (eqs. 25-27, ``e_v``) at every window of the signature file
    ``source`` and extrapolated to a zero window, written to ``out`` and returned."""
    checks.integer(fit_points, "`fit_points`", 3, "give at least 3 points per side (a parabola needs 3)")
    with io.open_dataset(source) as src:
        if "signature_sum" not in src or not {"group", "seed"} & set(src.dims) or "count" not in src or "dt" not in src.attrs:
            raise checks.InputError(f"{source} is not a signature file; make one with 'rockdec signatures'.")
        cube = src.load()
    lags = cube.sizes["lag"] // 2
    if fit_points > lags:
        raise checks.InputError(f"`fit_points` {fit_points}: more than the {lags} lags of the signatures in {source}; give at most {lags}.")
    if "replicate" not in cube.coords:
        dim = replicates.series_dim(cube)
        cube = cube.assign_coords(replicate=(dim, np.zeros(cube.sizes[dim], dtype=int)))
    est = replicates.replicate_estimates(cube, fit_points=fit_points, weights=weights)
    est.attrs.update(io.provenance("estimates", {"fit_points": fit_points, "weights": weights}, inputs=[source]))
    io.write_netcdf(est, out, overwrite=overwrite)
    return est

"""The public functions of rockdec: estimate ``e`` from a record, read a record, simulate one.

:func:`estimate` takes the record in the forms a notebook holds it (a NumPy array with its
step, an ``xarray.DataArray`` or a ``pandas.Series`` with a time axis, or a list of them:
records of one block, pooled), checks it, and runs the estimate's stages
(:func:`rockdec.estimation.estimate`) into a :class:`rockdec.RestitutionEstimate`.
:func:`read_record` reads the files laboratories write; :func:`simulate` makes a record of
known ``e`` with the simulator of ``rockdec simulate``. Errors name the Python parameter
(``dt``, ``load``): :class:`rockdec.InputError`, :class:`rockdec.RecordError` for a record.
"""

from __future__ import annotations

import math
import warnings
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from rockdec.cache import cache_folder
from rockdec import estimation
from rockdec.physics.geometry import Block, parse_block
from rockdec.physics.record_model import check_filter_declared_with_model, declared_load, parse_sensor_filter, parse_sensor_noise
from rockdec.record import records as records_mod
from rockdec.report.estimate_report import document
from rockdec.report.result import RestitutionEstimate
from rockdec.report.summary import with_block
from rockdec.timeaxis import RecordError, angle_factor
from rockdec.validate import InputError, positive, show
from rockdec.warning_types import SimulationWarning

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["block_angle", "estimate", "estimate_options", "free_rocking", "read_record", "shake_table", "simulate"]

#: Rocking models :func:`estimate` calibrates with.
MODELS = ("simplified", "housner")

#: The attributes of the time axis of a record in memory (:func:`simulate`, :func:`read_record`):
#: seconds from its first sample, with no reference date, so a plot labels it ``[s]``.
RELATIVE_TIME = {"units": "s", "standard_name": "time"}


def _series_arrays(theta, dt: float | None, source: str) -> list[tuple[np.ndarray, float | None, str]]:
    """``(angles in rad, step in s or None, source)`` of each record of one input of
    :func:`estimate` or :func:`free_rocking` (not yet checked as a record)."""
    if isinstance(theta, records_mod.Record):  # as rockdec.record.records.read_records reads it: no pandas, no xarray
        return [(theta.theta, theta.dt, theta.source)]
    import pandas as pd
    import xarray as xr

    if isinstance(theta, pd.Series):
        index = theta.index
        if isinstance(index, pd.DatetimeIndex | pd.TimedeltaIndex):
            time = np.asarray((index - index[0]) / pd.Timedelta(seconds=1), dtype=np.float64)
        elif pd.api.types.is_numeric_dtype(index) and not isinstance(index, pd.RangeIndex):
            time = np.asarray(index, dtype=np.float64)
        else:
            time = None
        theta = xr.DataArray(theta.to_numpy(dtype=np.float64), dims="time", coords=None if time is None else {"time": time},
                             name=theta.name)
    if isinstance(theta, xr.DataArray):
        return _data_array_arrays(theta, dt, source)
    values = np.asarray(theta)
    if values.dtype.kind not in "fiu":
        raise InputError(f"`theta` ({source}) holds {values.dtype} values; give the angles as numbers in rad.")
    if values.ndim != 1:
        raise InputError(f"`theta` ({source}) has shape {values.shape}; give a 1-D record, or a list of 1-D records of one block.")
    return [(values.astype(np.float64), None if dt is None else _step(dt), source)]


def _step(dt) -> float:
    try:
        step = float(dt)
    except (TypeError, ValueError):
        raise InputError(f"`dt` {dt!r} is not a number; give the sampling step in s, > 0.") from None
    if not (math.isfinite(step) and step > 0):
        raise InputError(f"`dt` {show(step)}: not a positive, finite number of seconds; give the sampling step in s, > 0.")
    return step


def _data_array_arrays(da: xr.DataArray, dt: float | None, source: str) -> list[tuple[np.ndarray, float | None, str]]:
    """The records of a DataArray (:func:`_series_arrays`): 1-D along its time dimension, or
    2-D (one record per row)."""
    source = str(da.attrs.get("source", da.name if da.name is not None else source))
    if da.ndim not in (1, 2):
        raise InputError(f"`theta` ({source}) has dimensions {da.dims}; give (time) or (record, time).")
    dim = "time" if "time" in da.dims else da.dims[-1]
    da = da.transpose(..., dim)
    values = np.asarray(da.values, dtype=np.float64) * angle_factor(da.attrs.get("units"), source, str(da.name or "theta"))
    step = None
    if dim in da.coords:
        step = records_mod.sampling_step(da[dim].values, source)
        if "dt" in da.attrs:
            stated = _step(da.attrs["dt"])
            if abs(stated - step) > 1e-6 * step:
                raise RecordError(f"{source}: its attribute dt {stated:g} s disagrees with its time axis ({step:g} s); fix one.")
            step = stated
    elif "dt" in da.attrs:
        step = _step(da.attrs["dt"])
    if dt is not None:
        given = _step(dt)
        if step is not None and abs(given - step) > 1e-6 * step:
            raise InputError(f"`dt` {given:g} s disagrees with the time axis of {source} ({step:g} s); leave `dt` out.")
        step = given
    if values.ndim == 1:
        return [(values, step, source)]
    names = da.attrs.get("sources")
    rows = names.split("\n") if isinstance(names, str) and len(names.split("\n")) == values.shape[0] else None
    return [(row, step, rows[i] if rows else f"{source}[{i}]") for i, row in enumerate(values)]


def _arrays(theta, dt) -> list[tuple[np.ndarray, float, str]]:
    """``(angles, step, source)`` of every record of ``theta``, each with its step."""
    if isinstance(theta, list | tuple):
        if not theta:
            raise InputError("`theta` is an empty list; give at least one record.")
        out = [r for i, item in enumerate(theta) for r in _series_arrays(item, dt, f"record {i}")]
    else:
        out = _series_arrays(theta, dt, "record")
    for _, step, source in out:
        if step is None:
            raise InputError(f"`theta` ({source}) has no time axis; give its sampling step `dt` in s.")
    return out


def _records(theta, dt) -> list[records_mod.Record]:
    """Every record of :func:`estimate`'s ``theta``, checked (:func:`rockdec.record.records.check_values`)."""
    return [records_mod.check_values(values, step, source) for values, step, source in _arrays(theta, dt)]


def estimate(theta, dt: float | None = None, *, g: float | None = None, load="auto", sensor_noise="auto", sensor_filter="auto",
             model: str = "simplified", theta_cr: float | None = None, cache=None, repair: bool = True,
             block=None, share_lengths: bool = False) -> RestitutionEstimate:
    """Estimate the coefficient of restitution ``e`` of a rocking block from its random response.

    The record's Random Decrement signatures (paper eqs. 8, 19) give every estimator of
    ``e`` (eqs. 25-27 and ``e_v``); records simulated at known ``e`` with the record's
    length, sampling and model (the calibration, built once and stored in ``cache``)
    correct their bias and give each a 95 % interval; the trusted estimator with the
    narrowest interval is reported.

    Parameters
    ----------
    theta : array_like, xarray.DataArray, pandas.Series, or list of them
        The rocking angle. A 1-D array needs ``dt``. A DataArray gives its step by its
        time coordinate (or a ``dt`` attribute, s) and its ``units`` (``rad``, ``mrad`` or
        ``degree``; any other is refused); a 2-D DataArray holds one record per row. A
        Series gives its step by a numeric (s), datetime or timedelta index. A list holds
        records of one block, pooled (one step for all).
    dt : float, optional
        Sampling step in s, for arrays without a time axis.
    g : float, optional
        The block's restoring acceleration ``nu^2 theta_cr`` in rad/s^2 (eq. 4), if known;
        read off the record otherwise.
    load : str or Load, optional
        The load the calibration simulates: ``"auto"`` (measured off the record: white, or
        low-pass when its colour is detected), ``"white"``, ``"lowpass:CORNER"`` (corner in
        rocking frequencies, eq. 5), ``"spectrum:FILE"`` or ``"base:FILE"``.
    sensor_noise : str, float or SensorNoise, optional
        ``"auto"`` (measured), ``0``, a standard deviation in rad, or ``"N%"`` of sigma_Y.
    sensor_filter : str, SensorFilter or None, optional
        A low-pass filter between the block and the record, which the calibration applies to
        its simulated records: ``"auto"`` (the record is checked for one and ``e`` declined
        when it shows one), ``"none"`` (the record is unfiltered; impacts blunted as a filter
        or a soft contact blunts them still decline ``e``), or
        ``"butterworth:ORDER:CORNER:PHASE"`` / ``"rc:CORNER:PHASE"`` with CORNER in rocking
        frequencies (eq. 5) or Hz (``12hz``) and PHASE ``zero-phase`` or ``causal``; declare
        ``load`` and ``sensor_noise`` beside it.
    model : {"simplified", "housner"}
        The rocking model of the calibration: eq. 4, or Housner's eq. 2 (needs ``theta_cr``).
    theta_cr : float, optional
        The block's critical angle in rad, for ``model="housner"`` (default with ``block``:
        its ``atan(B/H)``).
    cache : str or path, optional
        Folder of stored calibrations; ``None``: :func:`rockdec.cache.default_cache` (shared with
        the command line).
    repair : bool
        Repair the record first (:mod:`rockdec.record.repair`): isolated spikes are replaced by the line through their neighbours
        and, when the record drifts, a zero-phase high-pass well below the rocking frequency
        removes the drift; the calibration's simulated records are repaired alike, and the
        result's ``repair`` says what was done. ``False``: estimate the record as given.
    block : tuple of float, optional
        The block's height and width ``(H, B)``, one unit: the report sets Housner's
        ``e = 1 - 1.5 sin^2(atan(B/H))`` beside the measured one.
    share_lengths : bool
        Calibrate on the length grid (two lengths a decade, from 1,000 to 200,000 samples
        in all): records of nearby lengths share one calibration, simulated at the grid
        length at or below theirs and its spread scaled by ``sqrt(grid / record)``; a
        campaign of records of many lengths then builds few calibrations. ``False``:
        calibrate at the records' own length.

    Returns
    -------
    RestitutionEstimate

    Raises
    ------
    InputError
        A parameter the function cannot use; the message names it and the fix.
    RecordError
        A record that cannot be analysed (too short, constant, not rocking, ...).

    Examples
    --------
    >>> import rockdec
    >>> theta = rockdec.simulate(0.85, 20_000, seed=1)
    >>> res = rockdec.estimate(theta)
    >>> res.confidence_interval.low < 0.85 < res.confidence_interval.high
    True
    """
    block, theta_cr = block_angle(block, model, theta_cr)
    declared, folder = estimate_options(g=g, load=load, sensor_noise=sensor_noise, sensor_filter=sensor_filter, model=model,
                                        theta_cr=theta_cr, cache=cache)
    if not isinstance(repair, bool):
        raise InputError(f"`repair` {show(repair)} is not True or False; give True to repair spikes and drift, False to leave the record as given.")
    if not isinstance(share_lengths, bool):
        raise InputError(f"`share_lengths` {show(share_lengths)} is not True or False; give True to share calibrations across nearby lengths.")
    outcome = estimation.estimate(_records(theta, dt), cache_dir=folder, g=g, rocking=model, theta_cr=theta_cr, repair_records=repair,
                                 length_grid=share_lengths, **declared)
    return RestitutionEstimate.from_dict(with_block(document(outcome), block), analysis=outcome.analysis, belts=outcome.belts)


def block_angle(block, model: str, theta_cr: float | None) -> tuple[Block | None, float | None]:
    """The block ``(H, B)`` as a :class:`~rockdec.physics.geometry.Block` and the critical
    angle the Housner model takes: ``theta_cr`` if given (refused when it is not the block's
    ``atan(B/H)``), else the block's under ``model="housner"``.

    Examples
    --------
    >>> from rockdec.api import block_angle
    >>> block, theta_cr = block_angle((0.6, 0.2), "housner", None)
    >>> round(theta_cr, 4)
    0.3218
    """
    block = parse_block(block)
    if block is None:
        return None, theta_cr
    if theta_cr is not None and isinstance(theta_cr, int | float) and not math.isclose(theta_cr, block.theta_cr, rel_tol=1e-6):
        raise InputError(f"`theta_cr` {show(theta_cr)} is not the block's atan(B/H) = {block.theta_cr:.6g} rad; give one of the two, "
                         "or the block's true height and width.")
    return block, (block.theta_cr if model == "housner" and theta_cr is None else theta_cr)


def estimate_options(*, g=None, load="auto", sensor_noise="auto", sensor_filter="auto", model="simplified", theta_cr=None,
                     cache=None) -> tuple[dict, Path]:
    """Check :func:`estimate`'s options before any record is read: the declared record
    model (``load``, ``sensor``, ``sensor_filter``) as :func:`rockdec.estimation.estimate`
    takes it, and the calibration folder.

    Raises
    ------
    InputError
        An option :func:`estimate` cannot use, named with its fix.

    Examples
    --------
    >>> from rockdec.api import estimate_options
    >>> declared, folder = estimate_options(load="white", sensor_noise="2%")
    >>> declared["sensor"].std
    0.02
    """
    if model not in MODELS:
        raise InputError(f"`model` {model!r} is not a rocking model; give one of {', '.join(MODELS)}.")
    if model == "housner":
        if theta_cr is None:
            raise InputError("`model` housner needs the block's critical angle: give `theta_cr` in rad (atan(width/height)).")
        if not (isinstance(theta_cr, int | float) and 0.0 < theta_cr < math.pi / 2):
            raise InputError(f"`theta_cr` {show(theta_cr)} is not a critical angle; give it in rad, between 0 and pi/2.")
    elif theta_cr is not None:
        raise InputError("`theta_cr` is the Housner model's critical angle; give `model` housner with it, or leave it out.")
    if g is not None:
        positive(g, "`g`", "give the restoring acceleration nu^2 theta_cr in rad/s^2, or leave it out")
    declared = {"load": declared_load(load), "sensor": parse_sensor_noise(sensor_noise), "sensor_filter": parse_sensor_filter(sensor_filter)}
    check_filter_declared_with_model(declared["sensor_filter"], declared["load"], declared["sensor"])
    return declared, cache_folder(cache)


def free_rocking(theta, dt: float | None = None, *, model: str = "simplified", theta_cr: float | None = None,
                 block=None) -> RestitutionEstimate:
    """Estimate ``e`` from a free-rocking test: the block tilted, released, rocking down to rest.

    The reference test laboratories run first. Each release and each impact (zero
    crossing) is found to sub-sample precision; each flight between impacts is fitted with
    the model's closed-form free flight (a parabola, eq. 4, or Housner's eq. 2); ``e`` of
    each impact is the ratio of the angular speeds just after and just before it (eq. 6);
    one ``e`` with its 95 % interval comes from the line of the log impact speeds over every
    impact of every release, and ``g`` (or ``nu``) from the arcs. The analysis of a release
    stops where its arcs become too short to fit, and says where and why.

    Parameters
    ----------
    theta : array_like, xarray.DataArray, pandas.Series, or list of them
        The rocking angle, in the forms :func:`estimate` takes; several records (or several
        releases in one record) of one block are pooled.
    dt : float, optional
        Sampling step in s, for arrays without a time axis.
    model : {"simplified", "housner"}
        The free flight between impacts.
    theta_cr : float, optional
        The block's critical angle in rad (needed by ``"housner"``; gives ``nu``; default
        with ``block``: its ``atan(B/H)``).
    block : tuple of float, optional
        The block's height and width ``(H, B)``, one unit: the report sets Housner's ``e``
        beside the measured one.

    Returns
    -------
    RestitutionEstimate
        With ``test == "free"``; ``impacts`` holds the table of impacts.

    Raises
    ------
    InputError, RecordError
        A record that is not a free-rocking test (no release, a random response, a block
        that never comes to rest or overturns, clipping, ...), in one sentence.

    Examples
    --------
    >>> import rockdec
    >>> theta = rockdec.simulate(0.9, 3_000, seed=0, sigma_p=0.0, theta0=0.01)
    >>> res = rockdec.free_rocking(theta)
    >>> round(res.e, 6), res.test
    (0.9, 'free')
    """
    from rockdec.free.analysis import analyse_free_rocking
    from rockdec.report.free_result import free_document

    block, theta_cr = block_angle(block, model, theta_cr)
    arrays = _arrays(theta, dt)
    values, steps = [a[0] for a in arrays], [a[1] for a in arrays]
    many = len(arrays) > 1
    fit = analyse_free_rocking(values if many else values[0], steps if many else steps[0], model=model, theta_cr=theta_cr)
    doc = free_document(fit, [a[2] for a in arrays], steps, [v.size for v in values])
    return RestitutionEstimate.from_dict(with_block(doc, block), analysis=(fit, values if many else values[0], steps if many else steps[0]))


def shake_table(theta, base, dt: float | None = None, *, base_units: str | None = None, block=None, theta_cr: float | None = None,
                g_block: float | None = None, model: str = "simplified", start: float | None = None) -> RestitutionEstimate:
    """Estimate ``e`` from a shake-table test: the free-decay tails, and every impact with
    the base as a known load.

    The base acceleration, divided by the level that lifts the block (``g tan(alpha)``),
    says when the shaking ends: after 95 % of its Arias intensity and its last sample above
    5 % of that level. Every stretch as quiet as that, at least 1 s long, after the base
    first could lift the block, is a free decay: each is analysed as a free-rocking test
    (:func:`free_rocking`) and all are pooled into one ``e``. A base that still moves in a
    tail is refused with its reason, never fitted as if free. Every impact of the records
    is read too, the flights fitted with the base's load in them
    (``rockdec.free.forced``, the simplified model only; the base read both linear between
    its samples and held over each, the interval the union of the two); the result's ``e``
    is the reading with the narrower interval (``estimator`` "impacts" or "forced").

    Parameters
    ----------
    theta : array_like, xarray.DataArray, pandas.Series, or list of them
        The rocking angle, in the forms :func:`estimate` takes; several records of one block
        are pooled.
    base : array_like, xarray.DataArray, pandas.Series, or list of them
        The base acceleration, one sample per angle (a list: one per record).
    dt : float, optional
        Sampling step in s, for arrays without a time axis.
    base_units : {"m/s2", "g", "rad/s2"}, optional
        The base's units; default: a DataArray's ``units`` attribute. "m/s2" and "g" need the
        block's critical angle (``block`` or ``theta_cr``); "rad/s2", the simplified rocking
        equation's load, needs ``g_block``.
    block : tuple of float, optional
        The block's height and width ``(H, B)``, one unit: gives ``theta_cr = atan(B/H)``
        and sets Housner's ``e`` beside the measured one.
    theta_cr : float, optional
        The critical angle in rad.
    g_block : float, optional
        The block's restoring acceleration ``nu^2 theta_cr`` in rad/s^2 (base in "rad/s2").
    model : {"simplified", "housner"}
        The free flight the tails are fitted with.
    start : float, optional
        The tail's start (s from each record's start), cut by hand instead of found.

    Returns
    -------
    RestitutionEstimate
        With ``test == "shake"``; ``impacts`` holds the impacts of the tails,
        ``estimators`` both readings, and ``to_dict()["shake_table"]`` where the shaking
        ends, each tail and every impact's reading (``forced``: per record and pooled).

    Raises
    ------
    InputError, RecordError
        A base missing its units, sampled otherwise than the angle, or not one per record,
        and the refusals of :func:`free_rocking`, in one sentence.

    Examples
    --------
    >>> import numpy as np, rockdec
    >>> free = rockdec.simulate(0.9, 2_000, seed=0, sigma_p=0.0, theta0=0.01, dt=0.005).values
    >>> theta = np.concatenate([np.zeros(400), free])
    >>> base = np.concatenate([np.where(np.arange(400) % 2, 3.0, -3.0), np.zeros(2_000)])
    >>> res = rockdec.shake_table(theta, base, 0.005, base_units="rad/s2", g_block=1.0)
    >>> round(res.e, 6), res.test, res.to_dict()["shake_table"]["shaking_end"]
    (0.9, 'shake', [2.0])
    """
    from rockdec.free.shake import analyse_shake_table
    from rockdec.report.shake_result import shake_document

    block, theta_cr = block_angle(block, model, theta_cr)
    if theta_cr is None and block is not None:
        theta_cr = block.theta_cr
    arrays = _arrays(theta, dt)
    bases, units = _base_arrays(base, arrays, base_units)
    values, steps = [a[0] for a in arrays], [a[1] for a in arrays]
    many = len(arrays) > 1
    fit = analyse_shake_table(values if many else values[0], bases if many else bases[0], steps, base_units=units, g_block=g_block,
                              theta_cr=theta_cr, model=model, start=start)
    doc = shake_document(fit, [a[2] for a in arrays], steps, [v.size for v in values], base_units=units, model=model, theta_cr=theta_cr)
    pieces = [values[k][round(t0 / steps[k]):round(t1 / steps[k])] for k, t0, t1 in fit.tails]
    times = [steps[k] * np.arange(round(t0 / steps[k]), round(t1 / steps[k])) for k, t0, t1 in fit.tails]
    analysis = None if fit.fit is None else (fit.fit, pieces if len(pieces) > 1 else pieces[0], times if len(times) > 1 else times[0])
    return RestitutionEstimate.from_dict(with_block(doc, block), analysis=analysis)


def _base_arrays(base, arrays: list, base_units: str | None) -> tuple[list[np.ndarray], str]:
    """The base acceleration of each record of ``arrays`` (:func:`_arrays`) and its units:
    ``base_units``, else the ``units`` of the DataArrays, refused when they disagree or are missing."""
    import pandas as pd
    import xarray as xr

    from rockdec.free import shake

    items = list(base) if len(arrays) > 1 and isinstance(base, list | tuple) else [base]
    if len(items) != len(arrays):
        raise InputError(f"`base` holds {len(items)} record(s) for {len(arrays)} records of `theta`; give one base acceleration per record.")
    out, stated = [], set()
    for item, (angles, step, source) in zip(items, arrays):
        if isinstance(item, records_mod.Record):  # as rockdec.record.records.read_base reads it
            if abs(item.dt - step) > 1e-6 * step:
                raise RecordError(f"the base {item.source} is sampled every {item.dt:g} s, the angle every {step:g} s; "
                                  "resample the base onto the angle's samples.")
            item = item.theta
        if isinstance(item, pd.Series):
            item = xr.DataArray.from_series(item) if not isinstance(item.index, pd.RangeIndex) else item.to_numpy()
        if isinstance(item, xr.DataArray):
            if str(item.attrs.get("units", "")).strip() in ("rad", "radian", "radians", "deg", "degree", "degrees", "mrad"):
                raise InputError(f"`base` ({source}) is labelled an angle (units {item.attrs['units']!r}, as rockdec.read_record labels "
                                 "what it reads); give its values (base.values) with `base_units`.")
            if "units" in item.attrs:
                stated.add(shake.base_units_named(item.attrs["units"]))
            dim = item.dims[-1] if item.ndim else None
            if dim in item.coords and item.sizes[dim] > 1:
                base_step = records_mod.sampling_step(np.asarray(item[dim].values, dtype=np.float64), f"the base of {source}")
                if abs(base_step - step) > 1e-6 * step:
                    raise RecordError(f"the base of {source} is sampled every {base_step:g} s, the angle every {step:g} s; "
                                      "resample the base onto the angle's samples.")
            item = item.values
        values = np.asarray(item)
        if values.dtype.kind not in "fiu" or values.ndim != 1:
            raise InputError(f"`base` ({source}) holds {values.dtype} values of shape {values.shape}; "
                             "give the base acceleration as a 1-D array of numbers, one per angle.")
        out.append(values.astype(np.float64))
    if base_units is None:
        if len(stated) != 1:
            raise InputError("`base_units` is not given and the base states " + (f"several units ({', '.join(sorted(stated))})" if stated else "none")
                             + "; give base_units='m/s2', 'g' or 'rad/s2'.")
        base_units = stated.pop()
    elif stated - {base_units}:
        raise InputError(f"`base_units` {base_units!r} disagrees with the base's units attribute ({', '.join(sorted(stated))}); give one.")
    return out, base_units


def read_record(path, *, variable: str = "theta", column: str = "theta", dt: float | None = None,
                fs: float | None = None) -> xr.DataArray:
    """Read a measured record: CSV or text, ``.npy``, NetCDF or MATLAB ``.mat``.

    Parameters
    ----------
    path : str or path
        ``.csv``/``.txt``: a header with ``time`` and ``column``, or one column of angles
        (then ``dt`` or ``fs``); ``.nc``: ``variable`` as ``(time)`` or ``(record, time)``;
        ``.npy``: a 1-D array (with ``dt`` or ``fs``); ``.mat``: ``variable`` and a time
        vector ``time`` or ``t`` (or ``dt``/``fs``). Angles in rad (a NetCDF ``units`` of
        degrees is converted).
    variable, column : str
        The angle's name in a NetCDF or MATLAB file, and its column in a CSV.
    dt, fs : float, optional
        Sampling step (s) or rate (Hz), for files without a time axis.

    Returns
    -------
    xarray.DataArray
        ``theta(time)``, or ``theta(record, time)`` for several records, in rad, with its
        time coordinate in s and its sampling step as the attribute ``dt``.

    Raises
    ------
    RecordError
        A file that cannot be read as a record; the message names the file and the fix.

    Examples
    --------
    >>> import numpy as np, rockdec
    >>> np.save(tmp / "record.npy", np.sin(np.arange(2000) * 0.1))
    >>> rockdec.read_record(tmp / "record.npy", dt=0.01).sizes["time"]
    2000
    """
    import xarray as xr

    recs = records_mod.read_records(path, column=column, variable=variable, dt=dt, fs=fs, checked=False)
    step = recs[0].dt
    time = xr.DataArray(np.arange(recs[0].theta.size) * step, dims="time", attrs={**RELATIVE_TIME, "long_name": "time"})
    attrs = {"units": "rad", "long_name": "rocking angle", "source": str(path), "dt": step}
    if len(recs) == 1:
        return xr.DataArray(recs[0].theta, dims="time", coords={"time": time}, name="theta", attrs={**attrs, "source": recs[0].source})
    attrs["sources"] = "\n".join(r.source for r in recs)
    return xr.DataArray(np.stack([r.theta for r in recs]), dims=("record", "time"), coords={"time": time}, name="theta", attrs=attrs)


def simulate(e: float, n_points: int, *, seed=0, model: str = "simplified", points_per_cycle: float = 75.0,
             dt: float | None = None, nu: float | None = None, theta_cr: float | None = None, sigma_p: float | None = None,
             burn_in: int | None = None, theta0: float = 0.0, theta_dot0: float = 0.0) -> xr.DataArray:
    """Simulate the rocking angle of a block under white-noise impulses, exactly (eqs. 21-24).

    The simulator of ``rockdec simulate``: between impulses the block flies on the
    closed-form arcs of its model and loses the share ``1 - e`` of its angular velocity at
    each impact (eq. 6); the step is found so that a cycle at the amplitude ``sigma_Y``
    holds ``points_per_cycle`` samples (eq. 5); the burn-in is discarded.

    Parameters
    ----------
    e : float
        Coefficient of restitution, 0 to 1.
    n_points : int
        Samples per series.
    seed : int or sequence of int
        The seed of the series (several: one series each, along ``seed``).
    model : {"simplified", "housner", "auto"}
        Rocking model: eq. 4, Housner's eq. 2, or chosen by the amplitude.
    points_per_cycle : float
        Samples per rocking cycle at ``sigma_Y``, which set the step (unless ``dt``).
    dt : float, optional
        Time step in s.
    nu, theta_cr, sigma_p : float, optional
        Frequency parameter (rad/s), critical angle (rad), std of the velocity impulses
        (rad/s; 0: a free response from ``theta0``); the scenes' defaults otherwise.
    burn_in : int, optional
        Steps discarded before recording (default: 20 energy relaxation times).
    theta0, theta_dot0 : float
        Initial angle (rad) and angular velocity (rad/s).

    Returns
    -------
    xarray.DataArray
        ``theta(time)`` (``theta(seed, time)`` for several seeds) in rad, with CF
        attributes and the run's settings (``e``, ``dt``, ``sigma_y``, ...) as attributes;
        ``time`` in s from the end of the burn-in (``RELATIVE_TIME``, no reference date:
        ``rockdec simulate``'s files give it one, as CF asks of a file).

    Warns
    -----
    SimulationWarning
        Series that overturned (Housner's model), or samples per cycle off the request.

    Examples
    --------
    >>> import rockdec
    >>> theta = rockdec.simulate(0.85, 5_000, seed=3)
    >>> theta.sizes["time"], theta.attrs["e"]
    (5000, 0.85)
    """
    from rockdec.physics import run
    from rockdec.physics.loading import check_seeds

    settings = _simulation_settings(e=e, n_points=n_points, model=model, points_per_cycle=points_per_cycle, dt=dt, nu=nu,
                                    theta_cr=theta_cr, sigma_p=sigma_p, burn_in=burn_in, theta0=theta0, theta_dot0=theta_dot0)
    seeds = check_seeds(seed)
    contract = run.search(**settings, amplitude=abs(theta0))
    ds = contract.dataset(seeds, n_points).load()
    theta = ds["theta"]
    for line in run.simulation_report(theta, contract, step_given=dt is not None):
        warnings.warn(line, SimulationWarning, stacklevel=2)
    theta.attrs = {**ds.attrs, **theta.attrs, "units": "rad", "dt": contract.dt}
    theta["time"].attrs = {**RELATIVE_TIME, "long_name": ds["time"].attrs["long_name"]}
    return theta.isel(seed=0, drop=True) if np.ndim(seed) == 0 else theta


def _simulation_settings(*, e, n_points, model, points_per_cycle, dt, nu, theta_cr, sigma_p, burn_in, theta0, theta_dot0) -> dict:
    """:func:`simulate`'s parameters checked, each refusal naming the parameter, as
    :func:`rockdec.physics.run.search` takes them (its defaults for those not given)."""
    from rockdec.physics import run
    from rockdec.validate import in_range, integer

    if model not in ("simplified", "housner", "auto"):
        raise InputError(f"`model` {show(model)} is not a rocking model; give simplified, housner or auto.")
    integer(n_points, "`n_points`", 2, "give the samples per series, at least 2")
    given = {
        "e": in_range(e, "`e`", 0.0, 1.0, "give the coefficient of restitution, from 0 to 1"),
        "nu": None if nu is None else positive(nu, "`nu`", "give the frequency parameter in rad/s, > 0"),
        "theta_cr": None if theta_cr is None else positive(theta_cr, "`theta_cr`", "give the critical angle in rad, > 0"),
        "sigma_p": None if sigma_p is None else positive(sigma_p, "`sigma_p`", "give the impulses' std in rad/s, >= 0 (0: a free response)",
                                                         allow_zero=True),
        "points_per_cycle": in_range(points_per_cycle, "`points_per_cycle`", 2.0, math.inf, "give more than 2 samples per cycle",
                                     lo_open=True),
        "dt": None if dt is None else positive(dt, "`dt`", "give the time step in s, > 0, or leave it out"),
        "burn_in": None if burn_in is None else integer(burn_in, "`burn_in`", 0, "give the steps to discard, >= 0, or leave it out"),
        "theta0": in_range(theta0, "`theta0`", fix="give the initial angle in rad"),
        "theta_dot0": in_range(theta_dot0, "`theta_dot0`", fix="give the initial angular velocity in rad/s"),
    }
    return {"model": model, **{k: v for k, v in given.items() if v is not None}} | {
        k: run.DEFAULTS[k] for k in ("nu", "theta_cr", "sigma_p") if given[k] is None}


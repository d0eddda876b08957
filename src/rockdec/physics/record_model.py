"""The record model: what makes a record besides the block's ``e`` -- the load and the sensor.

:class:`Load` is the velocity impulses of eqs. 21-24: ``white`` (the paper's), ``lowpass``
(a first-order low-pass filter, its ``corner`` in rocking frequencies ``1/T(sigma_Y)``,
eq. 5; the open question of paper §6), ``spectrum`` (a tabulated one-sided PSD, in rocking
frequencies or Hz, :func:`read_spectrum_table`) or ``base`` (a measured base acceleration,
:func:`read_base_record`, drawn as the spectrum load of its Welch estimate).
:class:`SensorNoise` is white noise on the recorded angle (in ``sigma_Y`` or rad),
:class:`SensorFilter` a low-pass filter after the block (``butterworth`` of order 1-8 or
``rc``, ``causal`` or ``zero_phase``; :meth:`SensorFilter.apply`), and :class:`RecordModel`
the rocking model (eq. 4 or eq. 2), the load, the noise and the filter together: what a
scene or a record's measurement states, what :class:`rockdec.physics.run.Run` carries and
the calibration's cache key names. Each type is frozen, checks itself when built
(:class:`rockdec.validate.InputError`) and is written to and read from flat file attributes
by one pair of functions (:func:`load_attrs`, :func:`load_from_attrs`, :func:`sensor_attrs`,
:func:`sensor_from_attrs`). Imports nothing heavy (the readers import NumPy, SciPy, xarray
when called).

Explanation: docs/explanation/method/simulation.md (§3.1 Loading);
docs/how-to/record-model.md (declaring a load, noise, filter).
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

from rockdec import validate as checks

__all__ = [
    "Load", "NO_NOISE", "PAPER", "POLE_RATE_RANGE", "RecordModel", "SensorFilter", "SensorNoise", "WHITE",
    "carried_attrs", "check_filter_declared_with_model", "declared_load", "load_attrs", "load_from_attrs",
    "parse_load", "parse_sensor_filter", "parse_sensor_noise", "read_base_record", "sensor_attrs",
    "sensor_from_attrs",
]

LOAD_KINDS = ("white", "lowpass", "spectrum")

#: The range of ``2 pi corner / points_per_cycle`` (the low-pass pole's ``-log``) in which the
#: pole ``exp(-rate)`` is a float strictly between 0 and 1 that its ``log`` recovers: above
#: ``-log`` of the smallest normal float the pole underflows to 0 (a white load), below
#: the float spacing at 1 it rounds to 1 (a random walk).
POLE_RATE_RANGE = (2.0**-52, -math.log(2.2250738585072014e-308))
"""The loads a record model can state."""

SCENE_LOAD_KINDS = (*LOAD_KINDS, "base")
"""The loads a scene or a command line can state: ``base`` (a measured base-excitation
record) becomes a ``spectrum`` load when read (:func:`read_base_record`)."""

NOISE_UNITS = ("sigma_y", "rad")
"""Units of the sensor noise's standard deviation: ``sigma_Y`` of the response, or rad."""

SPECTRUM_COLUMNS = {"frequency_rocking": "rocking frequencies 1/T(sigma_Y)", "frequency_hz": "Hz"}
"""Headers of a spectrum table's frequency column and their units (the second column: ``psd``)."""

BASE_MIN_SAMPLES = 256
"""Fewest samples of a base-excitation record: eight Welch segments of 32 samples."""

WELCH_SEGMENTS = 8
"""A base record's Welch estimate averages segments of about ``1/WELCH_SEGMENTS`` of the record
(a power of two, at most :data:`WELCH_MAX_SEGMENT` samples, overlapping by half)."""

WELCH_MAX_SEGMENT = 4096
"""Longest Welch segment of a base record, in samples (the table's rows: half of it)."""


@dataclasses.dataclass(frozen=True)
class Load:
    """The load's spectrum: ``kind`` in :data:`LOAD_KINDS`; ``corner`` (``lowpass`` only) in
    units of the rocking frequency ``1/T(sigma_Y)`` (eq. 5), NaN otherwise; ``frequency``
    (ascending, ``>= 0``, rocking frequencies) and ``psd`` (``>= 0``, relative, not all 0):
    the table of a ``spectrum`` load (at least 2 rows), empty otherwise; ``source``: where
    the table came from (file name and SHA-256), as the files' attributes name it."""

    kind: str = "white"
    corner: float = math.nan
    frequency: tuple = ()
    psd: tuple = ()
    source: str = ""

    def __post_init__(self):
        if self.kind not in LOAD_KINDS:
            raise checks.InputError(
                f"load kind '{self.kind}' is not a load model; use one of {', '.join(LOAD_KINDS)} "
                "(a base-excitation record is read into a spectrum load by rockdec.physics.record_model.read_base_record)"
            )
        if self.kind != "spectrum" and (len(self.frequency) or len(self.psd) or self.source):
            raise checks.InputError(f"a {self.kind} load has no spectrum table (got frequency/psd/source); drop them, or use kind spectrum")
        if self.kind == "white":
            if not math.isnan(float(self.corner)):
                raise checks.InputError(f"a white load has no corner (got corner {self.corner}); drop it, or use kind lowpass")
            object.__setattr__(self, "corner", math.nan)
        elif self.kind == "lowpass":
            if self.corner is None or math.isnan(float(self.corner)):
                raise checks.InputError("a lowpass load needs its corner in rocking frequencies 1/T(sigma_Y); give corner (1.0, say)")
            corner = checks.positive(self.corner, "load corner", "give the corner in rocking frequencies 1/T(sigma_Y), > 0")
            object.__setattr__(self, "corner", float(corner))
        else:
            if not (self.corner is None or math.isnan(float(self.corner))):
                raise checks.InputError(f"a spectrum load has no corner (got corner {self.corner}); drop it, or use kind lowpass")
            object.__setattr__(self, "corner", math.nan)
            frequency, psd = _checked_table(self.frequency, self.psd, self.source or "the load spectrum")
            object.__setattr__(self, "frequency", frequency)
            object.__setattr__(self, "psd", psd)
            object.__setattr__(self, "source", str(self.source))

    def pole(self, points_per_cycle: float) -> float:
        """Pole ``c`` of the load filter (:func:`rockdec.physics.loading.draw_impulses`) at
        ``points_per_cycle`` samples per rocking cycle: ``exp(-2 pi corner / points_per_cycle)``,
        0 for white noise, NaN for a spectrum load, which has none (the simulators refuse a NaN
        pole; :meth:`draw_options` draws any load)."""
        if self.kind == "white":
            return 0.0
        if self.kind == "spectrum":
            return math.nan
        checks.positive(points_per_cycle, "points_per_cycle", "a low-pass load needs the samples per cycle that place its corner")
        rate = 2.0 * math.pi * self.corner / points_per_cycle
        pole = math.exp(-rate) if rate < POLE_RATE_RANGE[1] else 0.0
        if not (POLE_RATE_RANGE[0] <= rate < POLE_RATE_RANGE[1]):
            n = f"{points_per_cycle:.4g}"
            lo, hi = (r * points_per_cycle / (2.0 * math.pi) for r in POLE_RATE_RANGE)
            what = (
                "0: the load is white at this sampling; give `load` white, or a corner below " if pole == 0.0 or rate >= POLE_RATE_RANGE[1]
                else "1 to the last digit: a load that never becomes stationary; give a corner above "
            )
            raise checks.InputError(
                f"`load` lowpass:{self.corner:g} at {n} samples per rocking cycle puts its filter's pole "
                f"exp(-2 pi corner / {n}) at {what}{hi if 'below' in what else lo:.3g} rocking frequencies"
            )
        return float(pole)

    def draw_options(self, points_per_cycle: float) -> dict:
        """The load as the simulators' keyword arguments at ``points_per_cycle`` samples per
        rocking cycle: ``{"pole": c}`` (white: 0, lowpass: :meth:`pole`) or ``{"spectrum": ...}``
        (:class:`rockdec.physics.loading.ImpulseSpectrum`, the table's frequencies divided by
        ``points_per_cycle``: cycles per step)."""
        if self.kind != "spectrum":
            return {"pole": self.pole(points_per_cycle)}
        from rockdec.physics.loading import ImpulseSpectrum

        n = checks.positive(points_per_cycle, "points_per_cycle", "a spectrum load needs the samples per cycle that place its table")
        return {"spectrum": ImpulseSpectrum(tuple(f / n for f in self.frequency), self.psd)}

    def describe(self) -> str:
        """The load in words, as the files' ``load`` attribute and the tables state it."""
        if self.kind == "white":
            return "white"
        if self.kind == "lowpass":
            return f"low-pass, corner {self.corner:g} x rocking frequency"
        text = f"spectrum of {len(self.frequency)} rows, {self.frequency[0]:g} to {self.frequency[-1]:g} x rocking frequency"
        return text + (f", from {self.source}" if self.source else "")

    def to_dict(self) -> dict:
        """The load as a scene states it (``corner`` only for ``lowpass``, the table for ``spectrum``)."""
        if self.kind == "white":
            return {"kind": self.kind}
        if self.kind == "lowpass":
            return {"kind": self.kind, "corner": self.corner}
        return {"kind": self.kind, "frequency": list(self.frequency), "psd": list(self.psd), "source": self.source}

    @classmethod
    def from_dict(cls, d: dict | None) -> "Load":
        """The load of a scene's ``excitation.load`` (``None``: white); ``corner: null`` is no corner.

        ``spectrum`` takes its table inline (``frequency`` in rocking frequencies, ``psd``) or
        from ``file`` (:func:`read_spectrum_table`; a table in Hz needs ``rocking_frequency``,
        Hz); ``base`` reads ``file`` (:func:`read_base_record`) placed at ``rocking_frequency``.
        """
        d = dict(d or {})
        kind = d.get("kind", "white")
        if d.get("rocking_frequency") is not None and d.get("file") is None:
            raise checks.InputError("rocking_frequency places a file's table in Hz against the rocking frequency; give file, or drop rocking_frequency")
        if d.get("file") is not None:
            if kind not in ("spectrum", "base"):
                raise checks.InputError(f"a {kind} load reads no file (got file {d['file']!r}); drop it, or use kind spectrum or base")
            if len(d.get("frequency") or ()) or len(d.get("psd") or ()):
                raise checks.InputError("a spectrum load takes its table inline (frequency, psd) or from file, not both; drop one")
            reader = read_base_record if kind == "base" else read_spectrum_table
            return reader(d["file"], d.get("rocking_frequency"))
        if kind == "base":
            raise checks.InputError("a base load is read from its record: give file (CSV time,acceleration or NetCDF) and rocking_frequency in Hz")
        corner = d.get("corner")
        return cls(
            kind=kind, corner=math.nan if corner is None else corner, frequency=tuple(d.get("frequency") or ()),
            psd=tuple(d.get("psd") or ()), source=d.get("source") or "",
        )


def _checked_table(frequency, psd, source: str) -> tuple[tuple, tuple]:
    """``frequency`` and ``psd`` of a spectrum table as tuples of floats, or one sentence
    naming the bad row of ``source`` (too few rows, a non-number or NaN, a negative or
    non-increasing frequency, a negative PSD, no power at all)."""
    frequency, psd = tuple(frequency), tuple(psd)
    if len(frequency) != len(psd):
        raise checks.InputError(f"{source}: {len(frequency)} frequencies but {len(psd)} PSD values; give one PSD value per frequency")
    if len(frequency) < 2:
        raise checks.InputError(f"{source}: {len(frequency)} row(s); a spectrum table needs at least 2 rows (frequency, psd)")
    rows = []
    for name, column in (("frequency", frequency), ("psd", psd)):
        values = []
        for i, value in enumerate(column):
            if not checks.is_finite_number(value):
                raise checks.InputError(f"{source}: row {i + 1} has {name} {checks.show(value)}, not a finite number; fix or drop that row")
            if value < 0:
                raise checks.InputError(f"{source}: row {i + 1} has {name} {value:g} < 0; a {name} is >= 0")
            values.append(float(value))
        rows.append(tuple(values))
    frequency, psd = rows
    for i in range(1, len(frequency)):
        if not frequency[i] > frequency[i - 1]:
            raise checks.InputError(
                f"{source}: the frequency of row {i + 1} ({frequency[i]:g}) does not increase from row {i} ({frequency[i - 1]:g}); "
                "sort the table and drop repeated frequencies"
            )
    if not any(p > 0 for p in psd):
        raise checks.InputError(f"{source}: every PSD value is 0, so the load has no power; give the spectrum's shape")
    return frequency, psd


def _file(path, what: str) -> Path:
    """``path`` of a user's file, or one sentence: missing, a folder, empty."""
    path = checks.path_name(path, what)
    if not path.is_file():
        raise checks.InputError(f"{path}: no such {what} file; check the path")
    if path.stat().st_size == 0:
        raise checks.InputError(f"{path}: the {what} file is empty")
    return path


def _source(path: Path, what: str) -> str:
    """``what`` and ``path``'s name and SHA-256 (its first 16 hex digits), as the load's ``source``."""
    from rockdec.io import sha256

    return f"{what} {path.name} (sha256 {sha256(path)[:16]})"


def _read_csv_columns(path: Path, what: str) -> tuple[list[str], list[list[float]]]:
    """The header and the numeric columns of a small CSV (``,``, ``;``, tab or spaces between
    cells; ``#`` lines are comments), or one sentence naming the first bad cell."""
    lines = [(n + 1, line.strip()) for n, line in enumerate(path.read_text(errors="replace").splitlines())]
    lines = [(n, line) for n, line in lines if line and not line.startswith("#")]
    if not lines:
        raise checks.InputError(f"{path}: the {what} file holds no rows")

    def cells(line):
        for sep in (",", ";", "\t"):
            if sep in line:
                return [c.strip() for c in line.split(sep)]
        return line.split()

    header = [c.lower() for c in cells(lines[0][1])]
    columns: list[list[float]] = [[] for _ in header]
    for n, line in lines[1:]:
        row = cells(line)
        if len(row) != len(header):
            raise checks.InputError(f"{path}: line {n} has {len(row)} cells, the header {len(header)}; give one value per column")
        for column, cell in zip(columns, row):
            try:
                column.append(float(cell))
            except ValueError:
                raise checks.InputError(f"{path}: line {n} holds {cell!r}, not a number; fix that cell") from None
    return header, columns


def read_spectrum_table(path, rocking_frequency: float | None = None) -> Load:
    """The spectrum load of a CSV table: header ``frequency_rocking,psd`` (rocking frequencies
    ``1/T(sigma_Y)``) or ``frequency_hz,psd`` (Hz: placed at ``rocking_frequency`` Hz, the
    record's ``1/(dt N_cycle)``), one row per frequency; bad files refused in one sentence."""
    path = _file(path, "load spectrum")
    header, columns = _read_csv_columns(path, "load spectrum")
    if len(header) != 2 or header[0] not in SPECTRUM_COLUMNS or header[1] != "psd":
        raise checks.InputError(
            f"{path}: the header is {','.join(header)!r}; a load spectrum is two columns headed "
            + " or ".join(f"{name},psd ({units})" for name, units in SPECTRUM_COLUMNS.items())
        )
    frequency, psd = _checked_table(*columns, str(path))  # refusals name the file's path
    if header[0] == "frequency_hz":
        f_rock = _rocking_frequency(rocking_frequency, f"{path}: a table in Hz")
        frequency = [f / f_rock for f in frequency]
    return Load("spectrum", frequency=tuple(frequency), psd=tuple(psd), source=_source(path, "load spectrum"))


def _rocking_frequency(value, what: str) -> float:
    if value is None:
        raise checks.InputError(
            f"{what} is placed against the rocking frequency 1/T(sigma_Y) in Hz of the record it goes with; "
            "give rocking_frequency (Hz) in a scene, or the record's dt and samples per cycle"
        )
    return checks.positive(value, "rocking_frequency", "give the rocking frequency 1/T(sigma_Y) in Hz, > 0")


def _read_base(path: Path) -> tuple[list[float], float]:
    """Base acceleration and its step (s) of a CSV ``time,acceleration`` or a NetCDF
    variable ``acceleration(time)`` (times in its units, s by default)."""
    from rockdec.timeaxis import sampling_step

    if path.suffix.lower() in (".nc", ".nc4", ".netcdf"):
        import xarray as xr

        from rockdec.timeaxis import time_factor

        try:
            ds = xr.open_dataset(path, decode_times=False, decode_timedelta=False)
        except (OSError, ValueError) as exc:
            raise checks.InputError(f"{path}: not a readable NetCDF file ({exc})") from None
        with ds:
            if "acceleration" not in ds or ds["acceleration"].ndim != 1 or ds["acceleration"].dims[0] not in ds.coords:
                raise checks.InputError(f"{path}: no variable acceleration(time) with a time coordinate; store the base acceleration so")
            var = ds["acceleration"]
            coord = ds[var.dims[0]]
            step = sampling_step(coord.values, str(path), BASE_MIN_SAMPLES) * time_factor(coord.attrs.get("units"), str(path), var.dims[0])
            return [float(a) for a in var.values], step
    header, columns = _read_csv_columns(path, "base-excitation record")
    if "time" not in header or "acceleration" not in header:
        raise checks.InputError(f"{path}: the header is {','.join(header)!r}; a base-excitation record has the columns time,acceleration")
    return columns[header.index("acceleration")], sampling_step(columns[header.index("time")], str(path), BASE_MIN_SAMPLES)


def read_base_record(path, rocking_frequency: float | None = None) -> Load:
    """The spectrum load of a measured base-acceleration record (module docstring): its Welch
    estimate (:data:`WELCH_SEGMENTS`, Hann windows, mean removed, the constant bin dropped),
    its frequencies divided by ``rocking_frequency`` (Hz, the rocking record's
    ``1/(dt N_cycle)``). Refuses in one sentence a missing or unreadable file, a non-numeric or
    NaN sample, a time axis that is not uniform, fewer than :data:`BASE_MIN_SAMPLES` samples."""
    path = _file(path, "base-excitation record")
    f_rock = _rocking_frequency(rocking_frequency, f"{path}: a base-excitation record")
    accel, dt = _read_base(path)
    if len(accel) < BASE_MIN_SAMPLES:
        raise checks.InputError(f"{path}: {len(accel)} samples; a base-excitation record needs at least {BASE_MIN_SAMPLES} for its spectrum")
    bad = next((i for i, a in enumerate(accel) if not math.isfinite(a)), None)
    if bad is not None:
        raise checks.InputError(f"{path}: sample {bad} of the acceleration is {accel[bad]}; give a record without gaps (cut it at the gap)")
    import numpy as np
    from scipy.signal import welch

    segment = min(WELCH_MAX_SEGMENT, 2 ** int(math.log2(len(accel) / WELCH_SEGMENTS)))
    frequency, psd = welch(np.asarray(accel), fs=1.0 / dt, nperseg=segment, detrend="constant")
    source = _source(path, "base record") + f", Welch estimate, segments of {segment} samples at {dt:g} s"
    return Load("spectrum", frequency=tuple(frequency[1:] / f_rock), psd=tuple(float(p) for p in psd[1:]), source=source)


WHITE = Load()
"""The paper's load."""


LOAD_FORMS = "white, lowpass:CORNER, spectrum:FILE or base:FILE"
"""The forms of a load on the command line (:func:`parse_load`)."""


def parse_load(text: str, *, dt: float | None = None, points_per_cycle: float | None = None) -> Load:
    """The load of a command-line string: ``white``, ``lowpass:CORNER`` (corner in rocking
    frequencies ``1/T(sigma_Y)``, eq. 5), ``spectrum:FILE`` (a tabulated load spectrum,
    :func:`read_spectrum_table`) or ``base:FILE`` (a measured base-excitation record,
    :func:`read_base_record`); anything else is refused in one sentence. ``dt`` (s) and
    ``points_per_cycle`` of the rocking record place a table in Hz and a base record against its
    rocking frequency ``1/(dt points_per_cycle)``."""
    kind, sep, arg = str(text).strip().partition(":")
    kind, arg = kind.strip().lower(), arg.strip()
    if kind == "white" and not sep:
        return WHITE
    if kind == "lowpass" and arg:
        try:
            corner = float(arg)
        except ValueError:
            raise checks.InputError(f"`load` {text!r}: the corner '{arg}' is not a number; give lowpass:CORNER with CORNER in rocking frequencies, > 0") from None
        return Load("lowpass", corner)
    if kind in ("spectrum", "base") and arg:
        f_rock = None
        if dt is not None and points_per_cycle is not None:
            f_rock = 1.0 / (checks.positive(dt, "dt") * checks.positive(points_per_cycle, "points_per_cycle"))
        return (read_base_record if kind == "base" else read_spectrum_table)(arg, f_rock)
    raise checks.InputError(f"`load` {text!r} is not a load; give one of {LOAD_FORMS}")


@dataclasses.dataclass(frozen=True)
class SensorNoise:
    """White noise of the angle sensor: ``std`` (``>= 0``) in ``units`` (:data:`NOISE_UNITS`)."""

    std: float = 0.0
    units: str = "sigma_y"

    def __post_init__(self):
        if self.units not in NOISE_UNITS:
            raise checks.InputError(f"sensor noise units '{self.units}' are not known; use one of {', '.join(NOISE_UNITS)}")
        std = checks.positive(self.std, "sensor noise std", "give the sensor noise's standard deviation, >= 0", allow_zero=True)
        object.__setattr__(self, "std", float(std))

    def std_rad(self, sigma_y: float) -> float:
        """The standard deviation in rad for a response of standard deviation ``sigma_y`` (rad)."""
        return self.std * sigma_y if self.units == "sigma_y" else self.std

    def to_dict(self) -> dict:
        return {"std": self.std, "units": self.units}

    @classmethod
    def from_dict(cls, d: dict | None) -> "SensorNoise":
        """The noise of a scene's ``excitation.sensor_noise`` (``None``: none)."""
        d = dict(d or {})
        return cls(std=d.get("std", 0.0), units=d.get("units", "sigma_y"))


NO_NOISE = SensorNoise()
"""A perfect sensor."""


FILTER_KINDS = ("butterworth", "rc")
"""The filters after the block a record model can state (:class:`SensorFilter`)."""

FILTER_UNITS = ("rocking", "hz")
"""Units of a sensor filter's corner: rocking frequencies ``1/T(sigma_Y)`` (eq. 5), or Hz."""

BUTTERWORTH_ORDERS = (1, 8)
"""Lowest and highest order of a Butterworth sensor filter."""

FILTER_FORMS = "none, auto, butterworth:ORDER:CORNER:PHASE or rc:CORNER:PHASE (CORNER in rocking frequencies, or Hz as 12hz; PHASE zero-phase or causal)"
"""The forms of a sensor filter on the command line (:func:`parse_sensor_filter`)."""


@dataclasses.dataclass(frozen=True)
class SensorFilter:
    """A low-pass filter between the block and the record: ``kind`` in :data:`FILTER_KINDS`
    (``rc``: a first-order resistor-capacitor stage, ``order`` 1), ``order``
    (:data:`BUTTERWORTH_ORDERS`), ``corner`` (``> 0``, its -3 dB frequency in ``units``,
    :data:`FILTER_UNITS`) and ``zero_phase`` (run forward and back, so its gain is squared
    and its delay 0; else causal, run forward as an instrument runs it).

    Examples
    --------
    >>> SensorFilter("butterworth", 4, 10.0, zero_phase=True).describe()
    'zero-phase Butterworth of order 4, corner 10 x rocking frequency'
    """

    kind: str = "butterworth"
    order: int = 4
    corner: float = math.nan
    zero_phase: bool = False
    units: str = "rocking"

    def __post_init__(self):
        if self.kind not in FILTER_KINDS:
            raise checks.InputError(f"sensor filter kind '{self.kind}' is not known; use one of {', '.join(FILTER_KINDS)}")
        if self.units not in FILTER_UNITS:
            raise checks.InputError(f"sensor filter units '{self.units}' are not known; use one of {', '.join(FILTER_UNITS)}")
        lo, hi = BUTTERWORTH_ORDERS if self.kind == "butterworth" else (1, 1)
        if isinstance(self.order, bool) or not checks.is_finite_number(self.order) or int(self.order) != self.order or not lo <= self.order <= hi:
            orders = f"an integer from {lo} to {hi}" if hi > lo else "1"
            raise checks.InputError(f"a {self.kind} sensor filter of order {checks.show(self.order)} is not one; give order {orders}")
        if not isinstance(self.zero_phase, bool):
            raise checks.InputError(f"sensor filter zero_phase {self.zero_phase!r} is not True or False")
        corner = checks.positive(self.corner, "sensor filter corner", "give the filter's corner (-3 dB) in rocking frequencies or Hz, > 0")
        object.__setattr__(self, "order", int(self.order))
        object.__setattr__(self, "corner", float(corner))

    def in_rocking(self, rocking_frequency: float | None) -> "SensorFilter":
        """The filter with its corner in rocking frequencies: a corner in Hz divided by the
        record's ``rocking_frequency`` ``1/(dt N_cycle)`` (Hz); one in rocking frequencies as it is."""
        if self.units == "rocking":
            return self
        f_rock = _rocking_frequency(rocking_frequency, f"a sensor filter corner of {self.corner:g} Hz")
        return dataclasses.replace(self, corner=self.corner / f_rock, units="rocking")

    def cycles_per_sample(self, points_per_cycle: float) -> float:
        """The corner in cycles per sample at ``points_per_cycle`` samples per rocking cycle
        (a corner in rocking frequencies); refused in one sentence at or above the Nyquist
        frequency, 0.5."""
        if self.units != "rocking":
            raise ValueError("a sensor filter is placed on the samples with its corner in rocking frequencies (in_rocking)")
        n = checks.positive(points_per_cycle, "points_per_cycle", "a sensor filter needs the samples per cycle that place its corner")
        rate = self.corner / n
        if not rate < 0.5:
            raise checks.InputError(
                f"`sensor_filter` corner {self.corner:.4g} x rocking frequency at {n:.4g} samples per rocking cycle lies at or above "
                f"the Nyquist frequency ({n / 2.0:.4g} x rocking frequency), where a filter leaves the record as it is; give a lower "
                "corner, or `sensor_filter` none"
            )
        return rate

    def apply(self, theta, points_per_cycle: float):
        """``theta`` (last axis: time) through the filter at ``points_per_cycle`` samples per
        rocking cycle: a Butterworth of :func:`scipy.signal.butter` (second-order sections,
        :func:`scipy.signal.sosfilt`, or :func:`scipy.signal.sosfiltfilt` zero-phase), an RC
        stage ``y[k] = a y[k-1] + (1 - a) x[k]`` with ``a = exp(-2 pi f_c dt)`` (the exact
        sampled response of the analog stage, :func:`scipy.signal.lfilter`, or
        :func:`scipy.signal.filtfilt` zero-phase). A new array.

        Examples
        --------
        >>> import numpy as np
        >>> step = SensorFilter("rc", 1, 1.0).apply(np.ones(400), 100.0)
        >>> round(float(step[-1]), 6)
        1.0
        """
        from scipy import signal

        rate = self.cycles_per_sample(points_per_cycle)
        if self.kind == "rc":
            a = math.exp(-2.0 * math.pi * rate)
            b, den = [1.0 - a], [1.0, -a]
            return signal.filtfilt(b, den, theta, axis=-1) if self.zero_phase else signal.lfilter(b, den, theta, axis=-1)
        sos = signal.butter(self.order, 2.0 * rate, output="sos")
        return signal.sosfiltfilt(sos, theta, axis=-1) if self.zero_phase else signal.sosfilt(sos, theta, axis=-1)

    def describe(self) -> str:
        """The filter in words, as the report states it."""
        phase = "zero-phase" if self.zero_phase else "causal"
        what = f"Butterworth of order {self.order}" if self.kind == "butterworth" else "RC (first order)"
        where = "x rocking frequency" if self.units == "rocking" else "Hz"
        return f"{phase} {what}, corner {self.corner:g} {where}"

    def text(self) -> str:
        """The filter in the form :func:`parse_sensor_filter` reads."""
        corner = f"{self.corner:g}" + ("hz" if self.units == "hz" else "")
        phase = "zero-phase" if self.zero_phase else "causal"
        return f"butterworth:{self.order}:{corner}:{phase}" if self.kind == "butterworth" else f"rc:{corner}:{phase}"

    def to_dict(self) -> dict:
        return {"kind": self.kind, "order": self.order, "corner": self.corner, "zero_phase": self.zero_phase, "units": self.units}

    @classmethod
    def from_dict(cls, d: dict | None) -> "SensorFilter | None":
        """The filter of :meth:`to_dict` (``None``: no filter)."""
        if not d:
            return None
        return cls(d.get("kind", "butterworth"), d.get("order", 1), d.get("corner", math.nan), d.get("zero_phase", False), d.get("units", "rocking"))


def parse_sensor_filter(value) -> SensorFilter | str | None:
    """A declared ``sensor_filter``: ``"auto"`` (the record is checked for one, and declined
    when it shows one, :func:`rockdec.record.record_measure.rolloff`), ``None`` or ``"none"``
    (no filter: the record is taken as unfiltered, unchecked), a :class:`SensorFilter`, or a
    text ``butterworth:ORDER:CORNER:PHASE`` or ``rc:CORNER:PHASE`` with CORNER in rocking
    frequencies ``1/T(sigma_Y)`` (eq. 5), or in Hz with the suffix ``hz``, and PHASE
    ``zero-phase`` or ``causal``; anything else is refused in one sentence.

    Examples
    --------
    >>> parse_sensor_filter("butterworth:4:10:zero-phase")
    SensorFilter(kind='butterworth', order=4, corner=10.0, zero_phase=True, units='rocking')
    >>> parse_sensor_filter("rc:12.5Hz:causal").text()
    'rc:12.5hz:causal'
    >>> parse_sensor_filter("none") is None, parse_sensor_filter("auto")
    (True, 'auto')
    """
    if value is None or isinstance(value, SensorFilter):
        return value
    text = str(value).strip().lower()
    if text in ("none", "auto"):
        return None if text == "none" else "auto"
    parts = [p.strip() for p in text.split(":")]
    kind = parts[0]
    wanted = {"butterworth": 4, "rc": 3}.get(kind)
    if wanted is None or len(parts) != wanted:
        raise checks.InputError(f"`sensor_filter` {value!r} is not a filter; give {FILTER_FORMS}")
    if parts[-1] not in ("zero-phase", "causal"):
        raise checks.InputError(
            f"`sensor_filter` {value!r}: the phase '{parts[-1]}' is not known; end it with zero-phase (run forward and back, "
            "as filtfilt does) or causal (run forward, as an instrument does)"
        )
    corner_text = parts[-2]
    units = "hz" if corner_text.endswith("hz") else "rocking"
    corner_text = corner_text.removesuffix("hz").strip()
    try:
        corner = float(corner_text)
        order = float(parts[1]) if kind == "butterworth" else 1
    except ValueError:
        raise checks.InputError(f"`sensor_filter` {value!r}: the order and the corner must be numbers; give {FILTER_FORMS}") from None
    if not (math.isfinite(corner) and corner > 0.0):
        raise checks.InputError(f"`sensor_filter` {value!r}: the corner {corner_text} is not a frequency; give it > 0 (rocking frequencies, or Hz as 12hz)")
    return SensorFilter(kind, order, corner, parts[-1] == "zero-phase", units)


def check_filter_declared_with_model(sensor_filter, load, sensor) -> None:
    """Refuse a declared ``sensor_filter`` (a :class:`SensorFilter`) while ``load`` or ``sensor``
    is left to measure (``None``): the filter smooths what the load's colour and the sensor
    noise are measured from, so all three are declared together.

    Raises
    ------
    rockdec.validate.InputError
        In one sentence naming the declarations that would help.

    Examples
    --------
    >>> check_filter_declared_with_model(parse_sensor_filter("rc:5:causal"), Load(), SensorNoise())  # all declared: fine
    >>> check_filter_declared_with_model("auto", None, None)  # no filter declared: fine
    """
    if isinstance(sensor_filter, SensorFilter) and (load is None or sensor is None):
        raise checks.InputError(
            "a declared `sensor_filter` smooths what the load's colour and the sensor noise are measured from; declare "
            "`load` and `sensor_noise` beside it (`load` white with `sensor_noise` 0 is the paper's model)."
        )


ROCKING_MODELS = ("simplified", "housner")
"""The rocking models a record model states (eq. 4, eq. 2)."""


@dataclasses.dataclass(frozen=True)
class RecordModel:
    """The rocking model (:data:`ROCKING_MODELS`), the load, the sensor noise and the sensor
    filter (:class:`SensorFilter`, ``None``: none) of a record."""

    rocking: str = "simplified"
    load: Load = WHITE
    sensor: SensorNoise = NO_NOISE
    filter: SensorFilter | None = None

    def __post_init__(self):
        if self.rocking not in ROCKING_MODELS:
            raise checks.InputError(f"rocking model '{self.rocking}' is not known; use one of {', '.join(ROCKING_MODELS)}")
        if self.filter is not None and not isinstance(self.filter, SensorFilter):
            raise checks.InputError(f"sensor filter {self.filter!r} is not a SensorFilter; give one, or None")

    def to_attrs(self) -> dict:
        """Flat file attributes (numbers, strings, lists of numbers): ``rocking_model``, the load's
        (:func:`load_attrs`), ``sensor_noise``, ``sensor_noise_units`` and, with a filter,
        ``sensor_filter`` (its text, :meth:`SensorFilter.text`)."""
        out = {"rocking_model": self.rocking, **load_attrs(self.load), **sensor_attrs(self.sensor)}
        return out if self.filter is None else {**out, "sensor_filter": self.filter.text()}

    @classmethod
    def from_attrs(cls, attrs) -> "RecordModel":
        """The record model of attributes written by :meth:`to_attrs` (missing ones: the paper's)."""
        found = parse_sensor_filter(attrs["sensor_filter"]) if "sensor_filter" in attrs else None
        return cls(rocking=str(attrs.get("rocking_model", "simplified")), load=load_from_attrs(attrs), sensor=sensor_from_attrs(attrs),
                   filter=found if isinstance(found, SensorFilter) else None)

    def key(self) -> dict:
        """The model as a JSON-able dict (a calibration's cache key names it; a filter only
        when there is one); :meth:`from_key` reads it."""
        out = {"rocking": self.rocking, "load": self.load.to_dict(), "sensor_noise": self.sensor.to_dict()}
        return out if self.filter is None else {**out, "sensor_filter": self.filter.to_dict()}

    @classmethod
    def from_key(cls, key: dict) -> "RecordModel":
        """The record model of :meth:`key`."""
        return cls(key["rocking"], Load.from_dict(key["load"]), SensorNoise.from_dict(key["sensor_noise"]), SensorFilter.from_dict(key.get("sensor_filter")))


PAPER = RecordModel()
"""The paper's record model: simplified rocking, white load, no sensor noise, no sensor filter."""


LOAD_ATTRS = ("load", "load_corner", "load_frequency", "load_psd", "load_source")
"""The attributes that name a load (:func:`load_attrs`; the last three for a spectrum only)."""


def declared_load(value):
    """A declared ``load`` as the estimate's stages take it: ``None`` for ``"auto"`` (measured
    off the record), a :class:`Load` as given, or a text checked by :func:`parse_load` (a file
    at a stand-in rocking frequency) -- a spectrum's text kept, for the estimate to place
    against the record's rocking frequency, any other its :class:`Load`.

    Examples
    --------
    >>> declared_load("auto") is None, declared_load("lowpass:3").corner
    (True, 3.0)
    """
    if not isinstance(value, str):
        return value
    if value.strip().lower() == "auto":
        return None
    load = parse_load(value, dt=1.0, points_per_cycle=1.0)
    return value if load.kind == "spectrum" else load


def parse_sensor_noise(value) -> SensorNoise | None:
    """A declared ``sensor_noise``: ``None`` for ``"auto"`` (measured off the record), a
    :class:`SensorNoise` as given, a number (its standard deviation in rad) or ``"N%"`` (per
    cent of ``sigma_Y``); anything else is refused in one sentence.

    Examples
    --------
    >>> parse_sensor_noise("2%")
    SensorNoise(std=0.02, units='sigma_y')
    """
    if isinstance(value, SensorNoise):
        return value
    word = str(value).strip().lower()
    if word == "auto":
        return None
    percent = word.endswith("%")
    try:
        number = float(word[:-1] if percent else word)
    except ValueError:
        number = math.nan
    if not (number >= 0.0 and number < math.inf):
        raise checks.InputError(
            f"`sensor_noise` {value!r} is not a noise level; give auto (measured), 0, a standard deviation in rad "
            "(0.0002) or a share of sigma_Y (2%), >= 0."
        )
    return SensorNoise(number / 100.0, "sigma_y") if percent else SensorNoise(number, "rad")


def load_attrs(load: Load) -> dict:
    """The load as flat attributes: ``load`` (its kind) and ``load_corner`` (NaN but for
    lowpass); a spectrum adds its table as two lists of floats, ``load_frequency`` (rocking
    frequencies) and ``load_psd``, and ``load_source``."""
    out = {"load": load.kind, "load_corner": float(load.corner)}
    if load.kind == "spectrum":
        out.update(load_frequency=list(load.frequency), load_psd=list(load.psd), load_source=load.source)
    return out


def load_from_attrs(attrs) -> Load:
    """The load of attributes written by :func:`load_attrs` (none: white)."""
    kind = str(attrs.get("load", "white"))
    if kind == "white":
        return Load(kind)
    if kind == "spectrum":
        table = {name: tuple(float(x) for x in attrs[f"load_{name}"]) for name in ("frequency", "psd")}
        return Load(kind, **table, source=str(attrs.get("load_source", "")))
    return Load(kind, float(attrs["load_corner"]))


def sensor_attrs(sensor: SensorNoise) -> dict:
    """The sensor noise as flat attributes: ``sensor_noise`` (std) and ``sensor_noise_units``."""
    return {"sensor_noise": sensor.std, "sensor_noise_units": sensor.units}


def carried_attrs(attrs) -> dict:
    """The load and sensor attributes (:func:`load_attrs`, :func:`sensor_attrs`, ``sensor_filter``) among ``attrs``:
    what a product derived from a file of a run carries on, so every product names its load."""
    keys = (*LOAD_ATTRS, *sensor_attrs(NO_NOISE), "sensor_filter")
    return {key: attrs[key] for key in keys if key in attrs}


def sensor_from_attrs(attrs) -> SensorNoise:
    """The sensor noise of attributes written by :func:`sensor_attrs` (none: no noise)."""
    return SensorNoise(float(attrs.get("sensor_noise", 0.0)), str(attrs.get("sensor_noise_units", "sigma_y")))

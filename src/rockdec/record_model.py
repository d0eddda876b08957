"""The record model: what makes a record besides the block's ``e`` -- the load and the sensor.

:class:`Load`
    the velocity impulses of eqs. 21-24: ``white`` (independent, the paper's load), or
    ``lowpass`` (white impulses through a first-order low-pass filter,
    :func:`rockdec.loading.draw_impulses`) with its ``corner`` in units of the rocking
    frequency ``1/T(sigma_Y)`` (eq. 5), the open question of paper §6.
:class:`SensorNoise`
    white noise added to the recorded angle, its standard deviation in units of
    ``sigma_Y`` (``units="sigma_y"``) or in rad (``units="rad"``).
:class:`RecordModel`
    the rocking model (``simplified``, eq. 4, or ``housner``, eq. 2, whose geometry
    ``nu``, ``theta_cr`` the run holds), the load and the sensor noise together: what a
    scene (``excitation.load``, ``excitation.sensor_noise``) or a measurement of a record
    states, what :class:`rockdec.run.Run` carries and the calibration's cache key names.

An arbitrary load spectrum and a measured base-excitation record are not models yet: the
scene schema refuses any other ``kind``.

Each type is frozen, checks itself when built (:class:`rockdec.validate.InputError`, one
sentence) and is written to and read from flat file attributes by one pair of functions.
Imports nothing heavy.
"""

from __future__ import annotations

import dataclasses
import math

from rockdec import validate as checks

LOAD_KINDS = ("white", "lowpass")
"""The loads a record model can state."""

NOISE_UNITS = ("sigma_y", "rad")
"""Units of the sensor noise's standard deviation: ``sigma_Y`` of the response, or rad."""


@dataclasses.dataclass(frozen=True)
class Load:
    """The load's spectrum: ``kind`` in :data:`LOAD_KINDS`; ``corner`` (``lowpass`` only) in
    units of the rocking frequency ``1/T(sigma_Y)`` (eq. 5), NaN for white noise."""

    kind: str = "white"
    corner: float = math.nan

    def __post_init__(self):
        if self.kind not in LOAD_KINDS:
            raise checks.InputError(
                f"load kind '{self.kind}' is not a load model; use one of {', '.join(LOAD_KINDS)} "
                "(an arbitrary spectrum and a measured base excitation are not supported)"
            )
        if self.kind == "white":
            if not math.isnan(float(self.corner)):
                raise checks.InputError(f"a white load has no corner (got corner {self.corner}); drop it, or use kind lowpass")
            object.__setattr__(self, "corner", math.nan)
        else:
            if self.corner is None or math.isnan(float(self.corner)):
                raise checks.InputError("a lowpass load needs its corner in rocking frequencies 1/T(sigma_Y); give corner (1.0, say)")
            corner = checks.positive(self.corner, "load corner", "give the corner in rocking frequencies 1/T(sigma_Y), > 0")
            object.__setattr__(self, "corner", float(corner))

    def pole(self, points_per_cycle: float) -> float:
        """Pole ``c`` of the load filter (:func:`rockdec.loading.draw_impulses`) at
        ``points_per_cycle`` samples per rocking cycle: ``exp(-2 pi corner / points_per_cycle)``,
        0 for white noise."""
        if self.kind == "white":
            return 0.0
        checks.positive(points_per_cycle, "points_per_cycle", "a low-pass load needs the samples per cycle that place its corner")
        return float(math.exp(-2.0 * math.pi * self.corner / points_per_cycle))

    def describe(self) -> str:
        """The load in words, as the files' ``load`` attribute and the tables state it."""
        return "white" if self.kind == "white" else f"low-pass, corner {self.corner:g} x rocking frequency"

    def to_dict(self) -> dict:
        """The load as a scene states it (``corner`` only for ``lowpass``)."""
        return {"kind": self.kind} if self.kind == "white" else {"kind": self.kind, "corner": self.corner}

    @classmethod
    def from_dict(cls, d: dict | None) -> "Load":
        """The load of a scene's ``excitation.load`` (``None``: white); ``corner: null`` is no corner."""
        d = dict(d or {})
        corner = d.get("corner")
        return cls(kind=d.get("kind", "white"), corner=math.nan if corner is None else corner)


WHITE = Load()
"""The paper's load."""


LOAD_FORMS = "white, lowpass:CORNER, spectrum:FILE or base:FILE"
"""The forms of a load on the command line (:func:`parse_load`)."""


def parse_load(text: str) -> Load:
    """The load of a command-line string: ``white``, ``lowpass:CORNER`` (corner in rocking
    frequencies ``1/T(sigma_Y)``, eq. 5), ``spectrum:FILE`` (a tabulated load spectrum) or
    ``base:FILE`` (a measured base-excitation record); anything else is refused in one sentence."""
    kind, sep, arg = str(text).strip().partition(":")
    kind = kind.strip().lower()
    if kind == "white" and not sep:
        return WHITE
    if kind == "lowpass" and arg.strip():
        try:
            corner = float(arg)
        except ValueError:
            raise checks.InputError(f"--load {text!r}: the corner '{arg}' is not a number; give lowpass:CORNER with CORNER in rocking frequencies, > 0") from None
        return Load("lowpass", corner)
    if kind in ("spectrum", "base") and arg.strip():
        raise checks.InputError(f"--load {text!r}: a {kind} load is not supported yet; use white or lowpass:CORNER")
    raise checks.InputError(f"--load {text!r} is not a load; give one of {LOAD_FORMS}")


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

ROCKING_MODELS = ("simplified", "housner")
"""The rocking models a record model states (eq. 4, eq. 2)."""


@dataclasses.dataclass(frozen=True)
class RecordModel:
    """The rocking model (:data:`ROCKING_MODELS`), the load and the sensor noise of a record."""

    rocking: str = "simplified"
    load: Load = WHITE
    sensor: SensorNoise = NO_NOISE

    def __post_init__(self):
        if self.rocking not in ROCKING_MODELS:
            raise checks.InputError(f"rocking model '{self.rocking}' is not known; use one of {', '.join(ROCKING_MODELS)}")

    def to_attrs(self) -> dict:
        """Flat file attributes (numbers and strings): ``rocking_model``, ``load``, ``load_corner``,
        ``sensor_noise``, ``sensor_noise_units``."""
        return {"rocking_model": self.rocking, **load_attrs(self.load), **sensor_attrs(self.sensor)}

    @classmethod
    def from_attrs(cls, attrs) -> "RecordModel":
        """The record model of attributes written by :meth:`to_attrs` (missing ones: the paper's)."""
        return cls(rocking=str(attrs.get("rocking_model", "simplified")), load=load_from_attrs(attrs), sensor=sensor_from_attrs(attrs))

    def key(self) -> dict:
        """The model as a JSON-able dict (a calibration's cache key names it); :meth:`from_key` reads it."""
        return {"rocking": self.rocking, "load": self.load.to_dict(), "sensor_noise": self.sensor.to_dict()}

    @classmethod
    def from_key(cls, key: dict) -> "RecordModel":
        """The record model of :meth:`key`."""
        return cls(key["rocking"], Load.from_dict(key["load"]), SensorNoise.from_dict(key["sensor_noise"]))


PAPER = RecordModel()
"""The paper's record model: simplified rocking, white load, no sensor noise."""


def load_attrs(load: Load) -> dict:
    """The load as flat attributes: ``load`` (its kind) and ``load_corner`` (NaN for white)."""
    return {"load": load.kind, "load_corner": float(load.corner)}


def load_from_attrs(attrs) -> Load:
    """The load of attributes written by :func:`load_attrs` (none: white)."""
    kind = str(attrs.get("load", "white"))
    return Load(kind) if kind == "white" else Load(kind, float(attrs["load_corner"]))


def sensor_attrs(sensor: SensorNoise) -> dict:
    """The sensor noise as flat attributes: ``sensor_noise`` (std) and ``sensor_noise_units``."""
    return {"sensor_noise": sensor.std, "sensor_noise_units": sensor.units}


def carried_attrs(attrs) -> dict:
    """The load and sensor attributes (:func:`load_attrs`, :func:`sensor_attrs`) among ``attrs``:
    what a product derived from a file of a run carries on, so every product names its load."""
    keys = (*load_attrs(WHITE), *sensor_attrs(NO_NOISE))
    return {key: attrs[key] for key in keys if key in attrs}


def sensor_from_attrs(attrs) -> SensorNoise:
    """The sensor noise of attributes written by :func:`sensor_attrs` (none: no noise)."""
    return SensorNoise(float(attrs.get("sensor_noise", 0.0)), str(attrs.get("sensor_noise_units", "sigma_y")))

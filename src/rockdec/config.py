"""Scenes: load ``config/config.yaml``, validate it against the schema, fill defaults.

The schema (``scene_schema.yaml``, linked from ``config/schema.yaml``) is the single
statement of every option, its range and its default. Errors name the offending field
and say how to fix it.
"""

from __future__ import annotations

import copy
from importlib import resources
from pathlib import Path

import jsonschema
import yaml

from rockdec import validate as checks
from rockdec.fits import DEFAULT_FIT_POINTS, min_points_per_cycle

#: The config file the workflow reads unless told otherwise.
DEFAULT_PATH = "config/config.yaml"


class ConfigError(checks.InputError):
    """A configuration the user can fix; the message names the field, the file and the fix.

    ``field`` is the dotted key (``scenes.paper.system.e``) and ``problem`` what is wrong
    with it, for callers that name the field otherwise (the command line names its flag).
    """

    def __init__(self, message: str, field: str | None = None, problem: str | None = None):
        super().__init__(message)
        self.field, self.problem = field, problem


def _field_error(where: str, problem: str, fix: str) -> ConfigError:
    return ConfigError(f"config field '{where}': {problem}. {fix}", field=where, problem=problem)


def schema() -> dict:
    """The scene schema as a dict, with the defaults whose home is the code filled in
    (``estimates.fit_points``: :data:`rockdec.fits.DEFAULT_FIT_POINTS`)."""
    text = resources.files("rockdec").joinpath("scene_schema.yaml").read_text()
    out = yaml.safe_load(text)
    out["$defs"]["scene"]["properties"]["estimates"]["properties"]["fit_points"]["default"] = DEFAULT_FIT_POINTS
    return out


def _with_defaults(validator_class):
    """A validator that also writes each property's ``default`` into the instance."""
    validate_properties = validator_class.VALIDATORS["properties"]

    def set_defaults(validator, properties, instance, sub_schema):
        if isinstance(instance, dict):
            for name, prop in properties.items():
                if "default" in prop and name not in instance:
                    instance[name] = copy.deepcopy(prop["default"])
        yield from validate_properties(validator, properties, instance, sub_schema)

    # JSON numbers are finite and integers have no decimal point: NaN, inf and 6000.0 fail
    # the "type" keyword (the minimum/maximum keywords alone let NaN through).
    types = validator_class.TYPE_CHECKER.redefine_many(
        {"number": lambda _, x: checks.is_finite_number(x), "integer": lambda _, x: checks.is_whole(x)}
    )
    return jsonschema.validators.extend(validator_class, {"properties": set_defaults}, type_checker=types)


_Validator = _with_defaults(jsonschema.Draft202012Validator)


def _problem(err: jsonschema.ValidationError) -> str:
    """What is wrong with a field, in words: NaN and whole-number decimals are named as such."""
    value = err.instance
    if err.validator == "type" and checks.is_number(value):
        if not checks.is_finite_number(value):
            return f"{checks.show(value)} is not a finite number; {_allowed(err.schema)}"
        if "integer" in err.validator_value and float(value).is_integer():
            return f"{checks.show(value)} is written as a decimal: write {int(value)}"
    return f"{err.message}; {_allowed(err.schema)}"


def _allowed(prop: dict) -> str:
    """What a schema property accepts, in words: ``use a number >= 0 and <= 1``."""
    if "enum" in prop:
        return "use one of " + ", ".join(map(str, prop["enum"]))
    types = prop.get("type", [])
    types = [types] if isinstance(types, str) else list(types)
    words = {"integer": "a whole number", "number": "a finite number", "null": "null", "boolean": "true or false"}
    kinds = " or ".join(words.get(t, f"a{'n' if t[0] in 'aeiou' else ''} {t}") for t in types if t != "null")
    bounds = [
        f"{sign} {prop[key]}"
        for key, sign in (("minimum", ">="), ("exclusiveMinimum", ">"), ("maximum", "<="), ("exclusiveMaximum", "<"))
        if key in prop
    ]
    if prop.get("minItems"):
        bounds.append(f"with at least {prop['minItems']} item")
    text = f"use {kinds or 'a value'}" + (" " + " and ".join(bounds) if bounds else "")
    return text + (" (or null)" if "null" in types else "")


def validate(config: dict, source: str | Path = DEFAULT_PATH) -> dict:
    """Validate ``config`` (a dict, changed in place) and fill defaults; returns it.

    Raises :class:`ConfigError` naming the first bad field and ``source``, the file the
    user passed (``--config``, ``--configfile``).
    """
    fix = f"Fix it in {source} (see config/schema.yaml)."
    validator = _Validator(schema())
    errors = sorted(validator.iter_errors(config), key=lambda err: (list(map(str, err.absolute_path)), err.validator != "type"))
    if errors:
        err = errors[0]
        where = ".".join(str(p) for p in err.absolute_path) or "(top level)"
        raise _field_error(where, _problem(err), fix)
    for name, scene in config["scenes"].items():
        try:
            checks.identifier(name, "scene name")
        except checks.InputError as exc:
            raise ConfigError(f"config field 'scenes': {exc} Rename the scene in {source}.") from None
        windows = scene["signatures"]["windows"]
        if list(windows) != sorted(set(windows)):
            raise _field_error(
                f"scenes.{name}.signatures.windows", f"{windows} must be strictly ascending; sort it and drop repeats", fix
            )
        exc = scene["excitation"]
        floor = min_points_per_cycle(scene["system"]["e"], scene["signatures"]["level"])
        if exc["dt"] is None and exc["points_per_cycle"] < floor:
            raise _field_error(
                f"scenes.{name}.excitation.points_per_cycle",
                f"{exc['points_per_cycle']} is below {floor:.1f}, the fewest samples per cycle that leave the local "
                f"fits of eq. 27 three points each at e = {scene['system']['e']} and level "
                f"{scene['signatures']['level']}; raise it",
                fix,
            )
        _check_readings(name, scene, fix)
    if config["default_scene"] not in config["scenes"]:
        raise ConfigError(
            f"config field 'default_scene': '{config['default_scene']}' is not a scene; pick one of {sorted(config['scenes'])}. {fix}"
        )
    return config


def _check_readings(name: str, scene: dict, fix: str) -> None:
    """The ``groups_of_10`` reading (the scene's own, or one of ``compare_readings``) needs
    at least 10 series per replicate; refuse here rather than in a workflow rule."""
    est, n_series = scene["estimates"], scene["records"]["series_per_replicate"]
    if n_series >= 10 or not (est["reading"] == "groups_of_10" or est["compare_readings"]):
        return
    key = "reading" if est["reading"] == "groups_of_10" else "compare_readings"
    raise _field_error(
        f"scenes.{name}.estimates.{key}",
        f"the groups_of_10 reading needs at least 10 series per replicate, and "
        f"'scenes.{name}.records.series_per_replicate' is {n_series}; raise it to 10"
        + (" or choose another reading" if key == "reading" else " or set compare_readings: false"),
        fix,
    )


def validate_scene(scene: dict, name: str = "cli", source: str | Path = DEFAULT_PATH) -> dict:
    """Validate and complete one scene on its own (changed in place); returns it."""
    return validate({"default_scene": name, "scenes": {name: scene}}, source)["scenes"][name]


def load(path: str | Path = DEFAULT_PATH) -> dict:
    """Read, validate and complete the configuration file at ``path``."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise ConfigError(f"cannot read the config file '{path}': {exc.strerror}; pass --config PATH.") from None
    try:
        config = yaml.safe_load(text) or {}
    except yaml.YAMLError as exc:
        raise ConfigError(f"config file '{path}' is not valid YAML: {exc}") from None
    if not isinstance(config, dict):
        raise ConfigError(f"config file '{path}' is not a mapping of settings; start it with 'scenes:'.")
    return validate(config, source=path)


def scene(config: dict, name: str) -> dict:
    """The completed scene ``name``; an unknown name lists the known ones."""
    try:
        return config["scenes"][name]
    except KeyError:
        raise ConfigError(f"unknown scene '{name}'; known scenes: {', '.join(sorted(config['scenes']))}.") from None

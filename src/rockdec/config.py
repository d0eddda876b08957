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

from rockdec.estimators import min_points_per_cycle

class ConfigError(ValueError):
    """A configuration the user can fix; the message names the field and the fix."""


def schema() -> dict:
    """The scene schema as a dict."""
    text = resources.files("rockdec").joinpath("scene_schema.yaml").read_text()
    return yaml.safe_load(text)


def _with_defaults(validator_class):
    """A validator that also writes each property's ``default`` into the instance."""
    validate_properties = validator_class.VALIDATORS["properties"]

    def set_defaults(validator, properties, instance, sub_schema):
        if isinstance(instance, dict):
            for name, prop in properties.items():
                if "default" in prop and name not in instance:
                    instance[name] = copy.deepcopy(prop["default"])
        yield from validate_properties(validator, properties, instance, sub_schema)

    return jsonschema.validators.extend(validator_class, {"properties": set_defaults})


_Validator = _with_defaults(jsonschema.Draft202012Validator)


def validate(config: dict) -> dict:
    """Validate ``config`` (a dict, changed in place) and fill defaults; returns it.

    Raises :class:`ConfigError` naming the first bad field.
    """
    validator = _Validator(schema())
    errors = sorted(validator.iter_errors(config), key=lambda err: list(err.absolute_path))
    if errors:
        err = errors[0]
        where = ".".join(str(p) for p in err.absolute_path) or "(top level)"
        raise ConfigError(f"config field '{where}': {err.message}. Fix it in config/config.yaml (see config/schema.yaml).")
    for name, scene in config["scenes"].items():
        windows = scene["signatures"]["windows"]
        if list(windows) != sorted(set(windows)):
            raise ConfigError(
                f"config field 'scenes.{name}.signatures.windows': {windows} must be strictly ascending; sort it and drop repeats."
            )
        exc = scene["excitation"]
        floor = min_points_per_cycle(scene["system"]["e"], scene["signatures"]["level"])
        if exc["dt"] is None and exc["points_per_cycle"] < floor:
            raise ConfigError(
                f"config field 'scenes.{name}.excitation.points_per_cycle': {exc['points_per_cycle']} is below "
                f"{floor:.1f}, the fewest samples per cycle that leave the local fits of eq. 27 three points "
                f"each at e = {scene['system']['e']} and level {scene['signatures']['level']}; raise it."
            )
    if config["default_scene"] not in config["scenes"]:
        raise ConfigError(
            f"config field 'default_scene': '{config['default_scene']}' is not a scene; pick one of {sorted(config['scenes'])}."
        )
    return config


def validate_scene(scene: dict, name: str = "cli") -> dict:
    """Validate and complete one scene on its own (changed in place); returns it."""
    return validate({"default_scene": name, "scenes": {name: scene}})["scenes"][name]


def load(path: str | Path = "config/config.yaml") -> dict:
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
    return validate(config)


def scene(config: dict, name: str) -> dict:
    """The completed scene ``name``; an unknown name lists the known ones."""
    try:
        return config["scenes"][name]
    except KeyError:
        raise ConfigError(f"unknown scene '{name}'; known scenes: {', '.join(sorted(config['scenes']))}.") from None

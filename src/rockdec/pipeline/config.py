"""Scenes: load ``config/config.yaml``, validate it against the schema, fill defaults.

The schema (``scene_schema.yaml``, linked from ``config/schema.yaml``) is the single
statement of every option, its range and its default. Errors name the offending field
and say how to fix it.
"""

from __future__ import annotations

import copy
import functools
import math
import re
import shutil
from importlib import resources
from pathlib import Path

import jsonschema
import yaml

from rockdec.pipeline import layout
from rockdec import validate as checks
from rockdec.rdd.fits import DEFAULT_FIT_POINTS, min_points_per_cycle
from rockdec.physics.models import SCALE_CONSTANT_GUESS, restoring_acceleration, step_for_density
from rockdec.physics.record_model import Load

__all__ = [
    "ConfigError", "DEFAULT_PATH", "OVERRIDE_SOURCE", "apply_overrides", "check_yaml11", "load",
    "read_yaml", "scene", "validate", "validate_scene",
]

#: The config file the workflow reads unless told otherwise.
DEFAULT_PATH = "config/config.yaml"

#: What the workflow names as the source of a setting given on its command line.
OVERRIDE_SOURCE = "the --config option of snakemake"

#: Most samples (replicates x series_per_replicate x n_points) a scene may simulate: about
#: 12 CPU-hours at :data:`SAMPLES_PER_CPU_SECOND`, 8000 times the paper scene.
MAX_SAMPLES = 10**12

#: Samples simulated and reduced to signature sums per CPU-second (burn-in included), as
#: measured on the paper scene (``benchmarks/bench_paper.py``; docs/development/benchmarks.md).
SAMPLES_PER_CPU_SECOND = 2.3e7


#: Most nodes a config may hold once its aliases are expanded: the shipped config holds
#: about 300; a YAML "alias bomb" (anchors of anchors) expands to billions and is refused
#: before anything walks it.
MAX_NODES = 100_000

#: Largest seed a scene may use: the seeds are 64-bit signed integers (``layout.scene_seeds``).
MAX_SEED = 2**63 - 1

#: The range every scale of a simulation (g, sigma_p, the step, sigma_Y) must lie in: its
#: square, which the pilot statistics take, is then a normal float (neither 0 nor inf).
SCALE_RANGE = checks.SQUARE_RANGE


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


_BaseLoader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


class _Yaml12Loader(_BaseLoader):
    """PyYAML's safe loader with the YAML 1.2 core schema's scalars: ``06000`` is 6000 (not
    the octal 3072 of YAML 1.1), ``0o17`` is octal, ``1e5`` a number, ``yes``, ``on`` and
    ``1:30`` are text, only ``true``/``false`` are booleans."""


_DROPPED = {f"tag:yaml.org,2002:{t}" for t in ("bool", "int", "float", "timestamp")}
_Yaml12Loader.yaml_implicit_resolvers = {
    first: [(tag, rx) for tag, rx in resolvers if tag not in _DROPPED]
    for first, resolvers in yaml.SafeLoader.yaml_implicit_resolvers.items()
}
_Yaml12Loader.add_implicit_resolver(
    "tag:yaml.org,2002:bool", re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$"), list("tTfF")
)
_Yaml12Loader.add_implicit_resolver(
    "tag:yaml.org,2002:int", re.compile(r"^(?:[-+]?[0-9]+|0o[0-7]+|0x[0-9a-fA-F]+)$"), list("-+0123456789")
)
_Yaml12Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^(?:[-+]?(?:\.[0-9]+|[0-9]+(?:\.[0-9]*)?)(?:[eE][-+]?[0-9]+)?|[-+]?\.(?:inf|Inf|INF)|\.(?:nan|NaN|NAN))$"),
    list("-+.0123456789"),
)


def _construct_int(loader, node):
    text = loader.construct_scalar(node)
    try:
        if text[:2] in ("0o", "0x"):
            return int(text[2:], 8 if text[1] == "o" else 16)
        return int(text, 10)
    except ValueError:
        what = f"a whole number of {len(text)} digits, more than a setting can hold" if text.isdigit() else f"{text!r} is not a whole number"
        raise yaml.constructor.ConstructorError(None, None, what, node.start_mark) from None


_Yaml12Loader.add_constructor("tag:yaml.org,2002:int", _construct_int)


def _expanded_nodes(node, seen: dict) -> int:
    """How many nodes ``node`` holds once every alias is expanded (each shared node counted
    as often as it is referenced, each computed once)."""
    if id(node) in seen:
        return seen[id(node)]
    count = 1
    if isinstance(node, yaml.SequenceNode):
        count += sum(_expanded_nodes(item, seen) for item in node.value)
    elif isinstance(node, yaml.MappingNode):
        count += sum(_expanded_nodes(k, seen) + _expanded_nodes(v, seen) for k, v in node.value)
    seen[id(node)] = count
    return count


def _expanded_count(value, seen: dict) -> int:
    """:func:`_expanded_nodes` of a value already read (lists and dicts shared by aliases)."""
    if id(value) in seen:
        return seen[id(value)]
    count = 1
    if isinstance(value, list):
        count += sum(_expanded_count(item, seen) for item in value)
    elif isinstance(value, dict):
        count += sum(1 + _expanded_count(item, seen) for item in value.values())
    seen[id(value)] = count
    return count


def _too_many_nodes(count: int, source) -> ConfigError:
    return ConfigError(
        f"{source} holds {checks.show(count)} values once its YAML aliases (*name) are expanded, more than the "
        f"{MAX_NODES:,} a configuration may hold; write the settings out without nested aliases."
    )


def read_yaml(text: str, source) -> object:
    r"""``text`` (the YAML of ``source``, a file name or :data:`OVERRIDE_SOURCE`) read as YAML 1.2.

    Numbers follow the YAML 1.2 core schema (``06000`` is 6000, ``1e5`` a number, ``yes`` is
    text), and a text whose aliases expand to more than :data:`MAX_NODES` values (an alias
    bomb) is refused before it is built.

    Parameters
    ----------
    text : str
        The YAML text.
    source : str or Path
        Where it came from, for the error message.

    Returns
    -------
    object
        The value (None for an empty text).

    Raises
    ------
    ConfigError
        Not valid YAML, nested too deep, or too many values once expanded.

    Examples
    --------
    >>> read_yaml("n_points: 06000\nboth: yes\nbig: 1e5", "x.yaml")
    {'n_points': 6000, 'both': 'yes', 'big': 100000.0}
    """
    loader = _Yaml12Loader(text)
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        count = _expanded_nodes(node, {})
        if count > MAX_NODES:
            raise _too_many_nodes(count, source)
        return loader.construct_document(node)
    except yaml.YAMLError as exc:
        raise ConfigError(f"{source} is not valid YAML: {' '.join(str(exc).split())}") from None
    except RecursionError:
        raise ConfigError(f"{source} nests its settings too deeply to be a configuration; flatten it.") from None
    finally:
        loader.dispose()


def check_yaml11(path) -> None:
    r"""Refuse a config file (read by Snakemake, whose reader is YAML 1.1) holding a plain
    value that YAML 1.1 and YAML 1.2 read differently (``06000``: 3072 or 6000; ``yes``: true
    or text; ``1e5``: text or a number), and an alias bomb (:func:`read_yaml`).

    Parameters
    ----------
    path : str or Path
        The config file.

    Raises
    ------
    ConfigError
        Naming the line, the value, both readings and how to write it.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "c.yaml"
    >>> _ = path.write_text("scenes: {s: {records: {n_points: 06000}}}\n")
    >>> check_yaml11(path)
    Traceback (most recent call last):
    ...
    rockdec.pipeline.config.ConfigError: config file ...c.yaml, line 1: 06000 reads as 3072 in YAML 1.1 (Snakemake's reader) and as 6000 in YAML 1.2; write 6000 (or the value meant, unambiguously).
    """
    try:
        text = Path(path).read_text()
    except OSError:
        return  # Snakemake read it; a file gone since is Snakemake's to report
    read_yaml(text, f"config file {path}")
    loader = _Yaml12Loader(text)
    try:
        root = loader.get_single_node()
    finally:
        loader.dispose()
    stack, seen = [root] if root is not None else [], set()
    while stack:
        node = stack.pop()
        if id(node) in seen:
            continue
        seen.add(id(node))
        if isinstance(node, yaml.ScalarNode):
            if not node.style:  # a plain scalar (style None, or "" from libyaml): quoted ones are text in both
                _compare_readings(node, path)
        elif isinstance(node, yaml.SequenceNode):
            stack.extend(node.value)
        elif isinstance(node, yaml.MappingNode):
            stack.extend(v for pair in node.value for v in pair)


def _compare_readings(node, path) -> None:
    """Refuse the plain scalar ``node`` of ``path`` if YAML 1.1 and 1.2 read it differently."""
    try:
        old = yaml.load(node.value, Loader=_BaseLoader)
        new = yaml.load(node.value, Loader=_Yaml12Loader)
    except yaml.YAMLError:
        return  # not a value on its own (Snakemake read the file as a whole)
    if type(old) is type(new) and (old == new or old != old and new != new):  # NaN: the same reading
        return

    def described(value):
        if isinstance(value, str):
            return f"the text {value!r}"
        return str(value).lower() if isinstance(value, bool) else checks.show(value)

    raise ConfigError(
        f"config file {path}, line {node.start_mark.line + 1}: {node.value} reads as {described(old)} in YAML 1.1 "
        f"(Snakemake's reader) and as {described(new)} in YAML 1.2; write "
        + (f"{checks.show(new)}" if checks.is_whole(new) else "true or false" if isinstance(old, bool) else
           f"{float(new)!r}" if checks.is_number(new) else repr(node.value))
        + " (or the value meant, unambiguously)."
    )


@functools.lru_cache(maxsize=1)
def _parsed_schema() -> dict:
    """The scene schema file, parsed once a process (by libyaml when PyYAML has it: the
    pure-Python parser would add a noticeable share of every Snakemake start, a no-op
    rerun's included)."""
    return yaml.load(resources.files("rockdec").joinpath("scene_schema.yaml").read_text(), Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))


def schema() -> dict:
    """The scene schema as a dict (a copy the caller may change), with the defaults whose
    home is the code filled in (``estimates.fit_points``: :data:`rockdec.rdd.fits.DEFAULT_FIT_POINTS`)."""
    out = copy.deepcopy(_parsed_schema())
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
            if abs(value) < 2**53:  # a decimal that holds its whole number exactly
                return f"{checks.show(value)} is written as a decimal: write {int(value)}"
            return f"{checks.show(value)} is written as a decimal beyond any count; {_allowed(err.schema)}"
    if checks.is_number(value) and err.validator in ("minimum", "maximum", "exclusiveMinimum", "exclusiveMaximum"):
        return f"{checks.show(value)} is out of range; {_allowed(err.schema)}"
    if err.validator == "type":
        return f"{_shown(value)} is not {_allowed(err.schema)[4:]}"
    return f"{err.message}; {_allowed(err.schema)}"


def _shown(value) -> str:
    """``value`` for a message, at most 60 characters of it."""
    text = checks.show(value) if checks.is_number(value) else repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


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


def canonical(value):
    """``value`` with every mapping's keys sorted, recursively: equal settings written in
    another key order compare (and print, as Snakemake stores a rule's params) the same."""
    if isinstance(value, dict):
        return {key: canonical(value[key]) for key in sorted(value)}
    if isinstance(value, list):
        return [canonical(item) for item in value]
    return value


def apply_overrides(config: dict, overrides: dict) -> dict:
    """Read the values of ``overrides`` (Snakemake's ``--config KEY=VALUE``) as YAML 1.2 values.

    Snakemake reads a nested ``--config`` value (``scenes='{tiny: {records: {replicates: 3}}}'``)
    with every leaf a string, lists included (``signatures: {windows: [0.25, 0.5]}``); each
    such string of ``overrides`` is read again as a YAML 1.2 scalar (:func:`read_yaml`:
    ``3`` and ``06000`` integers, ``0.5`` and ``1e12`` numbers, ``true`` a boolean) and put in
    its place in ``config`` (changed in place; returned). Overrides whose aliases expand
    beyond :data:`MAX_NODES` values are refused.
    """
    count = _expanded_count(overrides or {}, {})
    if count > MAX_NODES:
        raise _too_many_nodes(count, OVERRIDE_SOURCE)

    def read(value, key=None):
        if isinstance(value, dict):
            return {k: read(v, k) for k, v in value.items()}
        if isinstance(value, list):
            return [read(item) for item in value]
        if not isinstance(value, str) or key == "description" or not value.strip():
            return value
        try:
            parsed = read_yaml(value, OVERRIDE_SOURCE)
        except ConfigError:
            return value
        return parsed if isinstance(parsed, (str, int, float, bool)) else value

    def walk(target: dict, given: dict):
        for key, value in given.items():
            if isinstance(value, dict) and isinstance(target.get(key), dict):
                walk(target[key], value)
            else:
                target[key] = read(value, key)

    walk(config, overrides or {})
    return config


def _given_in(where: list[str], overrides: dict) -> bool:
    """Whether the field at path ``where`` (or a mapping holding it) came from ``overrides``."""
    node = overrides
    for key in where:
        if not isinstance(node, dict) or key not in node:
            return False
        node = node[key]
        if not isinstance(node, dict):
            return True
    return True


def validate(config: dict, source: str | Path = DEFAULT_PATH, overrides: dict | None = None, sizes: bool = True) -> dict:
    """Validate ``config`` (a dict, changed in place) and fill defaults; returns it.

    Raises :class:`ConfigError` naming the first bad field and where it was set: the
    ``--config`` option for a field in ``overrides`` (what the command line set), else
    ``source``, the file the user passed (``--configfile``). ``sizes``: also refuse a scene
    too large to run (:func:`_check_size`).
    """

    def set_in(where: str) -> str:
        return OVERRIDE_SOURCE if _given_in(where.split("."), overrides or {}) else str(source)

    def fix(where: str) -> str:
        return f"Fix it in {set_in(where)} (see config/schema.yaml)."

    validator = _Validator(schema())
    errors = sorted(validator.iter_errors(config), key=lambda err: (list(map(str, err.absolute_path)), err.validator != "type"))
    if errors:
        err = errors[0]
        path = [str(p) for p in err.absolute_path]
        problem = _problem(err)
        if err.validator == "additionalProperties" and isinstance(err.instance, dict):
            extra = sorted(set(map(str, err.instance)) - set(err.schema.get("properties", {})))
            if extra:  # name the misspelt key itself, and where it was set
                path.append(extra[0])
                known = ", ".join(sorted(err.schema.get("properties", {})))
                problem = f"'{extra[0]}' is not a setting here; " + (f"use one of {known}" if known else "remove it")
        where = ".".join(path) or "(top level)"
        raise _field_error(where, problem, fix(where))
    for name, scene in config["scenes"].items():
        try:
            checks.identifier(name, "scene name")
        except checks.InputError as exc:
            raise ConfigError(f"config field 'scenes': {exc} Rename the scene in {set_in('scenes.' + name)}.") from None
        windows = scene["signatures"]["windows"]
        if list(windows) != sorted(set(windows)):
            where = f"scenes.{name}.signatures.windows"
            raise _field_error(where, f"{windows} must be strictly ascending; sort it and drop repeats", fix(where))
        exc = scene["excitation"]
        if scene["system"]["e"] == 1.0 and (exc["dt"] is None or exc["burn_in"] is None):
            where = f"scenes.{name}.system.e"
            raise _field_error(
                where,
                "e = 1 dissipates no energy, so the response never becomes stationary: neither the step (from "
                "points_per_cycle at sigma_Y) nor the burn-in can be derived; give both (excitation.dt and "
                "excitation.burn_in in a scene, --dt and --burn-in on the command line)",
                fix(where),
            )
        try:
            load = Load.from_dict(exc["load"])
            if exc["load"].get("file") is not None:  # the table read, so the scene (and its rules' params) carry it
                exc["load"] = load.to_dict()
        except checks.InputError as err:
            raise _field_error(f"scenes.{name}.excitation.load", str(err).rstrip("."), fix(f"scenes.{name}.excitation.load")) from None
        floor = min_points_per_cycle(scene["system"]["e"], scene["signatures"]["level"])
        if exc["dt"] is None and exc["points_per_cycle"] < floor:
            level = scene["signatures"]["level"]
            default_level = schema()["$defs"]["scene"]["properties"]["signatures"]["properties"]["level"]["default"]
            if exc["points_per_cycle"] >= min_points_per_cycle(scene["system"]["e"], default_level):
                # enough samples per cycle at the default level: the level raised the floor
                where = f"scenes.{name}.signatures.level"
                problem = (
                    f"{checks.show(level)} needs at least {floor:.3g} samples per cycle to leave the local fits of eq. 27 "
                    f"three points each at e = {checks.show(scene['system']['e'])}, more than points_per_cycle "
                    f"{checks.show(exc['points_per_cycle'])}; raise the level (the trigger in units of sigma_Y, 2 by default)"
                )
            else:
                where = f"scenes.{name}.excitation.points_per_cycle"
                problem = (
                    f"{checks.show(exc['points_per_cycle'])} is below {floor:.3g}, the fewest samples per cycle that leave "
                    f"the local fits of eq. 27 three points each at e = {checks.show(scene['system']['e'])} and level "
                    f"{checks.show(level)}; raise it"
                )
            raise _field_error(where, problem, fix(where))
        _check_seeds(name, scene, fix)
        _check_scales(name, scene, fix)
        _check_readings(name, scene, fix)
        if sizes:
            _check_size(name, scene, fix)
    if config["default_scene"] not in config["scenes"]:
        raise ConfigError(
            f"config field 'default_scene': '{config['default_scene']}' is not a scene; pick one of "
            f"{sorted(config['scenes'])}. {fix('default_scene')}"
        )
    return config


def _check_seeds(name: str, scene: dict, fix) -> None:
    """The scene's seeds (``first_seed`` on, one per series) must be 64-bit integers."""
    rec = scene["records"]
    count = rec["replicates"] * rec["series_per_replicate"]
    last = rec["first_seed"] + count - 1
    if count > MAX_SEED:
        where = f"scenes.{name}.records"
        raise _field_error(
            where,
            f"the scene asks for {checks.show(count)} series (replicates x series_per_replicate), more than the "
            f"{checks.show(MAX_SEED)} 64-bit seeds; lower replicates or series_per_replicate",
            fix(where),
        )
    if last > MAX_SEED:
        where = f"scenes.{name}.records.first_seed"
        raise _field_error(
            where,
            f"{checks.show(rec['first_seed'])} makes the scene's seeds run to {checks.show(last)}, beyond "
            f"{checks.show(MAX_SEED)}, the largest 64-bit seed; lower it",
            fix(where),
        )


def _check_scales(name: str, scene: dict, fix) -> None:
    """Refuse a system whose scales leave the floating-point range of the simulation before
    any job runs (rule ``calibrate`` would otherwise fail): ``g = nu^2 theta_cr``, ``sigma_p``,
    the step (given, or the first step of the step search at
    :data:`rockdec.physics.models.SCALE_CONSTANT_GUESS`) and the amplitude ``sigma_Y`` of the
    scale law (:func:`rockdec.physics.models.scale_constant`) must each lie in
    :data:`SCALE_RANGE`."""
    system, exc = scene["system"], scene["excitation"]
    lo, hi = SCALE_RANGE
    inside = f"outside [{lo:.2g}, {hi:.2g}], the finite range whose squares the simulation can take"
    g = restoring_acceleration(system["nu"], system["theta_cr"])
    if not lo <= g <= hi:
        # blamed: the factor of g further from 1 on a log scale
        nu_off = abs(2.0 * math.log(system["nu"]))  # nu, theta_cr > 0 (the schema): log(nu^2) without its under- or overflow
        key, other = ("nu", "theta_cr") if nu_off >= abs(math.log(system["theta_cr"])) else ("theta_cr", "nu")
        where = f"scenes.{name}.system.{key}"
        raise _field_error(
            where,
            f"{checks.show(system[key])} with {other} {checks.show(system[other])} gives g = nu^2 theta_cr = "
            f"{g:.3g} rad/s^2, {inside}; choose nu and theta_cr for a g in that range",
            fix(where),
        )
    sigma_p = exc["sigma_p"]
    if sigma_p == 0.0:
        return  # a free response: its step comes from its amplitude
    if not lo <= sigma_p <= hi:
        where = f"scenes.{name}.excitation.sigma_p"
        raise _field_error(where, f"{checks.show(sigma_p)} is {inside}; give the impulse std in rad/s in that range", fix(where))
    given_dt = exc["dt"] is not None
    dt = exc["dt"] if given_dt else step_for_density(SCALE_CONSTANT_GUESS, sigma_p, g, exc["points_per_cycle"])
    log_sigma_y = math.log(SCALE_CONSTANT_GUESS) + 4 * math.log(sigma_p) - 2 * math.log(dt) - 3 * math.log(g)
    for what, value in (("the step", dt), ("the amplitude sigma_Y", math.exp(min(log_sigma_y, 709.0)))):
        if not lo <= value <= hi:
            where = f"scenes.{name}.excitation.{'dt' if given_dt else 'sigma_p'}"
            raise _field_error(
                where,
                f"{checks.show(dt if given_dt else sigma_p)} with g = {g:.3g} rad/s^2 makes {what} about {value:.2g}, "
                f"{inside}; choose sigma_p{' and dt' if given_dt else ''} on the scale of g (g = 1 rad/s^2 with "
                "sigma_p = 0.003 rad/s gives sigma_Y about 0.002 rad)",
                fix(where),
            )


def _check_readings(name: str, scene: dict, fix) -> None:
    """The ``groups_of_10`` reading (the scene's own, or one of ``compare_readings``) needs
    at least 10 series per replicate; refuse here rather than in a workflow rule."""
    est, n_series = scene["estimates"], scene["records"]["series_per_replicate"]
    if n_series >= 10 or not (est["reading"] == "groups_of_10" or est["compare_readings"]):
        return
    key = "reading" if est["reading"] == "groups_of_10" else "compare_readings"
    where = f"scenes.{name}.estimates.{key}"
    raise _field_error(
        where,
        f"the groups_of_10 reading needs at least 10 series per replicate, and "
        f"'scenes.{name}.records.series_per_replicate' is {n_series}; raise it to 10"
        + (" or choose another reading" if key == "reading" else " or set compare_readings: false"),
        fix(where),
    )


def signature_memory_bytes(scene: dict, part: int | None = None) -> float:
    """Memory one signature job of ``scene`` needs: the whole pass, or job ``part`` of a
    scene split by ``records.replicates_per_job`` (:func:`rockdec.pipeline.layout.part_records`).

    Sums, signatures and free responses of every unit of the pass (about 3 x 8 bytes x
    2 triggers x windows x lags each; the lag range is about n_periods sqrt(level) samples
    per cycle at sigma_Y a side, eq. 5), the series of the chunks in flight (about 6
    float64 copies of chunk_seeds x n_points per thread, 2 threads), and 1 GB for the
    interpreter and libraries. The workflow asks a cluster for this (``resources: mem_mb``).
    """
    rec = scene["records"] if part is None else layout.part_records(scene["records"], part)[0]
    sig, est, exc = scene["signatures"], scene["estimates"], scene["excitation"]
    spr = rec["series_per_replicate"]
    units = rec["replicates"] * (min(spr, 100 + spr // 10) if est["compare_readings"] else spr)
    lags = 2 * sig["n_periods"] * sig["level"] ** 0.5 * exc["points_per_cycle"] + 1
    sums = 3 * 8 * 2 * len(sig["windows"]) * lags * units
    series = 2 * 6 * 8 * min(rec["chunk_seeds"], rec["replicates"] * spr) * rec["n_points"]
    return sums + series + 1e9


def machine_memory_bytes() -> float:
    """Physical memory of this machine."""
    import psutil

    return float(psutil.virtual_memory().total)


def _check_size(name: str, scene: dict, fix) -> None:
    """Refuse a scene beyond what a run can do, before any work (so ``snakemake -n`` refuses
    too), with the estimate in the sentence: more than :data:`MAX_SAMPLES` samples, a
    signature job that needs more memory than this machine has, or series files
    (``store_series: all``, float32) larger than the free space of the working folder."""
    rec = scene["records"]
    samples = rec["replicates"] * rec["series_per_replicate"] * rec["n_points"]
    where = f"scenes.{name}.records"
    if samples > MAX_SAMPLES:
        hours = samples / SAMPLES_PER_CPU_SECOND / 3600
        raise _field_error(
            where,
            f"the scene needs about {samples:.2g} samples (replicates x series_per_replicate x n_points), "
            f"about {hours:,.0f} CPU-hours at {SAMPLES_PER_CPU_SECOND:.2g} samples per CPU-second, more than the "
            f"{MAX_SAMPLES:.0e} samples a run may simulate; lower n_points, replicates or series_per_replicate",
            fix(where),
        )
    parts = layout.signature_parts(rec)
    job_bytes = max(signature_memory_bytes(scene, part) for part in parts) if parts else signature_memory_bytes(scene)
    if job_bytes > machine_memory_bytes():
        raise _field_error(
            where,
            f"one signature job of the scene needs about {job_bytes / 1e9:.3g} GB of memory, more than the "
            f"{machine_memory_bytes() / 1e9:.3g} GB of this machine; lower chunk_seeds or n_points, or split the "
            "pass into jobs with replicates_per_job",
            fix(where),
        )
    if layout.stores_all(rec):
        disk, free = 4.0 * samples, shutil.disk_usage(".").free
        if disk > free:
            raise _field_error(
                f"{where}.store_series",
                f"'all' writes about {disk / 1e9:.3g} GB of series files, more than the {free / 1e9:.3g} GB free "
                "on this disk; store fewer series (a count) or free some space",
                fix(f"{where}.store_series"),
            )


def validate_scene(scene: dict, name: str = "cli", source: str | Path = DEFAULT_PATH, sizes: bool = False) -> dict:
    """Validate and complete one scene on its own (changed in place); returns it. The size
    checks are the caller's (the command line estimates its own work, naming its options)
    unless ``sizes``."""
    return validate({"default_scene": name, "scenes": {name: scene}}, source, sizes=sizes)["scenes"][name]


def load(path: str | Path = DEFAULT_PATH) -> dict:
    """Read, validate and complete the configuration file at ``path``."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise ConfigError(f"cannot read the config file '{path}': {exc.strerror}; pass --config PATH.") from None
    config = read_yaml(text, f"config file '{path}'") or {}
    if not isinstance(config, dict):
        raise ConfigError(f"config file '{path}' is not a mapping of settings; start it with 'scenes:'.")
    return validate(config, source=path)


def scene(config: dict, name: str) -> dict:
    """The completed scene ``name``; an unknown name lists the known ones."""
    try:
        return config["scenes"][name]
    except KeyError:
        raise ConfigError(f"unknown scene '{name}'; known scenes: {', '.join(sorted(config['scenes']))}.") from None

"""Scenes: load ``config/config.yaml``, validate it against the schema, fill defaults.

The schema (``scene_schema.yaml``, linked from ``config/schema.yaml``) is the single
statement of every option, its range and its default. Errors name the offending field
and say how to fix it.
"""

from __future__ import annotations

import copy
import functools
import shutil
from importlib import resources
from pathlib import Path

import jsonschema
import yaml

from rockdec.pipeline import layout
from rockdec import validate as checks
from rockdec.rdd.fits import DEFAULT_FIT_POINTS, min_points_per_cycle
from rockdec.physics.record_model import Load

#: The config file the workflow reads unless told otherwise.
DEFAULT_PATH = "config/config.yaml"

#: What the workflow names as the source of a setting given on its command line.
OVERRIDE_SOURCE = "the --config option of snakemake"

#: Most samples (replicates x series_per_replicate x n_points) a scene may simulate: about
#: 12 CPU-hours at :data:`SAMPLES_PER_CPU_SECOND`, 8000 times the paper scene.
MAX_SAMPLES = 10**12

#: Samples simulated and reduced to signature sums per CPU-second (burn-in included), as
#: measured on the paper scene (README, "How long it takes": 2.8e8 steps in 12.3 CPU s).
SAMPLES_PER_CPU_SECOND = 2.3e7


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


@functools.lru_cache(maxsize=1)
def _parsed_schema() -> dict:
    """The scene schema file, parsed once a process (by libyaml when PyYAML has it: the
    pure-Python parser takes 0.03 s of every Snakemake start, a no-op rerun's included)."""
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


def canonical(value):
    """``value`` with every mapping's keys sorted, recursively: equal settings written in
    another key order compare (and print, as Snakemake stores a rule's params) the same."""
    if isinstance(value, dict):
        return {key: canonical(value[key]) for key in sorted(value)}
    if isinstance(value, list):
        return [canonical(item) for item in value]
    return value


def apply_overrides(config: dict, overrides: dict) -> dict:
    """Read the values of ``overrides`` (Snakemake's ``--config KEY=VALUE``) as YAML values.

    Snakemake reads a nested ``--config`` value (``scenes='{tiny: {records: {replicates: 3}}}'``)
    with every leaf a string; each such string of ``overrides`` is read again as a YAML
    scalar (``3`` an integer, ``0.5`` a number, ``true`` a boolean, ``1e12`` a number) and
    put in its place in ``config`` (changed in place; returned).
    """

    def read(text: str):
        value = yaml.safe_load(text) if text.strip() else text
        if isinstance(value, str):
            try:
                value = float(text)  # YAML 1.1 reads 1e12 as text
            except ValueError:
                return text
        return value

    def walk(target: dict, given: dict):
        for key, value in given.items():
            if isinstance(value, dict) and isinstance(target.get(key), dict):
                walk(target[key], value)
            elif isinstance(value, str) and key != "description":
                target[key] = read(value)

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
        where = ".".join(str(p) for p in err.absolute_path) or "(top level)"
        raise _field_error(where, _problem(err), fix(where))
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
            where = f"scenes.{name}.excitation.points_per_cycle"
            raise _field_error(
                where,
                f"{exc['points_per_cycle']} is below {floor:.1f}, the fewest samples per cycle that leave the local "
                f"fits of eq. 27 three points each at e = {scene['system']['e']} and level "
                f"{scene['signatures']['level']}; raise it",
                fix(where),
            )
        _check_readings(name, scene, fix)
        if sizes:
            _check_size(name, scene, fix)
    if config["default_scene"] not in config["scenes"]:
        raise ConfigError(
            f"config field 'default_scene': '{config['default_scene']}' is not a scene; pick one of "
            f"{sorted(config['scenes'])}. {fix('default_scene')}"
        )
    return config


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

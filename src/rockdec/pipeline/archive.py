"""Archives a reader can verify: the NetCDF files behind a scene's tables and figures.

:func:`write_archive` (rule ``archive_scene``) copies every NetCDF file that a scene's
tables and figures are made from, the tables, and the workflow that made them (the
``Snakefile``, ``workflow/`` and ``config/``) into one folder. ``manifest.json`` records
per file its name, size in bytes and SHA-256 (and, for products, the rule that made it),
the scene's settings, the versions of the packages that ran, the git commit, whether the
source tree held uncommitted changes, and when the products were written. From the
manifest, :func:`rockdec.pipeline.crate.crate_from_manifest` derives ``ro-crate-metadata.json``, a
Workflow Run Crate: the manifest is the one source of truth.

:func:`verify` re-checks every listed file, reports files nobody listed, and checks the
crate against the manifest and the profile's required points; it never opens a path
outside the folder. :func:`rebuild` redraws the tables and figures from the archive alone
with the workflow's own step functions (:mod:`rockdec.pipeline.steps`), and no simulation.
"""

from __future__ import annotations

import copy
import errno
import hashlib
import json
import os
import secrets
import shutil
import stat
import uuid
from datetime import datetime, timezone
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path, PurePosixPath

import jsonschema

from rockdec import io
from rockdec.pipeline import layout
from rockdec.validate import MAX_NAME_BYTES, InputError

__all__ = [
    "ArchiveError", "CRATE", "MANIFEST", "check_manifest", "check_rebuild_target", "read_manifest",
    "rebuild", "same_data", "verify", "write_archive",
]

MANIFEST = "manifest.json"
CRATE = "ro-crate-metadata.json"

PACKAGES = ("rockdec", "numpy", "xarray", "netCDF4", "numba", "dask", "snakemake", "rocrate")
"""Packages whose versions a manifest records."""

_ENTRY = {
    "type": "object",
    "required": ["name", "size", "sha256"],
    "properties": {
        "name": {"type": "string", "minLength": 1},
        "size": {"type": "integer", "minimum": 0},
        "sha256": {"type": "string", "pattern": "^[0-9a-f]{64}$"},
        "rule": {"type": "string"},
    },
}
_TEXT = {"type": "string", "minLength": 1}

MANIFEST_SCHEMA = {
    "type": "object",
    "required": ["scene", "settings", "versions", "git_commit", "git_dirty", "datePublished", "run", "workflow", "files"],
    "properties": {
        "scene": _TEXT,
        "kind": {"enum": ["scene", "campaign"]},
        "settings": {"type": "object"},
        "versions": {"type": "object", "additionalProperties": {"type": "string"}},
        "git_commit": _TEXT,
        "git_dirty": {"type": ["boolean", "null"]},
        "datePublished": _TEXT,
        "run": {
            "type": "object",
            "required": ["id", "startTime", "endTime"],
            "properties": {"id": {"type": "string", "pattern": "^#run-[0-9a-f-]+$"}, "startTime": _TEXT, "endTime": _TEXT},
        },
        "workflow": {"type": "array", "minItems": 1, "items": _ENTRY},
        "files": {"type": "array", "minItems": 1, "items": {**_ENTRY, "required": ["name", "size", "sha256", "rule"]}},
    },
}
"""What a manifest holds; :func:`check_manifest` refuses anything else in one sentence."""


#: Longest path (bytes) the system's calls take (Linux ``PATH_MAX`` less its NUL); a
#: manifest name longer than this cannot be a file of any folder.
MAX_PATH_BYTES = 4095


class ArchiveError(InputError):
    """An archive folder that cannot be verified or rebuilt as it is; the message says why."""


def package_versions() -> dict[str, str]:
    """Installed version of each of :data:`PACKAGES` (``"not installed"`` if absent)."""
    out = {}
    for name in PACKAGES:
        try:
            out[name] = version(name)
        except PackageNotFoundError:
            out[name] = "not installed"
    return out


def _utc(seconds: float | None = None) -> str:
    moment = datetime.now(timezone.utc) if seconds is None else datetime.fromtimestamp(seconds, timezone.utc)
    return moment.isoformat(timespec="seconds")


def _copy(source: Path, folder: Path, name: str) -> dict:
    target = folder / name
    target.parent.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(source, target)
    return {"name": name, "size": target.stat().st_size, "sha256": io.sha256(target)}


def _write_json(path: Path, data) -> None:
    tmp = path.with_name(f".{path.name}.partial")
    tmp.write_text(json.dumps(data, indent=2) + "\n")
    os.replace(tmp, path)


def write_archive(
    folder: str | Path, results: str | Path, producers: dict[str, str], scene_name: str, scene: dict, workflow_root: str | Path,
    kind: str = "scene",
) -> Path:
    """Copy the products ``producers`` names (paths relative to ``results``, each mapped to
    the rule that wrote it) and the workflow's files under ``workflow_root`` into ``folder``,
    with ``manifest.json`` and the crate derived from it. Returns the manifest's path.

    Whatever ``folder`` held before is removed first, so it holds exactly what its manifest
    lists (the rules declare the manifest and the crate as their outputs, not the folder,
    which Snakemake would mark with a file of its own). ``kind``: what ``scene_name`` names, a
    ``scene`` of the config or a test ``campaign`` (its settings the sheet's rows)."""
    from rockdec.pipeline import crate as crates  # the rocrate library: only when writing or checking a crate

    folder, results, workflow_root = Path(folder), Path(results), Path(workflow_root)
    if folder.is_dir() and not folder.is_symlink():
        shutil.rmtree(folder)
    folder.mkdir(parents=True)
    written = [(results / name).stat().st_mtime for name in producers]
    files = [{**_copy(results / name, folder, name), "rule": rule} for name, rule in producers.items()]
    sources = [_copy(workflow_root / name, folder, name) for name in layout.workflow_sources(workflow_root)]
    manifest = {
        "scene": scene_name,
        "kind": kind,
        "settings": scene,
        "versions": package_versions(),
        "git_commit": io.git_commit(),
        "git_dirty": io.git_dirty(),
        "datePublished": _utc(),
        "run": {"id": f"#run-{uuid.uuid4()}", "startTime": _utc(min(written)), "endTime": _utc(max(written))},
        "workflow": sources,
        "files": files,
    }
    path = folder / MANIFEST
    check_manifest(manifest, path)
    _write_json(path, manifest)
    entry = {"name": MANIFEST, "size": path.stat().st_size, "sha256": io.sha256(path)}
    _write_json(folder / CRATE, crates.crate_from_manifest(manifest, entry))
    return path


#: How a JSON value's type reads in a sentence, by its JSON Schema name and by its Python type.
_KINDS = {"object": "an object", "array": "a list", "string": "a string", "boolean": "a boolean", "integer": "an integer", "number": "a number", "null": "null"}
_JSON_TYPES = {dict: "object", list: "array", str: "string", bool: "boolean", int: "integer", float: "number", type(None): "null"}


def _schema_problem(err: jsonschema.ValidationError) -> str:
    """The failed check ``err`` of :data:`MANIFEST_SCHEMA` as the end of a sentence."""
    if err.validator == "required":
        return f"lacks the key '{next(key for key in err.validator_value if key not in err.instance)}'"
    if err.validator == "type":
        wanted = [err.validator_value] if isinstance(err.validator_value, str) else err.validator_value
        return f"is {_KINDS[_JSON_TYPES[type(err.instance)]]}, not {' or '.join(_KINDS[t] for t in wanted)}"
    if err.validator == "minItems":
        return "is empty: an archive lists at least one file"
    if err.validator == "pattern":
        return f"'{str(err.instance)[:80]}' is not of the form {err.validator_value}"
    if err.validator == "minimum":
        return "is negative"
    if err.validator == "minLength":
        return "is empty"
    return err.message[:120]


def _name_problem(name: str) -> str | None:
    """Why ``name`` cannot be a file of an archive folder (None if it can)."""
    path = PurePosixPath(name)
    if path.is_absolute() or name.startswith("~") or (len(name) > 1 and name[1] == ":"):
        return "is an absolute path"
    if ".." in path.parts:
        return "climbs out of the folder with '..'"
    if "\\" in name or "\0" in name or path.as_posix() != name or "." in path.parts:
        return "is not a plain relative path (no backslash, NUL, '.', '//' or trailing '/')"
    if name in (MANIFEST, CRATE):
        return "is the manifest's or the crate's own name"
    longest = max(len(os.fsencode(part)) for part in path.parts)
    if longest > MAX_NAME_BYTES:
        return f"has a component of {longest} bytes, longer than the {MAX_NAME_BYTES} a file system stores"
    if len(os.fsencode(name)) > MAX_PATH_BYTES:
        return f"is {len(os.fsencode(name))} bytes long, longer than the {MAX_PATH_BYTES} a path may be"
    return None


def check_manifest(manifest, path: str | Path) -> dict:
    """``manifest`` if it is one that :func:`write_archive` writes; else :class:`ArchiveError`
    naming the first bad field of the file ``path``."""
    fix = "restore the published copy of the archive, or remake it with `snakemake --cores 2 results/<scene>/archive/manifest.json`"
    errors = sorted(jsonschema.Draft202012Validator(MANIFEST_SCHEMA).iter_errors(manifest), key=lambda e: list(map(str, e.absolute_path)))
    if errors:
        err = errors[0]
        where = ".".join(map(str, err.absolute_path)) or "(top level)"
        raise ArchiveError(f"'{path}' is not a manifest rockdec writes: field {where} {_schema_problem(err)}; {fix}.")
    for key in ("datePublished", "run.startTime", "run.endTime"):
        value = manifest[key] if "." not in key else manifest["run"][key.split(".")[1]]
        try:
            datetime.fromisoformat(value)
        except ValueError:
            raise ArchiveError(f"'{path}' field {key} '{value[:40]}' is not an ISO 8601 time; {fix}.") from None
    seen = set()
    for group in ("workflow", "files"):
        for i, entry in enumerate(manifest[group]):
            name = entry["name"]
            problem = _name_problem(name) or ("is listed twice" if name in seen else None)
            if problem:
                raise ArchiveError(f"'{path}' field {group}.{i}.name '{name[:80]}' {problem}; an archive lists only files inside its folder; {fix}.")
            seen.add(name)
    if manifest["workflow"][0]["name"] != "Snakefile":
        raise ArchiveError(f"'{path}' field workflow.0.name is not 'Snakefile' (the workflow's main file); {fix}.")
    return manifest


def _read_inside(folder: Path, name: str) -> bytes:
    """The bytes of the regular file ``name`` of ``folder``; :class:`ArchiveError` if it is
    missing or not a regular file (a symbolic link is never followed)."""
    path = folder / name
    try:
        mode = os.lstat(path).st_mode
    except (FileNotFoundError, NotADirectoryError):
        raise ArchiveError(f"'{folder}' holds no {name}: pass the folder rule `archive` wrote (results/<scene>/archive).") from None
    except OSError as exc:
        raise ArchiveError(f"cannot read '{path}' ({exc.strerror}); check its permissions.") from None
    if not stat.S_ISREG(mode):
        raise ArchiveError(f"'{path}' is not a regular file (a link or a folder); an archive's {name} must be the file itself.")
    try:
        with os.fdopen(os.open(path, os.O_RDONLY | os.O_NOFOLLOW), "rb") as f:
            return f.read()
    except OSError as exc:
        raise ArchiveError(f"cannot read '{path}' ({exc.strerror}); check its permissions.") from None


def read_manifest(folder: str | Path) -> dict:
    """The checked manifest of an archive folder (:func:`check_manifest`); :class:`ArchiveError`
    if there is none, it is not JSON or it is not a manifest rockdec writes."""
    folder = Path(folder)
    try:
        manifest = json.loads(_read_inside(folder, MANIFEST))
    except (json.JSONDecodeError, UnicodeDecodeError, RecursionError) as exc:
        raise ArchiveError(f"'{folder / MANIFEST}' is not valid JSON ({type(exc).__name__}); the manifest itself was changed.") from None
    return check_manifest(manifest, folder / MANIFEST)


def _file_problem(folder: Path, entry: dict) -> str | None:
    """What is wrong with the listed file ``entry`` in ``folder`` (None if it matches). No
    component of its path may be a symbolic link; only then is the file read."""
    name = entry["name"]
    path = folder
    for part in PurePosixPath(name).parts:
        path = path / part
        try:
            mode = os.lstat(path).st_mode
        except (FileNotFoundError, NotADirectoryError):
            return f"missing: {name}"
        except OSError as exc:
            return f"unreadable: {name} ({exc.strerror})"
        if stat.S_ISLNK(mode):
            return f"not a plain file: {name} ('{path.relative_to(folder).as_posix()}' is a symbolic link; an archive holds no links)"
    if not stat.S_ISREG(mode):
        return f"not a plain file: {name} (a folder or a device; an archive holds regular files)"
    try:
        size = os.lstat(path).st_size
        if size != entry["size"]:
            return f"changed: {name} (its size is {size} bytes, the manifest says {entry['size']})"
        if io.sha256(path) != entry["sha256"]:
            return f"changed: {name} (SHA-256 differs from the manifest)"
    except OSError as exc:
        return f"unreadable: {name} ({exc.strerror})"
    return None


def _present(folder: Path) -> set[str]:
    """Every file, link or other non-folder entry under ``folder``, relative (links not followed)."""
    found = set()
    for here, dirs, files in os.walk(folder):
        base = Path(here).relative_to(folder)
        found.update((base / name).as_posix() for name in files)
        found.update((base / name).as_posix() for name in dirs if os.path.islink(os.path.join(here, name)))
    return found


def _crate_problems(folder: Path, manifest: dict) -> list[str]:
    """The crate against the manifest (re-derived) and against the profile's required points."""
    from rockdec.pipeline import crate as crates

    if not os.path.lexists(folder / CRATE):
        return [f"missing: {CRATE}"]
    try:
        stored = json.loads(_read_inside(folder, CRATE))
    except ArchiveError:
        return [f"not a plain file: {CRATE} (a link or a folder; an archive holds regular files)"]
    except (json.JSONDecodeError, UnicodeDecodeError, RecursionError):
        return [f"changed: {CRATE} (not valid JSON)"]
    entry = {"name": MANIFEST, "size": os.lstat(folder / MANIFEST).st_size, "sha256": io.sha256(folder / MANIFEST)}
    problems = []
    for line in crates.differences(stored, crates.crate_from_manifest(manifest, entry)):
        if line.startswith(f"'{MANIFEST}' differs"):
            problems.append(f"changed: {MANIFEST} (its SHA-256 or size differs from the one {CRATE} records)")
        else:
            problems.append(f"changed: {CRATE} ({line})")
    try:
        profile = crates.profile_problems(stored)
    except Exception as exc:  # the library's own refusals of a malformed crate, whatever their type
        return [*problems, f"changed: {CRATE} (the rocrate library cannot read it: {type(exc).__name__})"]
    return problems + [f"changed: {CRATE} (Workflow Run Crate: {line})" for line in profile]


def verify(folder: str | Path) -> list[str]:
    """One line per problem of an archive folder: a listed file missing, changed or not a
    regular file; a file nobody listed; the crate departing from the manifest or from the
    Workflow Run Crate's required points. A malformed manifest raises :class:`ArchiveError`.
    No path outside ``folder`` is opened."""
    folder = Path(folder)
    manifest = read_manifest(folder)
    entries = manifest["workflow"] + manifest["files"]
    problems = [p for p in (_file_problem(folder, entry) for entry in entries) if p]
    listed = {entry["name"] for entry in entries} | {MANIFEST, CRATE}
    problems += [f"unlisted: {name} (in the folder, not in {MANIFEST})" for name in sorted(_present(folder) - listed)]
    return problems + _crate_problems(folder, manifest)


def _scene(manifest: dict, folder: Path) -> dict:
    """The archived settings, checked as a scene; :class:`ArchiveError` if they are not one."""
    from rockdec.pipeline import config

    try:
        return config.validate_scene(copy.deepcopy(manifest["settings"]), manifest["scene"], source=folder / MANIFEST)
    except InputError as exc:
        raise ArchiveError(f"the settings in '{folder / MANIFEST}' are not a scene rockdec can run ({exc})") from None


def check_rebuild_target(folder: str | Path, out: str | Path, manifest: dict | None = None) -> Path:
    """``out`` as a :class:`~pathlib.Path` if :func:`rebuild` may make it: a new name (not an
    existing file, folder or symbolic link, a dangling one included) in an existing folder,
    outside the archive ``folder`` (a rebuild written into the archive would change what it
    verifies); given the ``manifest``, with room on its disk for the rebuilt files (their
    archived sizes). Else :class:`rockdec.io.OutputError` in one sentence naming the rebuild
    folder (not by a parameter: the command line gives it as ``verify --rebuild``).

    Parameters
    ----------
    folder : str or Path
        The archive folder.
    out : str or Path
        The folder the rebuild would make.
    manifest : dict, optional
        The archive's checked manifest (:func:`read_manifest`), for the space check.

    Returns
    -------
    Path
        ``out``.

    Raises
    ------
    rockdec.io.OutputError
        ``out`` exists, is a link, lies in a missing folder or inside the archive, or its
        disk has too little room.

    Examples
    --------
    >>> import tempfile
    >>> base = Path(tempfile.mkdtemp())
    >>> (base / "archive").mkdir()
    >>> check_rebuild_target(base / "archive", base / "rebuilt") == base / "rebuilt"
    True
    >>> check_rebuild_target(base / "archive", base / "archive" / "rebuilt")
    Traceback (most recent call last):
    ...
    rockdec.io.OutputError: the rebuild folder '...rebuilt' lies inside the archive '...archive' it rebuilds from; choose a folder outside it.
    """
    folder, out = Path(folder), Path(out)
    if os.path.islink(out):
        target = os.readlink(out)
        state = "which does not exist" if not out.exists() else "which exists"
        raise io.OutputError(f"the rebuild folder '{out}' is a symbolic link (to '{target}', {state}); give a new folder name for the rebuild.")
    if out.exists():
        raise io.OutputError(f"the rebuild folder '{out}' exists already; remove it or choose another folder.")
    if not out.parent.is_dir():
        raise io.OutputError(f"the rebuild folder '{out}': its folder '{out.parent}' does not exist; create it first.")
    inside = out.parent.resolve() / out.name
    home = folder.resolve()
    if inside == home or home in inside.parents:
        raise io.OutputError(f"the rebuild folder '{out}' lies inside the archive '{folder}' it rebuilds from; choose a folder outside it.")
    if manifest is not None:
        rebuilt = {"estimates.nc", "table.csv", "table.md", "estimates_readings.nc", "table_readings.csv", "table_readings.md"}
        need = sum(e["size"] for e in manifest["files"] if e["name"] in rebuilt or e["name"].startswith("figures/"))
        free = shutil.disk_usage(out.parent).free
        if need > free:
            raise io.OutputError(
                f"the rebuild folder '{out}': the rebuild writes about {need / 1e6:.3g} MB, more than the {free / 1e6:.3g} MB free in "
                f"'{out.parent}'; free some space or choose another folder."
            )
    return out


def rebuild(folder: str | Path, out: str | Path) -> dict[str, bool]:
    """Remake the tables and figures of an archive in the new folder ``out``.

    The steps after the simulation run again on the archived files through the functions
    the workflow's rules call (:mod:`rockdec.pipeline.steps`): rule ``estimates`` on
    ``signatures.nc``, rule ``table_readings`` on ``readings.nc`` when the archive holds its
    table, and every figure rule the archive holds the inputs of. The work goes to a hidden
    folder beside ``out``, renamed to ``out`` only when complete and removed on failure.
    Returns, for each rebuilt table and NetCDF file, whether it equals the archived one
    (tables byte for byte, NetCDF files by :func:`same_data`).
    """
    from rockdec.pipeline import steps

    folder, out = Path(folder), Path(out)
    check_rebuild_target(folder, out)
    manifest = read_manifest(folder)
    check_rebuild_target(folder, out, manifest)
    scene = _scene(manifest, folder)
    names = {entry["name"] for entry in manifest["files"]}
    for needed in ("signatures.nc", "readings.nc") if "estimates_readings.nc" in names else ("signatures.nc",):
        if needed not in names:
            raise ArchiveError(f"'{folder}' holds no {needed}, which the rebuild starts from; pass a folder rule `archive` wrote.")
    try:
        work = out.parent / f".{out.name}.{secrets.token_hex(6)}.partial"
        work.mkdir()  # mode 0777 less the umask, as the folder it becomes (mkdtemp would make it 0700)
    except OSError as exc:
        raise io.OutputError(f"--rebuild '{out}': cannot write in '{out.parent}' ({exc.strerror}); choose another folder.") from None
    try:
        rebuilt = ["estimates.nc", "table.csv", "table.md"]
        steps.estimates(folder / "signatures.nc", *(work / name for name in rebuilt), scene["estimates"])
        if "estimates_readings.nc" in names:
            readings = ["estimates_readings.nc", "table_readings.csv", "table_readings.md"]
            steps.table_readings(folder / "readings.nc", *(work / name for name in readings), scene["estimates"]["weights"])
            rebuilt += readings
        (work / "figures").mkdir()

        def outputs(name):
            return [work / "figures" / f"{name}.png", work / "figures" / f"{name}.pdf"]

        steps.fig1b(outputs("fig1b"))
        steps.fig3(work / "estimates.nc", outputs("fig3"))
        steps.fig4(work / "estimates.nc", outputs("fig4"))
        steps.fig_ev(folder / "signatures.nc", work / "estimates.nc", outputs("fig_ev"))
        if {"stored_series.nc", "stored_signature.nc"} <= names:
            steps.fig2(folder / "stored_series.nc", folder / "stored_signature.nc", outputs("fig2"))
        same = {name: name in names and _same(work / name, folder / name) for name in rebuilt}
        if os.path.lexists(out):
            raise io.OutputError(f"--rebuild '{out}' appeared while rebuilding; remove it or choose another folder.")
        os.rename(work, out)
    except OSError as exc:
        shutil.rmtree(work, ignore_errors=True)
        full = exc.errno in (errno.ENOSPC, errno.EDQUOT)
        raise io.OutputError(
            f"the rebuild folder '{out}': " + ("the disk filled while rebuilding" if full else f"the rebuild could not write ({exc.strerror})")
            + "; free some space or choose another folder."
        ) from None
    except BaseException:
        shutil.rmtree(work, ignore_errors=True)
        raise
    return same


def _same(a: Path, b: Path) -> bool:
    return same_data(a, b) if a.suffix == ".nc" else a.read_bytes() == b.read_bytes()


def same_data(a: str | Path, b: str | Path) -> bool:
    """Whether two NetCDF files hold the same variables, dimensions and values (attributes,
    such as ``history`` and its dates, are ignored)."""
    with io.open_dataset(a) as x, io.open_dataset(b) as y:
        return set(x.variables) == set(y.variables) and all(
            x[name].dims == y[name].dims and x[name].equals(y[name]) for name in x.variables
        )

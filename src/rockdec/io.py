"""NetCDF encoding, CF-style attributes and provenance.

Every product is written through :func:`write_netcdf`: to a temporary file beside the
target, renamed into place only when complete, so a failed run leaves no partial file,
and an existing file is never replaced unless the caller says so. The temporary file is
made with mode 0666 less the umask, as any file the user creates, so a product is as
readable as the user's umask says (0644 under umask 022). Each run's temporary
file has a name of its own, so runs writing different outputs never touch each other's;
a run claims its output with a lock file made exclusively (``O_EXCL``) beside it, so a
second run on the same output refuses at once instead of racing the first.
"""

from __future__ import annotations

import contextlib
import datetime as _dt
import errno
import hashlib
import json
import os
import secrets
import shutil
import subprocess
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from rockdec import locks
from rockdec._version import __version__
from rockdec.validate import InputError, file_kind, path_name

if TYPE_CHECKING:  # annotations only: xarray loads where a function needs it
    import xarray as xr

__all__ = [
    "OutputError", "PAPER_TITLE", "TITLES", "check_output", "claimed", "git_commit", "git_dirty",
    "open_dataset", "provenance", "sha256", "write_claimed", "write_netcdf",
]

#: Largest magnitude a float32 variable can store without becoming inf.
FLOAT32_MAX = float(np.finfo(np.float32).max)

#: Free space below which a failed write is reported as a full disk (HDF5 hides the errno).
DISK_FULL_BYTES = 2**20


class OutputError(InputError):
    """An output path the user can fix (exists already, folder missing or not writable, disk full)."""


def sha256(path: str | Path) -> str:
    """Hex SHA-256 of a regular file, read in 1 MiB blocks (a symbolic link is refused, not followed)."""
    digest = hashlib.sha256()
    with os.fdopen(os.open(path, os.O_RDONLY | os.O_NOFOLLOW), "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _git(*args: str, cwd: Path) -> str | None:
    """The stdout of ``git args`` run in ``cwd``, stripped; ``None`` when git fails or is absent."""
    try:
        out = subprocess.run(["git", *args], cwd=cwd, capture_output=True, text=True, timeout=10)
    except (OSError, subprocess.TimeoutExpired):
        return None
    return out.stdout.strip() if out.returncode == 0 else None


def source_repository() -> Path | None:
    """The git work tree this package's own source belongs to, or ``None``.

    Only a checkout of rockdec counts: its top level holds ``pyproject.toml`` and this very
    package as ``src/rockdec``. An installed copy inside some other repository (a
    virtualenv in a project's folder) is not that repository's source, so it has none.
    """
    package = Path(__file__).resolve().parent
    top = _git("rev-parse", "--show-toplevel", cwd=package)
    if top is None:
        return None
    top = Path(top)
    source = top / "src" / "rockdec"
    if not (top / "pyproject.toml").is_file() or not source.is_dir() or not source.samefile(package):
        return None
    return top


def git_commit() -> str:
    """The git commit of the rockdec checkout this package runs from
    (:func:`source_repository`), or ``"unknown"`` (an installed package, no git)."""
    top = source_repository()
    commit = _git("rev-parse", "HEAD", cwd=top) if top is not None else None
    return commit or "unknown"


def git_dirty() -> bool | None:
    """Whether the rockdec checkout this package runs from has uncommitted changes;
    ``None`` outside such a checkout (:func:`source_repository`)."""
    top = source_repository()
    status = _git("status", "--porcelain", cwd=top) if top is not None else None
    return None if status is None else bool(status)


#: The ``title`` of each product, by the step that writes it (CF 1.10 section 2.6.2).
TITLES = {
    "simulate": "Random rocking response of a rigid block, simulated exactly (paper eqs. 21-24)",
    "stored_series": "Random rocking response of a rigid block, simulated exactly (paper eqs. 21-24): the stored series",
    "signatures": "Random Decrement signatures D_a and D_v of the rocking response (paper eqs. 8, 19)",
    "signature_part": "Random Decrement signatures D_a and D_v of the rocking response (paper eqs. 8, 19), one job's replicates",
    "stored_signature": "Random Decrement signatures of the stored series, pooled (paper fig. 2c)",
    "estimates": "Coefficient of restitution per replicate and window, extrapolated to zero window (paper eqs. 25-27)",
    "readings": "Coefficient of restitution against the window size under each reading of the paper's sizes (paper eq. 27, section 5)",
    "table_readings": "Coefficient of restitution under every reading of the paper's sizes",
    "choices": "Coefficient of restitution with one analysis choice changed at a time",
    "amplitude": "Simplified (eq. 4) and linearized Housner (eq. 2) models over sigma_Y/theta_cr",
    "tradeoff": "Cost and accuracy of each estimator configuration",
    "series": "Every simulated series of one replicate (paper eqs. 21-24)",
    "calibration": "Raw estimates of e on simulated record sets at known e (calibration of rockdec estimate)",
    "coverage": "Coverage of the 95 % interval of rockdec estimate on simulated records of known e",
}

#: The title of the paper rockdec reproduces (the copy we have names no authors or venue).
PAPER_TITLE = "Estimation of the Coefficient of Restitution of Rocking Systems by the Random Decrement Technique"

#: What every product cites for its method (CF attribute ``references``).
REFERENCES = f"{PAPER_TITLE}; the method as implemented: docs/method.md of rockdec"


def input_history(paths) -> list[str]:
    """The ``history`` lines of the NetCDF files among ``paths``, oldest first, each line once
    (other inputs, such as a run's JSON file, have none), read holding :data:`rockdec.locks.HDF5`."""
    lines: list[str] = []
    for path in paths:
        if Path(path).suffix != ".nc":
            continue
        with locks.HDF5, open_dataset(path) as ds:  # a step beside it may be writing (in_snakemake's threads)
            text = str(ds.attrs.get("history", ""))
        lines += [line for line in text.splitlines() if line.strip() and line not in lines]
    return lines


def provenance(step: str, settings: dict | None = None, inputs=()) -> dict:
    """Global attributes every product carries (CF 1.10 section 2.6.2, and where it came from).

    ``title`` (:data:`TITLES`), ``references``, package version and commit; ``history``
    appended, never overwritten: the history lines of every input file
    (:func:`input_history`), then this step's line ``<UTC time>: rockdec <version> <step>
    <inputs>``; ``source_files``: the input files (``inputs``, paths as given), one a line,
    when there are any. Python sources among ``inputs`` (a rule's code inputs,
    :func:`rockdec.sources.package_sources`) are left out: the version and commit name the code.
    """
    now = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    inputs = [str(path) for path in inputs if not str(path).endswith(".py")]
    line = " ".join([f"{now}: rockdec {__version__} {step}", *inputs])
    attrs = {
        "Conventions": "CF-1.10",
        "title": TITLES.get(step, f"rockdec {step}"),
        "references": REFERENCES,
        "rockdec_version": __version__,
        "git_commit": git_commit(),
        "history": "\n".join([*input_history(inputs), line]),
    }
    if inputs:
        attrs["source_files"] = "\n".join(inputs)
    if settings is not None:
        attrs["settings"] = json.dumps(settings, sort_keys=True)
    return attrs


def check_output(path: str | Path, overwrite: bool = False) -> Path:
    """Check before any work that ``path`` can be written; raise :class:`OutputError` if not."""
    path = path_name(path, "output")
    if path.is_dir():
        raise OutputError(f"output '{path}' is a folder; give a file name such as '{path / 'out.nc'}'.")
    if (path.exists() or path.is_symlink()) and not overwrite:
        raise OutputError(f"output '{path}' exists already; remove it or pass `overwrite`.")
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise OutputError(f"output folder '{folder}' does not exist; create it first.")
    if not os.access(folder, os.W_OK):
        raise OutputError(f"output folder '{folder}' is not writable; choose another output file.")
    if _live_owner(_lock_path(path)) is not None:
        raise _busy(path)
    return path


def _lock_path(path: Path) -> Path:
    return path.with_name(f".{path.name}.lock")


def _busy(path: Path) -> OutputError:
    return OutputError(
        f"output '{path}' is being written by another run (lock '{_lock_path(path)}'); "
        "wait for it to finish or choose another output file."
    )


def _live_owner(lock: Path) -> int | None:
    """The process id in ``lock`` if that process still runs on this machine, else ``None``."""
    try:
        pid = int(lock.read_text().strip() or 0)
    except (OSError, ValueError):
        return None
    if pid <= 0:
        return None
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return None
    except PermissionError:  # someone else's process
        return pid
    return pid


#: What ``os.link`` raises on a file system that keeps no hard links.
_NO_HARD_LINKS = (errno.EPERM, errno.ENOTSUP, errno.EOPNOTSUPP, errno.EXDEV, errno.EMLINK)


def _place(mine: Path, lock: Path, owner: str) -> None:
    """Give ``lock`` the content of ``mine`` at once (a hard link); on a file system without
    hard links, create it exclusively and write ``owner`` into it. Raises
    :class:`FileExistsError` if ``lock`` exists."""
    try:
        os.link(mine, lock)
    except OSError as exc:
        if exc.errno not in _NO_HARD_LINKS:  # FileExistsError among them
            raise
        fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        try:
            os.write(fd, owner.encode())
        except OSError:
            lock.unlink(missing_ok=True)  # a lock without its owner would read as stale
            raise
        finally:
            os.close(fd)


@contextlib.contextmanager
def _claim(path: Path):
    """Hold the lock file of ``path`` while writing it.

    The lock appears with its owner's process id already in it (:func:`_place`: the id is
    written to a file of this claim's own and hard-linked to the lock's name, which fails if
    the lock exists), so no other run reads an empty lock and takes it for a stale one. A lock
    left by a run that was killed (its process is gone) is taken over, and that run's
    temporary files are removed.
    """
    lock = _lock_path(path)
    owner = f"{os.getpid()}\n"
    try:
        mine = _new_partial(lock)
    except OSError as exc:
        raise _write_failure(exc, path) from None
    try:
        mine.write_text(owner)
        for attempt in range(2):
            try:
                _place(mine, lock, owner)
                break
            except FileExistsError:
                if attempt or _live_owner(lock) is not None:
                    raise _busy(path) from None
                for stale in path.parent.glob(f".{path.name}.*.partial*"):
                    stale.unlink(missing_ok=True)
                lock.unlink(missing_ok=True)
    except OSError as exc:  # a full disk, a file size limit: the claim's own files go with it
        raise _write_failure(exc, path) from None
    finally:
        mine.unlink(missing_ok=True)
    try:
        yield
    finally:
        lock.unlink(missing_ok=True)


def write_netcdf(
    ds: xr.Dataset, path: str | Path, *, float32: tuple[str, ...] = (), overwrite: bool = False, chunks: dict | None = None
) -> Path:
    """Write ``ds`` compressed (zlib level 4) to ``path`` atomically.

    Variables named in ``float32`` are stored as float32 (the simulated series); the rest
    keep their dtype. ``chunks`` (dimension -> length) sets the on-disk chunks of every
    variable along those dimensions (whole length along the others). Dask-backed
    variables are computed chunk by chunk while writing.
    """
    with claimed(path, overwrite) as path:
        encoding, excess = {}, []
        for name, var in ds.data_vars.items():
            enc = {"zlib": True, "complevel": 4}
            if name in float32:
                enc["dtype"] = "float32"
                ds = ds.assign({name: var.copy(data=_fits_float32(var.data, name, excess))})
            if var.ndim >= 1 and var.dtype.kind == "f":
                enc["_FillValue"] = float("nan")
            if chunks and var.ndim >= 1:
                enc["chunksizes"] = tuple(max(1, min(chunks.get(dim, size), size)) for dim, size in var.sizes.items())
            encoding[name] = enc
        encoding.update(coordinate_encoding(ds))

        def write(tmp):
            ds.to_netcdf(tmp, encoding=encoding, engine="netcdf4")
            if excess:  # raised once every chunk is written: no task still holds the file
                raise excess[0]

        return write_claimed(path, write, overwrite)


def _write_failure(exc: BaseException, path: Path) -> BaseException:
    """The one-sentence error of a failed write (full disk, file size limit), else ``exc``
    itself (HDF5 hides the errno, so the disk and the limit are looked at)."""
    import resource

    code = getattr(exc, "errno", None)
    limit = resource.getrlimit(resource.RLIMIT_FSIZE)[0]
    if limit != resource.RLIM_INFINITY and (code == errno.EFBIG or code is None):
        return OutputError(
            f"the file size limit of this shell (ulimit -f, {limit} bytes) stopped the write of '{path}'; "
            "raise the limit or write a smaller output."
        )
    if code == errno.EFBIG:
        return OutputError(f"'{path}' grew beyond the largest file its disk stores; write a smaller output.")
    if code in (errno.ENOSPC, errno.EDQUOT) or shutil.disk_usage(path.parent).free < DISK_FULL_BYTES:
        return OutputError(f"no space left on the disk of '{path}' while writing it; free some space or choose another output file.")
    return exc


@contextlib.contextmanager
def claimed(path: str | Path, overwrite: bool = False):
    """Check ``path`` (:func:`check_output`) and hold its lock for the whole block, so that a
    second run on the same output refuses at once; yields the path to give
    :func:`write_claimed` at the end."""
    path = check_output(path, overwrite)
    with _claim(path):
        yield path


def write_claimed(path: Path, write, overwrite: bool = False, keep_suffix: bool = False) -> Path:
    """Write ``path`` (claimed with :func:`claimed`) atomically: ``write(tmp)`` fills a
    temporary file ``.<name>.<random>.partial`` beside it (ending in ``path``'s suffix too
    with ``keep_suffix``, for writers that pick the format by it), given the name ``path``
    when complete: renamed over it with ``overwrite``, else only if nothing took the name
    meanwhile (:func:`_place_new`). A symlink at ``path`` is replaced itself (with
    ``overwrite``), never written through."""
    try:
        tmp = _new_partial(path, path.suffix if keep_suffix else "")
    except OSError as exc:
        raise _write_failure(exc, path) from None
    try:
        write(tmp)
        if overwrite:
            os.replace(tmp, path)
        else:
            _place_new(tmp, path)
    except (OSError, RuntimeError) as exc:
        raise _write_failure(exc, path) from None
    finally:
        tmp.unlink(missing_ok=True)
    return path


def _place_new(tmp: Path, path: Path) -> None:
    """Give the complete file ``tmp`` the name ``path`` unless something holds that name:
    a hard link fails on an existing name in one step, so a file made meanwhile by a writer
    that takes no lock is never replaced; file systems without hard links check, then rename."""
    appeared = OutputError(f"output '{path}' appeared while this run wrote it; remove it or pass `overwrite`.")
    try:
        os.link(tmp, path, follow_symlinks=False)
    except FileExistsError:
        raise appeared from None
    except OSError as exc:
        if exc.errno not in _NO_HARD_LINKS:
            raise
        if path.exists() or path.is_symlink():
            raise appeared from None
        os.replace(tmp, path)


def coordinate_encoding(ds: xr.Dataset) -> dict:
    """How each coordinate of ``ds`` is stored: without a fill value (CF 2.5.1: no missing
    values in coordinates); labels (``estimator``, ``trigger``, ``reading``, ...) as
    character arrays (CF 2.2), ``trigger(trigger, string1)``.

    A label coordinate stored as a variable-length string would be a one-dimensional
    coordinate variable of strings, which CF requires to be numeric and monotonic (the CF
    checker's monotonicity check raises on it). Stored as characters it is a label
    variable, and xarray reads it back as the same string index, so ``.sel(trigger="a")``
    works on the file as written.
    """
    encoding = {}
    for name, coord in ds.coords.items():
        encoding[name] = {"_FillValue": None}
        if coord.dtype.kind in "OUST":  # object, unicode, bytes, NumPy StringDType (pandas 3 string indexes)
            encoding[name]["dtype"] = "S1"
    return encoding


def _new_partial(path: Path, suffix: str = "") -> Path:
    """A new empty file ``.<name>.<random>.partial<suffix>`` beside ``path``, made
    exclusively with mode 0666 less the umask (a writer that fills it keeps that mode)."""
    while True:
        tmp = path.with_name(f".{path.name}.{secrets.token_hex(6)}.partial{suffix}")
        try:
            os.close(os.open(tmp, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o666))
            return tmp
        except FileExistsError:
            continue


def _fits_float32(data, name: str, excess: list):
    """``data``, checked to stay within the float32 range: at once if in memory (raising),
    chunk by chunk while writing if lazy, where a chunk beyond the range is noted in
    ``excess`` (raising inside a Dask task would end the write while other tasks still
    write, and one of them would reopen, so recreate, the removed temporary file)."""

    def check(block):
        big = np.abs(block) > FLOAT32_MAX  # NaN (a fallen block) is stored as NaN: not refused
        if np.any(big):
            return OutputError(
                f"'{name}' reaches {np.abs(block[big]).max():.3g}, beyond the float32 range it is stored in "
                f"({FLOAT32_MAX:.3g}); choose smaller scales (initial state, sigma_p, dt)."
            )
        return None

    def noted(block):
        found = check(block)
        if found is None:
            return block
        excess.append(found)
        return np.full_like(block, np.nan)  # written as NaN (no overflowing cast), then the file is removed

    if hasattr(data, "map_blocks"):
        return data.map_blocks(noted, dtype=data.dtype)
    found = check(np.asarray(data))
    if found is not None:
        raise found
    return np.asarray(data)


def open_dataset(path: str | Path, **kwargs) -> xr.Dataset:
    """Open a rockdec NetCDF file with a clear error when it is missing or not NetCDF."""
    import xarray as xr

    path = Path(path)
    kind = file_kind(path)
    if kind is not None:
        raise OutputError(f"input '{path}' is {kind}, not a NetCDF file; give the file.")
    if not path.is_file():
        raise OutputError(f"input '{path}' does not exist; run the step that makes it first.")
    try:
        return xr.open_dataset(path, engine="netcdf4", **kwargs)
    except (OSError, ValueError) as exc:
        raise OutputError(f"input '{path}' is not a readable NetCDF file ({exc}).") from None

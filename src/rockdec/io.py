"""NetCDF encoding, CF-style attributes and provenance.

Every product is written through :func:`write_netcdf`: to a temporary file beside the
target, renamed into place only when complete, so a failed run leaves no partial file,
and an existing file is never replaced unless the caller says so.
"""

from __future__ import annotations

import datetime as _dt
import json
import os
import subprocess
from pathlib import Path

import xarray as xr

from rockdec import __version__


class OutputError(ValueError):
    """An output path the user can fix (exists already, folder missing or not writable)."""


def git_commit() -> str:
    """The git commit of the source tree this package runs from, or ``"unknown"``."""
    try:
        out = subprocess.run(
            ["git", "rev-parse", "HEAD"], cwd=Path(__file__).parent, capture_output=True, text=True, timeout=5
        )
    except (OSError, subprocess.TimeoutExpired):
        return "unknown"
    return out.stdout.strip() if out.returncode == 0 else "unknown"


def provenance(step: str, settings: dict | None = None) -> dict:
    """Global attributes every product carries: package version, commit, history line."""
    now = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    attrs = {
        "Conventions": "CF-1.10",
        "rockdec_version": __version__,
        "git_commit": git_commit(),
        "history": f"{now}: rockdec {__version__} {step}",
    }
    if settings is not None:
        attrs["settings"] = json.dumps(settings, sort_keys=True)
    return attrs


def check_output(path: str | Path, overwrite: bool = False) -> Path:
    """Check before any work that ``path`` can be written; raise :class:`OutputError` if not."""
    path = Path(path)
    if path.exists() and not overwrite:
        raise OutputError(f"output '{path}' exists already; remove it or pass --overwrite.")
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise OutputError(f"output folder '{folder}' does not exist; create it first.")
    if not os.access(folder, os.W_OK):
        raise OutputError(f"output folder '{folder}' is not writable; choose another --out.")
    return path


def write_netcdf(
    ds: xr.Dataset, path: str | Path, *, float32: tuple[str, ...] = (), overwrite: bool = False, chunks: dict | None = None
) -> Path:
    """Write ``ds`` compressed (zlib level 4) to ``path`` atomically.

    Variables named in ``float32`` are stored as float32 (the simulated series); the rest
    keep their dtype. ``chunks`` (dimension -> length) sets the on-disk chunks of every
    variable along those dimensions (whole length along the others). Dask-backed
    variables are computed chunk by chunk while writing.
    """
    path = check_output(path, overwrite)
    encoding = {}
    for name, var in ds.data_vars.items():
        enc = {"zlib": True, "complevel": 4}
        if name in float32:
            enc["dtype"] = "float32"
        if var.ndim >= 1 and var.dtype.kind == "f":
            enc["_FillValue"] = float("nan")
        if chunks and var.ndim >= 1:
            enc["chunksizes"] = tuple(max(1, min(chunks.get(dim, size), size)) for dim, size in var.sizes.items())
        encoding[name] = enc
    tmp = path.with_name(f".{path.name}.partial")
    try:
        ds.to_netcdf(tmp, encoding=encoding, engine="netcdf4")
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
    return path


def open_dataset(path: str | Path, **kwargs) -> xr.Dataset:
    """Open a rockdec NetCDF file with a clear error when it is missing or not NetCDF."""
    path = Path(path)
    if not path.is_file():
        raise OutputError(f"input '{path}' does not exist; run the step that makes it first.")
    try:
        return xr.open_dataset(path, engine="netcdf4", **kwargs)
    except (OSError, ValueError) as exc:
        raise OutputError(f"input '{path}' is not a readable NetCDF file ({exc}).") from None

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


#: The ``title`` of each product, by the step that writes it (CF 1.10 section 2.6.2).
TITLES = {
    "simulate": "Random rocking response of a rigid block, simulated exactly (paper eqs. 21-24)",
    "signatures": "Random Decrement signatures D_a and D_v of the rocking response (paper eqs. 8, 19)",
    "stored_signature": "Random Decrement signatures of the stored series, pooled (paper fig. 2c)",
    "estimates": "Coefficient of restitution per replicate and window, extrapolated to zero window (paper eqs. 25-27)",
    "readings": "Coefficient of restitution under the other readings of the paper's sizes",
    "table_readings": "Coefficient of restitution under every reading of the paper's sizes",
    "choices": "Coefficient of restitution with one analysis choice changed at a time",
    "amplitude": "Simplified (eq. 4) and linearized Housner (eq. 2) models over sigma_Y/theta_cr",
    "tradeoff": "Cost and accuracy of each estimator configuration",
}

#: What every product cites for its method (CF attribute ``references``).
REFERENCES = (
    "Estimation of the Coefficient of Restitution of Rocking Systems by the Random Decrement "
    "Technique; the method as implemented: docs/method.md of rockdec"
)


def input_history(paths) -> list[str]:
    """The ``history`` lines of the NetCDF files ``paths``, oldest first, each line once."""
    lines: list[str] = []
    for path in paths:
        with open_dataset(path) as ds:
            text = str(ds.attrs.get("history", ""))
        lines += [line for line in text.splitlines() if line.strip() and line not in lines]
    return lines


def provenance(step: str, settings: dict | None = None, inputs=()) -> dict:
    """Global attributes every product carries (CF 1.10 section 2.6.2, and where it came from).

    ``title`` (:data:`TITLES`), ``references``, package version and commit; ``history``
    appended, never overwritten: the history lines of every input file
    (:func:`input_history`), then this step's line ``<UTC time>: rockdec <version> <step>
    <inputs>``; ``source_files``: the input files (``inputs``, paths as given), one a line,
    when there are any.
    """
    now = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    inputs = [str(path) for path in inputs]
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
    path = Path(path)
    if path.exists() and not overwrite:
        raise OutputError(f"output '{path}' exists already; remove it or pass --overwrite.")
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise OutputError(f"output folder '{folder}' does not exist; create it first.")
    if not os.access(folder, os.W_OK):
        raise OutputError(f"output folder '{folder}' is not writable; choose another --out.")
    return path


def write_netcdf(ds: xr.Dataset, path: str | Path, *, float32: tuple[str, ...] = (), overwrite: bool = False) -> Path:
    """Write ``ds`` compressed (zlib level 4) to ``path`` atomically.

    Variables named in ``float32`` are stored as float32 (the simulated series); the rest
    keep their dtype. Dask-backed variables are computed chunk by chunk while writing.
    """
    path = check_output(path, overwrite)
    encoding = {}
    for name, var in ds.data_vars.items():
        enc = {"zlib": True, "complevel": 4}
        if name in float32:
            enc["dtype"] = "float32"
        if var.ndim >= 1 and var.dtype.kind == "f":
            enc["_FillValue"] = float("nan")
        encoding[name] = enc
    for name in ds.coords:
        encoding[name] = {"_FillValue": None}  # CF 2.5.1: no missing values in coordinates
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

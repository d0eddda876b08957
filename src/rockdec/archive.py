"""Archives a reader can verify: the NetCDF files behind a scene's tables and figures.

:func:`write_archive` (rule ``archive``) copies every NetCDF file that a scene's tables and
figures are made from, and the tables themselves, into one folder with a
``manifest.json``: per file its name, size in bytes, SHA-256 and the rule that made it,
plus the scene's settings, the versions of the packages that ran, the git commit and
whether the source tree held uncommitted changes. :func:`verify` re-checks the
checksums; :func:`rebuild` redraws the tables and figures from the archive alone, with
the functions the workflow's rules call, and no simulation.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

from rockdec import io

MANIFEST = "manifest.json"

PACKAGES = ("rockdec", "numpy", "xarray", "netCDF4", "numba", "dask", "snakemake")
"""Packages whose versions a manifest records."""


def sha256(path: str | Path) -> str:
    """Hex SHA-256 of a file, read in 1 MiB blocks."""
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def package_versions() -> dict[str, str]:
    """Installed version of each of :data:`PACKAGES` (``"not installed"`` if absent)."""
    out = {}
    for name in PACKAGES:
        try:
            out[name] = version(name)
        except PackageNotFoundError:
            out[name] = "not installed"
    return out


def write_archive(folder: str | Path, results: str | Path, producers: dict[str, str], scene_name: str, scene: dict) -> Path:
    """Copy the files ``producers`` names (paths relative to ``results``) into ``folder`` with a manifest.

    ``producers`` maps each file to the rule that wrote it. Returns the manifest's path.
    """
    folder, results = Path(folder), Path(results)
    entries = []
    for name, rule in producers.items():
        target = folder / name
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(results / name, target)
        entries.append({"name": name, "size": target.stat().st_size, "sha256": sha256(target), "rule": rule})
    manifest = {
        "scene": scene_name,
        "settings": scene,
        "versions": package_versions(),
        "git_commit": io.git_commit(),
        "git_dirty": io.git_dirty(),
        "files": entries,
    }
    path = folder / MANIFEST
    tmp = folder / f".{MANIFEST}.partial"
    tmp.write_text(json.dumps(manifest, indent=2) + "\n")
    os.replace(tmp, path)
    return path


def read_manifest(folder: str | Path) -> dict:
    """The manifest of an archive folder; :class:`rockdec.io.OutputError` if there is none."""
    path = Path(folder) / MANIFEST
    if not path.is_file():
        raise io.OutputError(f"'{folder}' holds no {MANIFEST}: pass the folder rule `archive` wrote (results/<scene>/archive).")
    try:
        return json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        raise io.OutputError(f"'{path}' is not valid JSON ({exc}); the manifest itself was changed.") from None


def verify(folder: str | Path) -> list[str]:
    """One line per file of the manifest that is missing or whose size or SHA-256 changed."""
    folder = Path(folder)
    problems = []
    for entry in read_manifest(folder)["files"]:
        path = folder / entry["name"]
        if not path.is_file():
            problems.append(f"missing: {entry['name']}")
        elif path.stat().st_size != entry["size"] or sha256(path) != entry["sha256"]:
            problems.append(f"changed: {entry['name']} (SHA-256 differs from the manifest)")
    return problems


def rebuild(folder: str | Path, out: str | Path) -> dict[str, bool]:
    """Remake the tables and figures of an archive in ``out`` (an existing, empty folder).

    The steps after the simulation run again on the archived files, through files as in
    the workflow and with the functions its rules call: rule ``estimates`` on
    ``signatures.nc`` (:func:`rockdec.replicates.scene_estimates`), rule
    ``table_readings`` on ``readings.nc`` when the scene compares readings
    (:func:`rockdec.replicates.readings_estimates`), and every figure rule the archive
    holds the inputs of. Returns, for each rebuilt table and NetCDF file, whether it
    equals the archived one (tables byte for byte, NetCDF files by :func:`same_data`).
    """
    from rockdec import figures, replicates, tables  # matplotlib and numba: only when rebuilding

    folder, out = Path(folder), Path(out)
    manifest = read_manifest(folder)
    scene = manifest["settings"]
    names = {entry["name"] for entry in manifest["files"]}
    with io.open_dataset(folder / "signatures.nc") as sig_file:
        sig = sig_file.load()
    est, table = replicates.scene_estimates(sig, scene["estimates"])
    est.attrs.update(io.provenance("estimates", scene["estimates"]))
    io.write_netcdf(est, out / "estimates.nc")
    tables.write_table(table, out / "table.csv", out / "table.md")
    rebuilt = ["estimates.nc", "table.csv", "table.md"]
    with io.open_dataset(out / "estimates.nc") as est_file:
        est = est_file.load()
    e_target = float(est.attrs["e_target"])
    if "estimates_readings.nc" in names:
        with io.open_dataset(folder / "readings.nc") as curves:
            combined, table = replicates.readings_estimates(curves.load(), scene["estimates"]["weights"])
        combined.attrs.update(io.provenance("table_readings", {"weights": scene["estimates"]["weights"]}))
        io.write_netcdf(combined, out / "estimates_readings.nc")
        tables.write_table(table, out / "table_readings.csv", out / "table_readings.md")
        rebuilt += ["estimates_readings.nc", "table_readings.csv", "table_readings.md"]
    drawn = {
        "fig1b": figures.fig1b(),
        "fig3": figures.fig3(est, e_target=e_target),
        "fig4": figures.fig4(est, e_target=e_target),
        "fig_ev": figures.fig_ev(sig, est, e_target=e_target),
    }
    if "stored_signature.nc" in names:
        with io.open_dataset(folder / "stored_series.nc") as sim, io.open_dataset(folder / "stored_signature.nc") as stored:
            drawn["fig2"] = figures.fig2(sim.load(), stored.load())
    (out / "figures").mkdir()
    for name, fig in drawn.items():
        figures.save(fig, [out / "figures" / f"{name}.png", out / "figures" / f"{name}.pdf"])
    return {name: name in names and _same(out / name, folder / name) for name in rebuilt}


def _same(a: Path, b: Path) -> bool:
    return same_data(a, b) if a.suffix == ".nc" else a.read_bytes() == b.read_bytes()


def same_data(a: str | Path, b: str | Path) -> bool:
    """Whether two NetCDF files hold the same variables, dimensions and values (attributes,
    such as ``history`` and its dates, are ignored)."""
    with io.open_dataset(a) as x, io.open_dataset(b) as y:
        return set(x.variables) == set(y.variables) and all(
            x[name].dims == y[name].dims and x[name].equals(y[name]) for name in x.variables
        )

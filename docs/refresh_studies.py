"""Refresh the study tables and figures the docs include, from the files the workflow writes.

    python docs/refresh_studies.py            # copy what results/ holds now
    python docs/refresh_studies.py --run paper  # first run the workflow's targets of these studies

Every table the docs quote is a file a workflow rule writes under ``results/``; this script
copies it to ``docs/generated/studies/<study>.md`` with a first line that says which file,
which commit made it (the ``git_commit`` attribute of the NetCDF product beside it, else the
checkout's commit) and when, and copies the figures to ``docs/generated/figures/``. The docs
pages ``{include}`` those files, so no study number is typed into the prose. A study whose
results are absent keeps its last generated file. ``--run`` takes the studies to run first
(``paper``, ``choices``, ``diagnostics``, ``amplitude``, ``tradeoff``, ``coverage``,
``coverage_fresh``, ``shake``; ``all``); the coverage and warnings' studies take hours on 2 cores, in
jobs per cell or per ``e``, load and noise level that are kept as they finish (run again to go on).
"""

from __future__ import annotations

import argparse
import datetime as dt
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "generated"

# study: (its Snakemake target, the table it writes, a NetCDF product that carries its commit)
STUDIES = {
    "paper": ("results/paper/table.md", "results/paper/table.md", "results/paper/estimates.nc"),
    "readings": ("results/paper/table_readings.md", "results/paper/table_readings.md", "results/paper/estimates_readings.nc"),
    "choices": ("results/paper/table_choices.md", "results/paper/table_choices.md", "results/paper/estimates.nc"),
    "diagnostics": ("diagnostics", "results/studies/diagnostics/table.md", None),
    "amplitude": ("amplitude_study", "results/studies/amplitude/table.md", None),
    "tradeoff": ("tradeoff_study", "results/studies/tradeoff/table.md", None),
    "coverage": ("coverage", "results/studies/coverage/table.md", None),
    "coverage_fresh": ("coverage_fresh_table", "results/studies/coverage/fresh/table.md", None),
    "shake": ("shake_coverage", "results/studies/shake_coverage/table.md", None),
}
FIGURES = {
    "results/paper/figures": ["fig1b.png", "fig2.png", "fig3.png", "fig4.png", "fig_ev.png"],
    "results/studies/amplitude/figures": ["amplitude.png"],
    "results/studies/coverage": ["coverage.png"],
}
# the products whose every dimension, variable and attribute the output-files reference lists
PRODUCTS = [
    "results/paper/stored_series.nc",
    "results/paper/signatures.nc",
    "results/paper/stored_signature.nc",
    "results/paper/readings.nc",
    "results/paper/estimates.nc",
    "results/paper/estimates_readings.nc",
]
RUN_ALIASES = {"paper": ["paper", "readings"], "all": list(STUDIES)}


def _git(*args: str) -> str:
    try:
        return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def commit_of(product: Path | None) -> str:
    """The commit a product was made at: its ``git_commit`` attribute, else the checkout's."""
    if product is not None and product.exists():
        import netCDF4

        with netCDF4.Dataset(product) as ds:
            commit = getattr(ds, "git_commit", None)
        if commit:
            return str(commit)
    dirty = " (with uncommitted changes)" if _git("status", "--porcelain", "--untracked-files=no") else ""
    return _git("rev-parse", "HEAD") + dirty


def stamp(table: Path, product: Path | None, study: str = "") -> str:
    made = dt.datetime.fromtimestamp(table.stat().st_mtime, dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    commit = commit_of(product)
    return (
        f"*Generated from `{table.relative_to(ROOT)}` (made at commit `{commit[:12]}` on {made}; "
        f"regenerate: `python docs/refresh_studies.py --run{' ' + study if study else ''}`).*\n\n"
    )


def _value(value) -> str:
    text = " ".join(str(value).split())
    return (text[:77] + "...") if len(text) > 80 else text


def describe_netcdf(path: Path) -> str:
    """Every dimension, variable (with its dtype, dimensions and attributes) and global
    attribute of a NetCDF file, as Markdown."""
    import netCDF4

    def cell(text) -> str:
        return str(text).replace("|", "\\|")

    with netCDF4.Dataset(path) as ds:
        lines = ["| dimension | length |", "| --- | --- |"]
        lines += [f"| `{name}` | {len(dim)} |" for name, dim in ds.dimensions.items()]
        lines += ["", "| variable | type | dimensions | units | long_name | other attributes |", "| --- | --- | --- | --- | --- | --- |"]
        for name, var in ds.variables.items():
            attrs = {k: var.getncattr(k) for k in var.ncattrs()}
            units, long_name = attrs.pop("units", ""), attrs.pop("long_name", "")
            other = ", ".join(f"`{k}`" for k in attrs if not k.startswith("_"))
            lines.append(f"| `{name}` | {cell(getattr(var.dtype, '__name__', var.dtype))} | {', '.join(var.dimensions)} | {cell(units)} | {cell(long_name)} | {other} |")
        lines += ["", "| global attribute | value (this run) |", "| --- | --- |"]
        lines += [f"| `{k}` | {cell(_value(ds.getncattr(k)))} |" for k in ds.ncattrs()]
    return "\n".join(lines) + "\n"


def refresh_products() -> list[str]:
    """Describe each workflow product that results/ holds (docs/generated/outputs/)."""
    (OUT / "outputs").mkdir(parents=True, exist_ok=True)
    done = []
    for product in PRODUCTS:
        path = ROOT / product
        if path.exists():
            text = stamp(path, path) + describe_netcdf(path)
            (OUT / "outputs" / f"{path.stem}.md").write_text(text)
            done.append(path.name)
    return done


def refresh_estimate_files() -> list[str]:
    """Describe the files an estimate writes: ``RestitutionEstimate.to_dataset()`` as NetCDF and
    the calibration it stored, for a short simulated record (seconds; a cache of its own)."""
    import tempfile

    import rockdec

    with tempfile.TemporaryDirectory() as tmp:
        res = rockdec.estimate(rockdec.simulate(0.85, 20_000, seed=1), cache=tmp)
        path = Path(tmp) / "estimate.nc"
        res.to_dataset().to_netcdf(path)
        made = dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
        header = (f"*Generated by `python docs/refresh_studies.py` from the estimate of a simulated record "
                  f"(rockdec at commit `{commit_of(None)[:12]}` on {made}).*\n\n")
        (OUT / "outputs" / "estimate.md").write_text(header + describe_netcdf(path))
        (calibration,) = Path(tmp).rglob("calibration-*.nc")
        (OUT / "outputs" / "calibration.md").write_text(header + describe_netcdf(calibration))
    return ["estimate.nc", "calibration-<hash>.nc"]


def refresh(names: list[str]) -> list[str]:
    """Copy each study's table (and every figure) that results/ holds; return what was copied."""
    (OUT / "studies").mkdir(parents=True, exist_ok=True)
    (OUT / "figures").mkdir(parents=True, exist_ok=True)
    done = []
    for name in names:
        _, table, product = STUDIES[name]
        table = ROOT / table
        if not table.exists():
            continue
        text = stamp(table, ROOT / product if product else None, name) + table.read_text()
        (OUT / "studies" / f"{name}.md").write_text(text)
        done.append(name)
    for folder, files in FIGURES.items():
        for file in files:
            if (ROOT / folder / file).exists():
                shutil.copyfile(ROOT / folder / file, OUT / "figures" / file)
                done.append(file)
    return done


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--run", nargs="*", metavar="STUDY", help="run these studies' workflow targets first (none given: paper)")
    parser.add_argument("--cores", type=int, default=2)
    args = parser.parse_args(argv)
    if args.run is not None:
        wanted = [s for name in (args.run or ["paper"]) for s in RUN_ALIASES.get(name, [name])]
        unknown = sorted(set(wanted) - set(STUDIES))
        if unknown:
            parser.error(f"unknown studies {unknown}; choose from {sorted(STUDIES)} or all")
        targets = sorted({STUDIES[s][0] for s in wanted})
        subprocess.run([sys.executable, "-m", "snakemake", "--cores", str(args.cores), *targets], cwd=ROOT, check=True)
    done = refresh(list(STUDIES)) + refresh_products() + refresh_estimate_files()
    print("refreshed: " + (", ".join(done) if done else "nothing (results/ holds no study tables)"))
    return 0


if __name__ == "__main__":
    sys.exit(main())

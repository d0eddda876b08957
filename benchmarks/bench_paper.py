"""The paper run against a floor measured in the same run: the timing table of docs/development/benchmarks.md.

1. **The run**: ``snakemake --cores N`` from an empty ``results/`` in a temporary copy of the
   workflow (the tree's ``Snakefile``, ``workflow/``, ``config/``, ``profiles/``, its ``src/``
   first on ``PYTHONPATH``), default scene ``paper``. Wall time of the command, the CPU
   seconds of the command and its jobs (``os.wait4`` of the process, children included),
   and each rule's wall and CPU seconds from its benchmark file. Then the same command
   again, with nothing to do: the no-op rerun.
2. **The floor**: in this one process, what the run cannot do without: the paper's
   20 x 1000 series simulated under the run's contract (``run.json`` of step 1, so no
   calibration), their pooled signatures (the paper's reading, one pass) and eq. 28 from
   them (the estimates and the replicate statistics of the table), on ``--floor-threads``
   threads; no files, no figures, no other readings. Its eq. 28 is compared with the
   run's ``table.csv``.

With ``--before OTHER_TREE`` (another checkout of the repository; the option may be given
several times) the run and the no-op rerun are timed for every tree, the order turning by
one tree at each of ``--repeat`` rounds, with a floor in each round, so that all see the
same load on a shared machine; the tables and figures of this tree and each other are
compared byte for byte, and the NetCDF products
number for number: every variable's values bit for bit, every attribute but ``history``
and ``git_commit`` (which name the run and the tree).

Prints the runs, the floors, the ratios run / floor (the median over the rounds) and a
markdown table of the rules of the last run of this tree. Numba's cache is whatever the
interpreter finds: run once to fill it, then again to time a warm cache.

Run: ``PYTHONPATH=src python benchmarks/bench_paper.py`` (``--cores``, ``--floor-threads``,
``--before``, ``--repeat``, ``--keep`` to leave the copies). Measures; asserts nothing.
"""

from __future__ import annotations

import argparse
import csv
import filecmp
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def timed(command: list[str], env: dict | None = None, cwd: Path | None = None) -> tuple[float, float]:
    """Wall and CPU seconds (the process and the children it waited for, ``os.wait4``) of
    ``command`` run in ``cwd`` with ``env`` added to the environment; exits naming the
    command and its output when it fails."""
    start = time.perf_counter()
    proc = subprocess.Popen(command, cwd=cwd, env={**os.environ, **(env or {})}, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)
    out = proc.stdout.read()
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - start
    if os.waitstatus_to_exitcode(status) != 0:
        sys.exit(f"{' '.join(command)} failed{f' in {cwd}' if cwd else ''}:\n{out}")
    return wall, usage.ru_utime + usage.ru_stime


def snakemake(root: Path, tree: Path, cores: int, scene: str, env: dict | None = None) -> tuple[float, float]:
    """Wall and CPU seconds (the command and its jobs) of ``snakemake --cores`` in ``root``,
    with ``tree``'s sources first on the path and ``env`` added to the environment."""
    return timed([sys.executable, "-m", "snakemake", "--cores", str(cores), "-q", "--config", f"default_scene={scene}"],
                 {**(env or {}), "PYTHONPATH": str(tree / "src")}, root)


def paper_run(tree: Path, root: Path, cores: int, scene: str, env: dict | None = None) -> dict:
    """The run and its no-op rerun in a fresh copy of ``tree`` at ``root`` (``env`` added to
    their environment): wall and CPU seconds of each, per-rule rows."""
    root.mkdir(parents=True)
    shutil.copy(tree / "Snakefile", root)
    for folder in ("workflow", "config", "profiles"):
        shutil.copytree(tree / folder, root / folder)
    wall, cpu = snakemake(root, tree, cores, scene, env)
    noop_wall, noop_cpu = snakemake(root, tree, cores, scene, env)
    rules = []
    for path in sorted((root / "results" / scene / "benchmarks").glob("*.tsv")):
        with open(path) as f:
            row = next(csv.DictReader(f, delimiter="\t"))
        rules.append((path.stem, float(row["s"]), float(row["cpu_time"])))
    return {"wall": wall, "cpu": cpu, "noop_wall": noop_wall, "noop_cpu": noop_cpu, "rules": rules, "root": root}


def floor(root: Path, scene_name: str, threads: int) -> dict:
    """The floor of the module docstring, timed in this process; its eq. 28 table."""
    import yaml

    from rockdec.pipeline import config, replicates
    from rockdec.physics.run import Run

    cfg = config.validate(yaml.safe_load((root / "config" / "config.yaml").read_text()))
    scene = cfg["scenes"][scene_name]
    contract = Run.read(root / "results" / scene_name / "run.json")
    start, cpu = time.perf_counter(), time.process_time()
    cube = replicates.scene_cubes(contract, scene["records"], scene["signatures"], ["pooled"], threads=threads)["pooled"]
    _, table = replicates.scene_estimates(cube, scene["estimates"])
    return {"wall": time.perf_counter() - start, "cpu": time.process_time() - cpu, "table": table}


def largest_difference(table, path: Path) -> float:
    """Largest |difference| between the floor's table and the run's ``table.csv``, over
    the numeric columns both hold."""
    import numpy as np
    import pandas as pd

    run_table = pd.read_csv(path)
    common = [c for c in table.columns if c in run_table.columns and pd.api.types.is_numeric_dtype(table[c])]
    return float(np.nanmax(np.abs(table[common].to_numpy(float) - run_table[common].to_numpy(float))))


def products(results: Path) -> list[Path]:
    """The tables and figures of a scene's results, relative to ``results``."""
    return sorted(p.relative_to(results) for p in [*results.glob("table*"), *results.glob("figures/*")] if p.is_file())


def compared(a: Path, b: Path) -> str:
    """Which tables and figures differ between two scenes' results, in words."""
    names = products(a)
    if names != products(b):
        return f"different products: {sorted(set(map(str, names)) ^ set(map(str, products(b))))}"
    differ = [str(n) for n in names if not filecmp.cmp(a / n, b / n, shallow=False)]
    return f"all {len(names)} identical" if not differ else f"{len(differ)} of {len(names)} differ: {', '.join(differ)}"


#: Attributes of a NetCDF product that say when and from which tree it was made.
RUN_ATTRS = ("history", "git_commit")


def compared_data(a: Path, b: Path) -> str:
    """Which NetCDF products of two scenes' results hold different numbers or attributes
    (but :data:`RUN_ATTRS`), in words."""
    import numpy as np
    import xarray as xr

    def same(x, y) -> bool:
        u, w = x.values, y.values
        if u.dtype.kind in "biufc":
            return u.dtype == w.dtype and u.shape == w.shape and u.tobytes() == w.tobytes()
        return u.shape == w.shape and all(str(p) == str(q) for p, q in zip(u.ravel(), w.ravel()))

    def attrs(v):
        return {k: str(x) for k, x in v.attrs.items() if k not in RUN_ATTRS}

    names = sorted(p.relative_to(a) for p in a.rglob("*.nc"))
    if names != sorted(p.relative_to(b) for p in b.rglob("*.nc")):
        return "different NetCDF products"
    differ = []
    for name in names:
        with xr.open_dataset(a / name, decode_times=False) as x, xr.open_dataset(b / name, decode_times=False) as y:
            if (set(x.variables) != set(y.variables) or attrs(x) != attrs(y)
                    or not all(same(x[v], y[v]) and attrs(x[v]) == attrs(y[v]) for v in x.variables)):
                differ.append(str(name))
    return f"all {len(names)} hold the same numbers" if not differ else f"{len(differ)} of {len(names)} differ: {', '.join(differ)}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="paper")
    parser.add_argument("--cores", type=int, default=2, help="snakemake --cores (default %(default)s)")
    parser.add_argument("--floor-threads", type=int, default=1, help="threads of the floor (default %(default)s)")
    parser.add_argument("--before", type=Path, action="append", default=[],
                        help="another checkout of the repository, timed in the same run (may be given several times)")
    parser.add_argument("--repeat", type=int, default=1, help="rounds (default %(default)s)")
    parser.add_argument("--keep", action="store_true", help="leave the copies of the workflow and print their path")
    args = parser.parse_args()
    others = [tree.resolve() for tree in args.before]
    names = ["before"] if len(others) == 1 else [f"before {tree.name}" for tree in others]
    trees = {"this tree": REPO} | dict(zip(names, others))
    base = Path(tempfile.mkdtemp(prefix="rockdec_bench_paper_"))
    runs = {label: [] for label in trees}
    floors = []
    try:
        for k in range(args.repeat):
            turn = k % len(trees)
            order = list(trees)[turn:] + list(trees)[:turn]
            for label in order:
                runs[label].append(paper_run(trees[label], base / f"{label.replace(' ', '_')}_{k}", args.cores, args.scene))
                print(f"round {k + 1}, {label}: {runs[label][-1]['wall']:.1f} s", file=sys.stderr, flush=True)
            low = floor(runs["this tree"][-1]["root"], args.scene, args.floor_threads)
            floors.append(low)
        results = runs["this tree"][-1]["root"] / "results" / args.scene
        diff = largest_difference(floors[-1]["table"], results / "table.csv")
        checks = {}
        for name in names:
            other = runs[name][-1]["root"] / "results" / args.scene
            checks[name] = (compared(results, other), compared_data(results, other))
    finally:
        if args.keep:
            print(f"copies kept in {base}")
        else:
            shutil.rmtree(base, ignore_errors=True)
    print("| rule | wall s | CPU s |\n|---|---:|---:|")
    for name, wall, cpu in runs["this tree"][-1]["rules"]:
        print(f"| {name} | {wall:.1f} | {cpu:.1f} |")
    last = runs["this tree"][-1]
    print(f"| **whole run** (`snakemake --cores {args.cores}`) | **{last['wall']:.1f}** | {last['cpu']:.1f} |")
    print(f"| no-op rerun | {last['noop_wall']:.2f} | {last['noop_cpu']:.2f} |")
    print(f"| floor (one process, {args.floor_threads} thread(s)) | {floors[-1]['wall']:.1f} | {floors[-1]['cpu']:.1f} |")
    print()
    def listed(rows, key, digits=1):
        return ", ".join(f"{row[key]:.{digits}f}" for row in rows)

    for label, rounds in runs.items():
        walls = [r["wall"] / f["wall"] for r, f in zip(rounds, floors)]
        cpus = [r["cpu"] / f["cpu"] for r, f in zip(rounds, floors)]
        print(f"{label}: run {listed(rounds, 'wall')} s wall, {listed(rounds, 'cpu')} s CPU; "
              f"no-op rerun {listed(rounds, 'noop_wall', 2)} s wall, {listed(rounds, 'noop_cpu', 2)} s CPU; "
              f"run / floor (median of {len(rounds)}): {statistics.median(walls):.2f} wall, {statistics.median(cpus):.2f} CPU")
    print(f"floors: {listed(floors, 'wall')} s wall, {listed(floors, 'cpu')} s CPU")
    print(f"floor's eq. 28 against the run's table.csv: largest |difference| {diff:.3g}")
    for name, (same, data) in checks.items():
        print(f"tables and figures, this tree against {name}: {same}")
        print(f"NetCDF products, this tree against {name} (numbers bit for bit, attributes but {', '.join(RUN_ATTRS)}): {data}")


if __name__ == "__main__":
    main()

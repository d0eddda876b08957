"""The paper run against a floor measured in the same run: the README's timing table.

1. **The run**: ``snakemake --cores N`` from an empty ``results/`` in a temporary copy of the
   workflow (the repository's ``Snakefile``, ``workflow/``, ``config/``, ``profiles/``),
   default scene ``paper``. Wall time of the command, the CPU seconds of the command and
   its jobs (``os.wait4`` of the process, children included), and each rule's wall and
   CPU seconds from its benchmark file.
2. **The floor**: in this one process, what the run cannot do without: the paper's
   20 x 1000 series simulated under the run's contract (``run.json`` of step 1, so no
   calibration), their pooled signatures (the paper's reading, one pass) and eq. 28 from
   them (the estimates and the replicate statistics of the table), on ``--floor-threads``
   threads; no files, no figures, no other readings. Its eq. 28 is compared with the
   run's ``table.csv``.

Prints both, the ratio run / floor, and a markdown table of the rules. Numba's cache is
whatever the interpreter finds: run once to fill it, then again to time a warm cache.

Run: ``PYTHONPATH=src python benchmarks/bench_paper.py`` (``--cores``, ``--floor-threads``,
``--keep`` to leave the copy). Measures; asserts nothing.
"""

from __future__ import annotations

import argparse
import csv
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def paper_run(root: Path, cores: int, scene: str) -> dict:
    """``snakemake --cores`` in a fresh copy at ``root``: wall and CPU seconds, per-rule rows."""
    shutil.copy(REPO / "Snakefile", root)
    for folder in ("workflow", "config", "profiles"):
        shutil.copytree(REPO / folder, root / folder)
    start = time.perf_counter()
    proc = subprocess.Popen(
        [sys.executable, "-m", "snakemake", "--cores", str(cores), "-q", "--config", f"default_scene={scene}"],
        cwd=root, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
    )
    out = proc.stdout.read()
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - start
    if os.waitstatus_to_exitcode(status) != 0:
        sys.exit(f"the run failed:\n{out}")
    rules = []
    for path in sorted((root / "results" / scene / "benchmarks").glob("*.tsv")):
        with open(path) as f:
            row = next(csv.DictReader(f, delimiter="\t"))
        rules.append((path.stem, float(row["s"]), float(row["cpu_time"])))
    return {"wall": wall, "cpu": usage.ru_utime + usage.ru_stime, "rules": rules}


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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", default="paper")
    parser.add_argument("--cores", type=int, default=2, help="snakemake --cores (default %(default)s)")
    parser.add_argument("--floor-threads", type=int, default=1, help="threads of the floor (default %(default)s)")
    parser.add_argument("--keep", action="store_true", help="leave the copy of the workflow and print its path")
    args = parser.parse_args()
    root = Path(tempfile.mkdtemp(prefix="rockdec_bench_paper_"))
    try:
        run = paper_run(root, args.cores, args.scene)
        low = floor(root, args.scene, args.floor_threads)
        diff = largest_difference(low["table"], root / "results" / args.scene / "table.csv")
    finally:
        if args.keep:
            print(f"copy kept in {root}")
        else:
            shutil.rmtree(root, ignore_errors=True)
    print(f"| rule | wall s | CPU s |\n|---|---:|---:|")
    for name, wall, cpu in run["rules"]:
        print(f"| {name} | {wall:.1f} | {cpu:.1f} |")
    print(f"| **whole run** (`snakemake --cores {args.cores}`) | **{run['wall']:.1f}** | {run['cpu']:.1f} |")
    print(f"| floor (one process, {args.floor_threads} thread(s)) | {low['wall']:.1f} | {low['cpu']:.1f} |")
    print(f"\nrun / floor: {run['wall'] / low['wall']:.2f} (wall), {run['cpu'] / low['cpu']:.2f} (CPU)")
    print(f"floor's eq. 28 against the run's table.csv: largest |difference| {diff:.3g}")


if __name__ == "__main__":
    main()

"""The campaign's overhead: ``snakemake --cores 2 campaign`` against the same work done by hand.

A plain script (not a test): prints timings and their ratio, never asserts them.

    python benchmarks/bench_campaign.py [--samples 100000] [--keep DIR]

1. The demonstration campaign's records (``config/records.tsv``: six records in four blocks,
   block A of three pooled) are simulated once as NetCDF files, ``--samples`` samples each,
   and listed in a sheet of measured records (paths, no ``simulate``): the campaign then
   reads files, as a lab's would.
2. **Campaign**: ``python -m snakemake --cores 2 campaign`` on a copy of the workflow, its
   calibrations into an empty cache; wall seconds from start to end (table, figures and
   archive included).
3. **By hand**: for each record and each block of two or more records (its files given
   together), ``python -m rockdec estimate FILES --json --cache DIR`` into another empty
   cache, one after the other: the first command that needs a calibration builds it (cold),
   and each command is run again once it is stored (warm). A calibration's build time is
   its cold command's time less the same command's warm time.
4. The ratio: the campaign's wall time over (the sum of the warm times + the sum of the
   build times) / 2, the by-hand work spread over 2 cores; and the same in CPU seconds
   (every process and thread), which another user's load moves less.

Wall seconds on a machine that may be shared: the load average is printed with them.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def _cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _timed(command: list[str], cwd: Path) -> tuple[float, float, str]:
    """Wall and CPU seconds (the command's and its children's, every thread) and its output."""
    start, cpu = time.perf_counter(), _cpu()
    done = subprocess.run(command, cwd=cwd, capture_output=True, text=True)
    seconds = time.perf_counter() - start
    if done.returncode:
        sys.exit(f"failed ({done.returncode}): {' '.join(command)}\n{done.stderr[-3000:]}")
    return seconds, _cpu() - cpu, done.stdout


def records(folder: Path, samples: int) -> list[dict]:
    """The demonstration's rows simulated as files under ``folder``; the rows of a sheet of them."""
    from rockdec import io
    from rockdec.pipeline import campaign

    folder.mkdir(parents=True, exist_ok=True)
    rows = campaign.read_sheet(REPO / "config" / "records.tsv", simulated=folder)
    out = []
    for row in rows:
        row["simulate"]["n_points"] = samples
        io.write_netcdf(campaign.simulated_record(row), row["path"])
        out.append({"record": row["record"], "path": row["path"], "block": row["block"], "true_e": row["true_e"]})
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=100_000, help="samples per record (default: %(default)s)")
    parser.add_argument("--keep", type=Path, help="work in this folder and keep it (default: a temporary one)")
    args = parser.parse_args()
    work = args.keep or Path(tempfile.mkdtemp(prefix="bench_campaign_"))
    work.mkdir(parents=True, exist_ok=True)
    for name in ("workflow", "config", "profiles"):
        shutil.copytree(REPO / name, work / name, dirs_exist_ok=True)
    shutil.copy(REPO / "Snakefile", work)
    rows = records(work / "records", args.samples)
    sheet = work / "measured.tsv"
    sheet.write_text("record\tpath\tblock\ttrue_e\n" + "".join(f"{r['record']}\t{r['path']}\t{r['block']}\t{r['true_e']}\n" for r in rows))

    campaign_cache, hand_cache = work / "cache_campaign", work / "cache_hand"
    for cache in (campaign_cache, hand_cache):
        shutil.rmtree(cache, ignore_errors=True)
    load = os.getloadavg()[0]
    wall, wall_cpu, _ = _timed([sys.executable, "-m", "snakemake", "--cores", "2", "campaign", "--config",
                                f"campaign={{name: bench, sheet: {sheet}, cache: {campaign_cache}}}"], work)

    blocks: dict[str, list[str]] = {}
    for row in rows:
        blocks.setdefault(row["block"], []).append(row["path"])
    units = [[row["path"]] for row in rows] + [paths for paths in blocks.values() if len(paths) > 1]
    warm, built, warm_cpu, built_cpu = [], [], [], []
    for paths in units:
        command = [sys.executable, "-m", "rockdec", "estimate", *paths, "--json", "--cache", str(hand_cache)]
        first, first_cpu, out = _timed(command, work)
        again, again_cpu, _ = _timed(command, work)
        warm.append(again)
        warm_cpu.append(again_cpu)
        if not json.loads(out)["calibration"]["cached"]:
            built.append(first - again)
            built_cpu.append(first_cpu - again_cpu)
    hand = (sum(warm) + sum(built)) / 2
    print(f"records: {len(rows)} of {args.samples} samples, {len(units) - len(rows)} pooled block(s); load average {load:.2f} at the start")
    print(f"campaign (snakemake --cores 2 campaign): {wall:.1f} s wall, {len(list(campaign_cache.glob('calibration-*.nc')))} calibrations")
    print(f"by hand: {len(units)} warm estimates {sum(warm):.1f} s in all, {len(built)} calibrations built in {sum(built):.1f} s; "
          f"(warm + builds) / 2 = {hand:.1f} s")
    print(f"ratio: {wall / hand:.2f}")
    hand_cpu = sum(warm_cpu) + sum(built_cpu)
    print(f"CPU: campaign {wall_cpu:.1f} s, by hand {hand_cpu:.1f} s (warm {sum(warm_cpu):.1f} + builds {sum(built_cpu):.1f}); "
          f"ratio {wall_cpu / hand_cpu:.2f} (less moved by a shared machine's load than the wall times)")
    if not args.keep:
        shutil.rmtree(work)


if __name__ == "__main__":
    main()

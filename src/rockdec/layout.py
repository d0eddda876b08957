"""What a scene's seeds and products are called: light enough for the Snakefile to import.

The workflow (``workflow/rules/common.smk``) turns scenes into file names with these names
and functions only; importing them loads NumPy and nothing of the numerical core, so a
Snakemake run that has nothing to do stays fast.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

FIGURES = ("fig1b", "fig2", "fig3", "fig4", "fig_ev")
"""The paper's figures a scene draws (fig. 2 only when it stores series), and ``fig_ev``."""

READINGS = ("pooled", "per_series", "groups_of_10")
"""The readings of the paper's sizes (docs/method.md §8), in the order tables list them."""

COVERAGE_CASES = {
    "white_200000": (200_000, None),
    "white_20000": (20_000, None),
    "corner1": (200_000, 1.0),
    "corner3": (200_000, 3.0),
    "corner10": (200_000, 10.0),
}
"""The coverage study's cases (``results/studies/coverage/{case}.nc``): name -> (record
length, load corner in rocking frequencies or ``None`` for white noise)."""

FIGURE_SERIES = 10
"""Series ``stored_series.nc`` keeps when every series is stored apart: the pooling of fig. 2c."""


def scene_seeds(records: dict) -> np.ndarray:
    """Seeds of a scene's ``records`` section as ``(replicate, series)``: consecutive integers
    from ``first_seed``."""
    n = records["replicates"] * records["series_per_replicate"]
    return (records["first_seed"] + np.arange(n, dtype=np.int64)).reshape(records["replicates"], records["series_per_replicate"])


def stores_all(records: dict) -> bool:
    """Whether a scene's ``records`` section writes every series (``store_series: all``)."""
    return records["store_series"] == "all"


def simulation_seeds(records: dict) -> np.ndarray:
    """Seeds whose series ``stored_series.nc`` holds: the first ``store_series`` of the scene
    (the first :data:`FIGURE_SERIES` with ``store_series: all``)."""
    count = FIGURE_SERIES if stores_all(records) else records["store_series"]
    n = records["replicates"] * records["series_per_replicate"]  # the first seeds of scene_seeds, not all of them
    return records["first_seed"] + np.arange(min(count, n), dtype=np.int64)


def replicate_files(folder: str | Path, records: dict) -> list[Path]:
    """Paths of the per-replicate series files under ``folder`` (none unless ``store_series: all``)."""
    if not stores_all(records):
        return []
    return [Path(folder) / "series" / f"replicate_{r}.nc" for r in range(records["replicates"])]


def signature_parts(records: dict) -> list[int]:
    """The jobs the signature pass is split into: ``replicates_per_job`` replicates each
    (the last may hold fewer); none when the scene runs it as one job."""
    per_job = records.get("replicates_per_job")
    if not per_job:
        return []
    return list(range(-(-records["replicates"] // per_job)))


def part_records(records: dict, part: int) -> tuple[dict, int]:
    """The ``records`` of one job of :func:`signature_parts`, and its first replicate.

    A part is a scene of its own: ``replicates_per_job`` replicates whose seeds start where
    its first replicate's do, so its series are the scene's, seed for seed.
    """
    per_job = records["replicates_per_job"]
    first = part * per_job
    count = min(per_job, records["replicates"] - first)
    if not 0 <= first < records["replicates"]:
        raise ValueError(f"part {part} is outside the scene's {len(signature_parts(records))} signature jobs")
    shifted = {**records, "replicates": count, "first_seed": records["first_seed"] + first * records["series_per_replicate"],
               "replicates_per_job": None}
    return shifted, first


def compared_readings(estimates: dict) -> list[str]:
    """The readings a scene's ``estimates`` section asks for: its own first, then the others
    when it compares readings."""
    own = estimates["reading"]
    return [own] + ([r for r in READINGS if r != own] if estimates["compare_readings"] else [])


#: What :func:`workflow_sources` lists of the workflow: the Snakefile, then every file under
#: these folders (hidden files and Python caches left out).
SOURCE_FOLDERS = ("workflow", "config")


def workflow_sources(root: str | Path) -> list[str]:
    """The workflow's own files under ``root`` (the folder of its Snakefile), as relative
    names, Snakefile first: what an archive holds of the workflow (rule ``archive_scene``)."""
    root = Path(root)
    names = [
        path.relative_to(root).as_posix()
        for folder in SOURCE_FOLDERS
        for path in sorted((root / folder).rglob("*"))
        if path.is_file() and not any(part.startswith(".") or part == "__pycache__" for part in path.relative_to(root).parts)
    ]
    return ["Snakefile", *names]

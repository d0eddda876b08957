"""What a scene's seeds and products are called: light enough for the Snakefile to import.

The workflow (``workflow/rules/common.smk``) turns scenes into file names with these names
and functions only; importing them loads NumPy and nothing of the numerical core, so a
Snakemake run that has nothing to do stays fast.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = [
    "COVERAGE_CASES", "COVERAGE_CONDITIONS", "COVERAGE_E", "COVERAGE_SIMULATORS",
    "DIAGNOSTICS_COLOURED_NOISE", "DIAGNOSTICS_CORNERS", "DIAGNOSTICS_E", "DIAGNOSTICS_NOISE",
    "DIAGNOSTICS_PARTS", "FIGURES", "FIGURE_SERIES", "READINGS", "compared_readings", "diagnostics_noise",
    "part_records", "replicate_files", "scene_seeds", "signature_parts", "simulation_seeds", "stores_all",
    "workflow_sources",
]

FIGURES = ("fig1b", "fig2", "fig3", "fig4", "fig_ev")
"""The paper's figures a scene draws (fig. 2 only when it stores series), and ``fig_ev``."""

READINGS = ("pooled", "per_series", "groups_of_10")
"""The readings of the paper's sizes (docs/method.md §8), in the order tables list them."""

COVERAGE_E = (0.6, 0.8, 0.9, 0.95, 0.98)
"""True ``e`` of the coverage study's cells."""

COVERAGE_CONDITIONS = {
    "clean": (0.0, None),
    "noise1": (0.01, None),
    "noise3": (0.03, None),
    "noise5": (0.05, None),
    "corner0.5": (0.0, 0.5),
    "corner1": (0.0, 1.0),
    "corner3": (0.0, 3.0),
    "corner1_noise2": (0.02, 1.0),
}
"""The coverage study's conditions: name -> (sensor noise in units of ``sigma_Y``, load
corner in rocking frequencies ``1/T(sigma_Y)`` or ``None`` for white impulses)."""

COVERAGE_SIMULATORS = ("kernel", "reference")
"""Who makes a cell's records: the compiled kernel the calibration runs, or the NumPy
reference written apart (``tests/rocking_vectorised.py``)."""

COVERAGE_REFERENCE = (("clean", "noise3", "corner1"), (0.6, 0.9, 0.98))
"""Conditions and ``e`` also run on the reference simulator's records."""

COVERAGE_CASES = {
    **{f"kernel_{c}_e{e:g}": ("kernel", c, e) for c in COVERAGE_CONDITIONS for e in COVERAGE_E},
    **{f"reference_{c}_e{e:g}": ("reference", c, e) for c in COVERAGE_REFERENCE[0] for e in COVERAGE_REFERENCE[1]},
}
"""The coverage study's cells (``results/studies/coverage/cells/{case}.nc``): name ->
(simulator, condition, true ``e``)."""

DIAGNOSTICS_E = (0.6, 0.8, 0.95, 0.98)
"""True ``e`` of the warnings' study (:mod:`rockdec.studies.diagnostics_study`)."""

DIAGNOSTICS_NOISE = (0.0, 0.01, 0.03, 0.05)
"""Sensor noise of the warnings' study's records, in units of each clean record's rms (white,
as the calibration simulates it once the record's own noise is measured)."""

DIAGNOSTICS_CORNERS, DIAGNOSTICS_COLOURED_NOISE = (0.0, 3.0), (0.0, 0.03)
"""Loads of the warnings' study's records: the corner of a first-order low-pass load in
rocking frequencies ``1/T(sigma_Y)`` (eq. 5), 0 for white impulses; under a coloured load
only the noise levels of ``DIAGNOSTICS_COLOURED_NOISE`` (each coloured cell asks for
calibrations of its own, each several times a white one's cost, and its records' measured
models scatter over many bins)."""


def diagnostics_noise(corner: float, noise_levels=DIAGNOSTICS_NOISE, coloured_noise=DIAGNOSTICS_COLOURED_NOISE) -> tuple:
    """The sensor noise levels the warnings' study runs under a load of ``corner`` (0: white
    impulses): every one of ``noise_levels`` under a white load, under a coloured one only
    those also in ``coloured_noise``.

    Examples
    --------
    >>> diagnostics_noise(0.0), diagnostics_noise(3.0)
    ((0.0, 0.01, 0.03, 0.05), (0.0, 0.03))
    """
    return tuple(noise_levels) if corner == 0.0 else tuple(x for x in noise_levels if x in coloured_noise)


DIAGNOSTICS_PARTS = {
    f"e{e:g}_{'white' if corner == 0.0 else f'corner{corner:g}'}_noise{noise:g}": (e, corner, noise)
    for e in DIAGNOSTICS_E
    for corner in DIAGNOSTICS_CORNERS
    for noise in diagnostics_noise(corner)
}
"""The warnings' study's workflow jobs (``results/studies/diagnostics/records_{part}.csv``):
name -> (true ``e``, load corner, sensor noise), so that the study, hours long on 2 cores,
is kept in parts as they finish; together they make the rows of one run of all
(:func:`rockdec.studies.diagnostics_study.run`)."""

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

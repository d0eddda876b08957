"""What an estimate costs before it runs: the seconds of each stage and the bytes held, from
constants measured by the benchmarks (``benchmarks/long_record.py``, ``benchmarks/pooled_cost.py``);
the command line refuses, before reading the records, a run the machine cannot finish soon.
"""

from __future__ import annotations

from rockdec.calibrate import calibration

__all__ = ["ANALYSIS_SECONDS", "BYTES_PER_SAMPLE", "CALIBRATION_SECONDS", "CSV_SECONDS", "PAIR_SECONDS", "RECORD_SECONDS", "calibration_sets", "cost", "stage_seconds"]

#: Cost model of :func:`cost`: seconds per sample to read a CSV and to do all but the
#: calibration, seconds per simulated and analysed calibration sample on one core, and
#: bytes held per sample while reading and analysing (measured by
#: ``benchmarks/long_record.py``; docs/explanation/constants.md).
CSV_SECONDS, ANALYSIS_SECONDS, CALIBRATION_SECONDS, BYTES_PER_SAMPLE = 5e-7, 1.0e-6, 1.3e-7, 160.0

#: Seconds each record of a pooled set adds besides its samples, on one core (its own pass
#: of signatures and checks in every simulated set of the calibration), and each pair of
#: records the check for copies in disguise compares (:mod:`rockdec.record.sameness`):
#: measured by ``benchmarks/pooled_cost.py`` (many short records against one long record
#: of as many samples, in one run).
RECORD_SECONDS, PAIR_SECONDS = 4e-4, 7e-5


def stage_seconds(samples: int, csv: bool, g_given: bool, cores: int = 2, records: int = 1,
                  length_grid: bool = False) -> dict[str, float]:
    """Seconds each stage of :func:`rockdec.estimation.estimate` takes on ``records`` records of ``samples`` in all:
    ``reading`` (a CSV), ``analysing`` (twice with a given ``g``) and ``calibrating``
    (building the calibration: :func:`calibration_sets` records, of the records' length up to
    :data:`rockdec.calibrate.calibration.LENGTH_CAP` in all, or of the length grid's length
    with ``length_grid``, :func:`rockdec.calibrate.calibration.simulated_lengths`, and beyond
    the cap the step search's pilot sets of that length), from :data:`CSV_SECONDS` and the other constants of the
    model; each record beyond the first adds :data:`RECORD_SECONDS` in every simulated set
    and each pair of records :data:`PAIR_SECONDS`; several records are analysed twice more,
    each alone (:func:`~rockdec.estimation.analysed.own_scales`, :func:`~rockdec.estimation.pooled.check_pooled`)."""
    simulated = sum(calibration.simulated_lengths([samples], length_grid))
    sets = calibration_sets(samples)
    return {
        "reading": samples * CSV_SECONDS * csv,
        "analysing": samples * ANALYSIS_SECONDS * (1 + g_given + 2 * (records > 1)) + records * (records - 1) / 2 * PAIR_SECONDS,
        "calibrating": simulated * sets * CALIBRATION_SECONDS / cores + (records - 1) * sets * RECORD_SECONDS,
    }


def calibration_sets(samples: int) -> int:
    """How many records a calibration for records of ``samples`` in all simulates:
    :data:`rockdec.calibrate.calibration.SETS_PER_E` at each ``e`` of its grid, and beyond
    :data:`rockdec.calibrate.calibration.LENGTH_CAP`
    :data:`rockdec.calibrate.calibration.SETS_PER_E_CAPPED` and the step search's pilot sets
    (as long as the sets, :func:`rockdec.calibrate.calibration.step_for`) on the longer grid
    (:func:`rockdec.calibrate.calibration.sets_per_e`)."""
    if sum(calibration.simulated_lengths([samples])) == samples:
        return len(calibration.E_GRID) * calibration.SETS_PER_E
    from rockdec.physics.simulate import STEP_ITERATIONS

    sets = calibration.SETS_PER_E_CAPPED + calibration.PILOT_SETS * STEP_ITERATIONS["white"]
    return len(calibration.E_GRID_LONG) * sets


def cost(samples: int, csv: bool, g_given: bool, cores: int = 2, records: int = 1, length_grid: bool = False) -> tuple[float, float]:
    """``(seconds, bytes)`` that :func:`rockdec.estimation.estimate` needs for ``records`` records of ``samples``
    in all, calibration included (:func:`stage_seconds`)."""
    return sum(stage_seconds(samples, csv, g_given, cores, records, length_grid).values()), samples * BYTES_PER_SAMPLE

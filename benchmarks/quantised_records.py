"""What a logger's hold and an encoder's integer counts do to the record checks.

A plain script (not a test): prints measurements, never asserts them.

    nice python benchmarks/quantised_records.py
    nice python benchmarks/quantised_records.py --records 10 --part sharpness

``held``: for records of ``e`` 0.6-0.95 at 10-75 samples per cycle (1,000 and 20,000 samples,
:func:`rockdec.physics.simulate.simulate_block` and the independent simulator of
``tests/rocking_vectorised.py``), as given and rounded to counts of ``sigma_Y`` / 200, / 20,
/ 5 and / 2, the share that :func:`rockdec.record.records.held` refuses (false alarms), and
the share of the same records held for 2, 3 and 4 samples that it names with their hold
(:data:`rockdec.record.records.HOLD_SHARE`).

``sharpness``: for records of ``e`` 0.7-0.95 at 40-120 samples per cycle rounded to counts of
``sigma_Y`` / 50 to / 2,000, the one-sample velocity at the fast zero crossings in counts and
how far rounding moves the statistic of the check ``filtered``
(:func:`rockdec.record.diagnostics.impact_sharpness`, with :func:`rockdec.record.diagnostics.impact_ratios`
reading every record, coarse or not) off the unrounded record's: what
:data:`rockdec.record.diagnostics.IMPACT_MIN_STEPS` rests on.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from unittest import mock

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from conftest import calibrated_step  # noqa: E402
import rocking_vectorised  # noqa: E402

from rockdec.physics import simulate  # noqa: E402
from rockdec.record import diagnostics  # noqa: E402
from rockdec.record.records import Record, held  # noqa: E402


def records(source: str, seeds, n: int, e: float, ppc: float) -> np.ndarray:
    cal = calibrated_step(e, 1.0, 0.003, ppc)
    if source == "reference":
        return rocking_vectorised.simulate_records(seeds, n, dt=cal["dt"], g=1.0, e=e, sigma_p=0.003, burn_in=cal["burn_in"])
    return simulate.simulate_block(seeds, n, dt=cal["dt"], g=1.0, e=e, sigma_p=0.003, burn_in=cal["burn_in"])[0]


def hold(y: np.ndarray, h: int) -> np.ndarray:
    out = y.copy()
    for i in range(1, h):
        out[i::h] = y[0::h][: out[i::h].size]
    return out


def held_part(count: int) -> None:
    alarms, found = {}, {}
    for e, ppc in ((0.6, 25.0), (0.6, 75.0), (0.85, 75.0), (0.95, 75.0), (0.85, 10.0), (0.95, 25.0)):
        for source in ("project", "reference"):
            for n in (1000, 20000):
                for y in records(source, list(range(40, 40 + count)), n, e, ppc):
                    for lsb in (0, 200, 20, 5, 2):
                        z = y if lsb == 0 else np.round(y / (np.std(y) / lsb))
                        alarms.setdefault(lsb, []).append(held(Record(z, 0.01, "r")) is not None)
                        for h in (2, 3, 4):
                            message = held(Record(hold(z, h), 0.01, "r"))
                            found.setdefault((lsb, h), []).append(message is not None and f"held for {h} samples" in message)
    for lsb, v in alarms.items():
        print(f"held: {'as given' if lsb == 0 else f'counts of sigma_Y / {lsb}'}: refused {sum(v)} of {len(v)}")
    for (lsb, h), v in found.items():
        print(f"held: {'as given' if lsb == 0 else f'counts of sigma_Y / {lsb}'}, held for {h}: named {sum(v)} of {len(v)}")


def sharpness_part(count: int) -> None:
    def sharpness(y):
        return diagnostics.impact_sharpness(diagnostics.sums([y]), None)

    with mock.patch.object(diagnostics, "IMPACT_MIN_STEPS", 0):  # every record read, however coarse
        for e in (0.95, 0.85, 0.7):
            for ppc in (40.0, 75.0, 120.0):
                theta = records("project", list(range(60, 60 + count)), 20000, e, ppc)
                for lsb in (50, 200, 500, 2000):
                    shifts, steps = [], []
                    for y in theta:
                        z = np.round(y / (np.std(y) / lsb))
                        steps.append(diagnostics.impact_steps(z))
                        shifts.append(sharpness(z) - sharpness(y))
                    shifts = np.abs(shifts)
                    print(f"sharpness: e {e} ppc {ppc:g} counts of sigma_Y / {lsb}: velocity at the fast crossings {np.median(steps):.1f} "
                          f"counts, shift of the statistic: median {np.median(shifts):.4f}, largest {shifts.max():.4f}", flush=True)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=None, help="records a cell (held: 40, sharpness: 20)")
    parser.add_argument("--part", choices=("held", "sharpness", "both"), default="both")
    args = parser.parse_args(argv)
    if args.part in ("held", "both"):
        held_part(args.records or 40)
    if args.part in ("sharpness", "both"):
        sharpness_part(args.records or 20)


if __name__ == "__main__":
    main()

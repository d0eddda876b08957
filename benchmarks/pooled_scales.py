"""How far apart do independent records of one block read ``sigma_Y`` and ``g``, each alone?

A plain script (not a test): prints measurements, never asserts them.

    nice python benchmarks/pooled_scales.py
    nice python benchmarks/pooled_scales.py --records 30 --lengths 2000 20000

The threshold of :func:`rockdec.calibrate.consistency.scales_apart` (records given together
whose own ``g`` differ beyond :data:`~rockdec.calibrate.consistency.G_FACTOR` are declined, by
:data:`~rockdec.calibrate.consistency.UNITS_RATIO` or more refused as given in different
units) rests on these rates. For each cell (``e``, samples per cycle, length, simulator:
:func:`rockdec.physics.simulate.simulate_block` and the independent one of
``tests/rocking_vectorised.py``) it simulates ``--records`` records of one block at one load
(``g = 1``, each its own seed) and reads each alone as the estimate does
(:func:`rockdec.estimation.own_scales`); every pair of them is one pool of two. It
prints the share of pairs declined and refused, the largest ``g`` and ``sigma_Y`` ratios, and
records whose ``g`` is unread. Then pairs of one block at loads 2 and 3 times apart (``g`` the
same: they must pass) and pairs whose second record is in degrees, mrad or µrad (or rad against
degrees: they must be refused).
"""

from __future__ import annotations

import argparse
import itertools
import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from conftest import calibrated_step  # noqa: E402
import rocking_vectorised  # noqa: E402

from rockdec.calibrate import consistency

from rockdec import estimation  # noqa: E402
from rockdec.physics import simulate  # noqa: E402
from rockdec.rdd import measured  # noqa: E402
from rockdec.record.records import Record  # noqa: E402

SETTINGS = dict(measured.DEFAULT_SETTINGS)
SIGMA_P = 0.003


def records(source: str, seeds, n: int, e: float, ppc: float, sigma_p: float = SIGMA_P) -> tuple[list[Record], float]:
    cal = calibrated_step(e, 1.0, SIGMA_P, ppc)
    dt, burn = cal["dt"], cal["burn_in"]
    if source == "reference":
        theta = rocking_vectorised.simulate_records(seeds, n, dt=dt, g=1.0, e=e, sigma_p=sigma_p, burn_in=burn)
    else:
        theta = simulate.simulate_block(seeds, n, dt=dt, g=1.0, e=e, sigma_p=sigma_p, burn_in=burn)[0]
    return [Record(y, dt, f"r{s}") for y, s in zip(theta, seeds)], dt


def pairs(sigmas, gs) -> list:
    return [consistency.scales_apart(["a", "b"], [sigmas[i], sigmas[j]], [gs[i], gs[j]])
            for i, j in itertools.combinations(range(len(gs)), 2)]


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=60)
    parser.add_argument("--lengths", type=int, nargs="+", default=[1000, 2000, 5000, 20000])
    parser.add_argument("--long", type=int, default=12, help="records of 200,000 samples per cell (0: none)")
    args = parser.parse_args(argv)
    totals: dict[int, list] = {}
    print("cell: pairs, declined, refused, largest g ratio, largest sigma_Y ratio, records with g unread")
    for e, ppc, source in itertools.product((0.6, 0.85, 0.95), (25.0, 75.0), ("project", "reference")):
        for n in [*args.lengths, *([200_000] if args.long and source == "project" else [])]:
            count = args.long if n == 200_000 else args.records
            recs, dt = records(source, list(range(300, 300 + count)), n, e, ppc)
            sigmas, gs = estimation.own_scales(recs, dt, SETTINGS)
            out = pairs(sigmas, gs)
            totals.setdefault(n, []).extend(out)
            ok = np.isfinite(gs)
            g = np.asarray(gs)[ok]
            s = np.asarray(sigmas)
            print(f"e {e} ppc {ppc:g} {source} n {n}: {len(out)} pairs, declined {sum(o is not None and o.kind == 'blocks' for o in out)}, "
                  f"refused {sum(o is not None and o.kind == 'units' for o in out)}, g ratio {g.max() / g.min():.2f}, "
                  f"sigma_Y ratio {s.max() / s.min():.1f}, unread {int((~ok).sum())}/{len(gs)}", flush=True)
    print("all cells by length: pairs, declined share, refused share")
    for n, out in sorted(totals.items()):
        declined = sum(o is not None and o.kind == "blocks" for o in out)
        refused = sum(o is not None and o.kind == "units" for o in out)
        print(f"n {n}: {len(out)} pairs, declined {declined / len(out):.4f}, refused {refused / len(out):.4f}")
    print("one block at loads k times apart (first seed's record against the other's), and pairs whose second record is in other units")
    for n in (2000, 20000):
        base, dt = records("project", list(range(500, 530)), n, 0.85, 75.0)
        for k in (2.0, 3.0):
            other, _ = records("project", list(range(600, 630)), n, 0.85, 75.0, k * SIGMA_P)
            out, ratios = [], []
            for a, b in zip(base, other):
                sigmas, gs = estimation.own_scales([a, b], dt, SETTINGS)
                ratios.append(sigmas[1] / sigmas[0])
                out.append(consistency.scales_apart(["a", "b"], sigmas, gs))
            print(f"load x{k:g}, n {n}: {len(out)} pairs, sigma_Y ratio {min(ratios):.1f}-{max(ratios):.1f}, "
                  f"flagged {sum(o is not None for o in out)}", flush=True)
        sigmas, gs = estimation.own_scales(base, dt, SETTINGS)
        read = [(s, g) for s, g in zip(sigmas, gs) if np.isfinite(g)]
        for factor in (180.0 / math.pi, 1e3 * math.pi / 180.0, 1e3, 1e6, math.pi / 180.0):
            out = [consistency.scales_apart(["a", "b"], [s, t * factor], [g, h * factor]) for (s, g), (t, h) in zip(read, read[1:])]
            print(f"n {n}, the second record of a pair x{factor:.4g}: refused {sum(o is not None and o.kind == 'units' for o in out)}, "
                  f"declined {sum(o is not None and o.kind == 'blocks' for o in out)} of {len(out)} pairs")


if __name__ == "__main__":
    main()

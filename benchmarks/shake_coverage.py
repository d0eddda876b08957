"""Answer rate and coverage of the shake-table test (what :func:`rockdec.shake_table` runs,
:func:`rockdec.free.shake.analyse_shake_table`) on records of
the tests' independent transient generator (``tests/transient_reference.py``: its own rocking
stepper under Clough-Penzien base noise, not the project's simulator).

A plain script (not a test): prints measurements, never asserts them.

    python benchmarks/shake_coverage.py                       # the default grid, 10 records a cell
    python benchmarks/shake_coverage.py --records 4 --peak 1.6 --e 0.9
    python benchmarks/shake_coverage.py --base linear --peak 1.2 1.6 2.2

Cells: true ``e`` x the shaking's strength (``--peak``: the base's std in its strong phase,
in units of the uplift level) x sensor noise (a share of the record's std) x the base's
residual motion in the free part (``--residual``, in units of the uplift level: below
:data:`rockdec.free.shake.QUIET` the tail counts as free). Each record is 20 s of shaking
and 20 s of free decay at 200 Hz, its base held over each sample or linear between samples
(``--base``). Per cell, for the test's ``e`` and for each of its two readings alone (the
free-decay tails; every impact with the base a known load, :mod:`rockdec.free.forced`): the
records answered, how many of their 95 % intervals hold the true ``e``, the median width;
and why the test gave no ``e`` (the first words of each reason, counted); then the pooled
coverage.

With ``--campaigns M``, each cell also gets ``M`` campaigns of ``--records`` records of one
block (seeds apart from the cell's), pooled by one analysis: how many
campaigns are answered and covered, and the median pooled width against the median width of
their records analysed one by one.

    python benchmarks/shake_coverage.py --campaigns 20 --e 0.9 0.95 --peak 1.6
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import transient_reference as tr  # noqa: E402

from rockdec.free.shake import analyse_shake_table  # noqa: E402
from rockdec.studies.shake_coverage import COLUMNS, markdown, tally  # noqa: E402


#: How the generator's base acts between samples (``--base``): linear, as a sampled smooth
#: motion and as the forced reading fits it (read at the midpoints of 8 steps), or held over
#: each sample (a simulator's staircase).
SUBSTEPS = {"held": 0, "linear": 8}

def _records(e: float, peak: float, noise: float, residual: float, seeds, base: str) -> list:
    return [tr.transient_with_base(e, seed, peak=peak, noise=noise, residual=residual, substeps=SUBSTEPS[base]) for seed in seeds]


def _fit(theta, base):
    """:func:`rockdec.free.shake.analyse_shake_table`, what ``rockdec.shake_table`` runs."""
    return analyse_shake_table(theta, base, 1 / tr.FS, base_units="rad/s2", g_block=tr.G)


def cell(e: float, peak: float, noise: float, residual: float, records: int, seed: int, base: str) -> dict:
    """Answered, covered, widths and reasons of ``records`` records of one cell (:func:`rockdec.studies.shake_coverage.tally`)."""
    fits = (_fit(theta, base) for theta, base in _records(e, peak, noise, residual, range(seed, seed + records), base))
    return {"e": e, "peak": peak, "noise": noise, "residual": residual, "records": records, **tally(fits, e)}


def campaigns(e: float, peak: float, noise: float, residual: float, records: int, count: int, seed: int, base: str) -> dict:
    """``count`` campaigns of ``records`` records each, pooled: answered, covered, the pooled
    widths and their records' single widths."""
    out = {"answered": 0, "covered": 0, "pooled": [], "single": []}
    for j in range(count):
        data = _records(e, peak, noise, residual, range(seed + (j + 1) * records, seed + (j + 2) * records), base)
        out["single"] += tally((_fit(theta, base) for theta, base in data), e)["widths"]
        pooled = tally([_fit([d[0] for d in data], [d[1] for d in data])], e)
        out["answered"] += pooled["answered"]
        out["covered"] += pooled["covered"]
        out["pooled"] += pooled["widths"]
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--e", type=float, nargs="+", default=[0.8, 0.9, 0.95])
    parser.add_argument("--peak", type=float, nargs="+", default=[0.8, 1.2, 1.6, 2.2])
    parser.add_argument("--noise", type=float, nargs="+", default=[0.0, 0.01])
    parser.add_argument("--residual", type=float, nargs="+", default=[0.0],
                        help="the base's motion in the free part, in units of the uplift level (uniform white noise)")
    parser.add_argument("--records", type=int, default=10)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--campaigns", type=int, default=0, help="campaigns of --records records a cell, each pooled")
    parser.add_argument("--base", choices=list(SUBSTEPS), default="held", help="how the base acts between samples")
    args = parser.parse_args()
    start = time.perf_counter()
    cells = []
    for e in args.e:
        for peak in args.peak:
            for noise in args.noise:
                for residual in args.residual:
                    cells.append(cell(e, peak, noise, residual, args.records, args.seed, args.base))
                    if args.campaigns:
                        cells[-1]["campaigns"] = campaigns(e, peak, noise, residual, args.records, args.campaigns, args.seed, args.base)
                    print(f"  e {e:g}, peak {peak:g}, noise {noise:g}, residual {residual:g}: "
                          f"{cells[-1]['answered']}/{args.records} answered", file=sys.stderr)
    print(markdown(cells, (*COLUMNS, ("residual", "residual"))))
    if args.campaigns:
        print(f"\n| e | peak | noise | residual | campaigns of {args.records} answered | covered | median pooled width | "
              "median single width |\n| --- | --- | --- | --- | --- | --- | --- | --- |")
        for c in cells:
            p = c["campaigns"]
            pooled = f"{statistics.median(p['pooled']):.3g}" if p["pooled"] else "-"
            single = f"{statistics.median(p['single']):.3g}" if p["single"] else "-"
            print(f"| {c['e']:g} | {c['peak']:g} | {c['noise']:g} | {c['residual']:g} | {p['answered']}/{args.campaigns} | "
                  f"{p['covered']}/{p['answered']} | {pooled} | {single} |")
    print(f"\n{sum(c['records'] for c in cells)} records in {time.perf_counter() - start:.0f} s.")


if __name__ == "__main__":
    main()

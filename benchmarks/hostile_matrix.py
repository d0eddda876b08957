"""The hostile matrix (issues 21, 38): every test marked ``@pytest.mark.hostile(kind, outcome)``,
counted by kind and by what the tool does.

``kind`` is what the user got wrong: numbers (option values and numeric fields of files,
records scaled beyond the floats' square range, low-pass corners whose pole rounds to 0 or 1),
record files (FIFOs and devices, a ``.npz`` named ``.npy``, byte-order marks), units (NetCDF
times in any unit of time, with a reference date), output paths (rebuilds onto links or into
their archive), configs (YAML 1.1 against 1.2, ``--config`` lists, misspelt keys and the
source named), archive (tampered archives given to ``verify``), concurrency, kills (SIGTERM,
Ctrl-C, locks stamped in the future or left by ended processes), limits (memory, disk, file
size, YAML alias bombs), sizes (runs too long to finish), cache (caches that cannot be
written), engines (Dask schedulers), wrong answers (records and options that once gave a
confident wrong ``e``; the same data given twice in disguise; records through a low-pass
filter after the block, undeclared; declared models the record contradicts; simulations that
overturn or miss their sampling) and report (what the report prints). ``outcome`` is what the case asserts the tool does:
refused (one sentence, exit 2, or ``verify`` naming the fault), answered (the correct result),
warned (the result with the warning that qualifies it), or refused or answered (generated
values, each draw one or the other).

Run::

    python benchmarks/hostile_matrix.py            # count the cases (pytest --collect-only)
    python benchmarks/hostile_matrix.py --run      # run them: a case that fails with rockdec's
                                                   # "internal error" counts as one, a case still
                                                   # running after --hang-after seconds as a hang

Extra arguments go to pytest (``-k``, test files). Prints a table of kinds by outcome; asserts
nothing.
"""

from __future__ import annotations

import argparse
import collections
import signal
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
OUTCOMES = ("refused", "answered", "warned", "refused or answered")
FAILED = ("internal error", "hang", "failed")


class Hang(Exception):
    """A case still running after the time a hang is declared."""


class Tally:
    """A pytest plugin: the kind and outcome of every hostile case, and, when run, what happened."""

    def __init__(self, hang_after: float | None):
        self.hang_after = hang_after
        self.cases: dict[str, tuple[str, str]] = {}
        self.result: dict[str, str] = {}

    def pytest_collection_modifyitems(self, items):
        for item in items:
            mark = item.get_closest_marker("hostile")
            if mark is not None:
                kind, outcome = mark.args
                if outcome not in OUTCOMES:
                    raise pytest.UsageError(f"{item.nodeid}: outcome {outcome!r} is not one of {OUTCOMES}")
                self.cases[item.nodeid] = (kind, outcome)

    @pytest.hookimpl(wrapper=True)
    def pytest_runtest_call(self, item):
        if self.hang_after is None or item.nodeid not in self.cases:
            return (yield)

        def alarm(signum, frame):
            raise Hang(f"still running after {self.hang_after:g} s")

        previous = signal.signal(signal.SIGALRM, alarm)
        signal.setitimer(signal.ITIMER_REAL, self.hang_after)
        try:
            return (yield)
        finally:
            signal.setitimer(signal.ITIMER_REAL, 0)
            signal.signal(signal.SIGALRM, previous)

    def pytest_runtest_logreport(self, report):
        if report.nodeid not in self.cases or (report.when != "call" and not report.failed and not report.skipped):
            return
        if report.passed:
            self.result[report.nodeid] = self.cases[report.nodeid][1]
        elif report.skipped:
            self.result.setdefault(report.nodeid, "skipped")
        else:
            text = report.longreprtext
            self.result[report.nodeid] = (
                "hang" if "Hang: still running" in text else "internal error" if "internal error" in text else "failed"
            )


def table(rows: dict[str, str], kinds: dict[str, tuple[str, str]], columns, optional=()) -> str:
    """Cases by kind (rows) and outcome (``columns``, then each of ``optional`` that occurs)."""
    counts = collections.Counter((kinds[node][0], outcome) for node, outcome in rows.items())
    names = sorted({kind for kind, _ in kinds.values()})
    columns = [*columns, *(c for c in optional if any(counts[(k, c)] for k in names))]
    lines = ["| kind | " + " | ".join(columns) + " | cases |", "|---" * (len(columns) + 2) + "|"]
    for kind in names:
        lines.append(f"| {kind} | " + " | ".join(str(counts[(kind, c)]) for c in columns) + f" | {sum(counts[(kind, c)] for c in columns)} |")
    lines.append("| all | " + " | ".join(str(sum(counts[(k, c)] for k in names)) for c in columns) + f" | {sum(counts.values())} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--run", action="store_true", help="run the cases, not only count them")
    parser.add_argument("--hang-after", type=float, default=600.0, help="seconds after which a running case is a hang (default: 600)")
    args, extra = parser.parse_known_args(argv)
    tally = Tally(args.hang_after if args.run else None)
    pytest_args = ["-q", "-p", "no:cacheprovider", "-n", "0", "-m", "hostile", "--rootdir", str(ROOT), *(extra or [str(ROOT / "tests")])]
    if not args.run:
        pytest_args[:1] = ["--collect-only", "-qq"]
    code = pytest.main(pytest_args, plugins=[tally])
    print(f"\nhostile matrix: {len(tally.cases)} cases by kind and declared outcome")
    print(table({node: outcome for node, (_, outcome) in tally.cases.items()}, tally.cases, OUTCOMES))
    if args.run:
        ran = {node: tally.result.get(node, "not run") for node in tally.cases}
        print(f"\nrun: outcome of each case (a failure: {', '.join(FAILED)})")
        print(table(ran, tally.cases, (*OUTCOMES, "internal error", "hang"), ("failed", "skipped", "not run")))
        for node, outcome in sorted(ran.items()):
            if outcome in (*FAILED, "not run"):
                print(f"{outcome}: {node}")
    return int(code) if args.run else 0


if __name__ == "__main__":
    sys.exit(main())

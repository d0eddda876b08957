"""Puts the repository's ``tests/`` folder on ``sys.path``: the reference implementations the
benchmarks time against live there (``tests/reference_*.py``, ``tests/rocking_reference.py``).

A benchmark runs as a script (``python benchmarks/bench_x.py``), so ``benchmarks/`` is on the
path; ``import tests_path`` before importing a reference module.
"""

import sys
from pathlib import Path

TESTS = Path(__file__).resolve().parents[1] / "tests"

if str(TESTS) not in sys.path:
    sys.path.insert(0, str(TESTS))

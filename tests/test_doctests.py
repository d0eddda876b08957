"""The examples in the docstrings of every module run and say what they print (the public
API's modules, whose examples need a record and a cache, run in ``tests/api``)."""

from __future__ import annotations

import doctest
import importlib
import pkgutil

import pytest

import rockdec

#: Modules whose examples run with fixtures (a result, a cache): ``tests/api/test_public_api.py``.
WITH_FIXTURES = ("rockdec.api", "rockdec.report.result", "rockdec.cache")

MODULES = sorted(m.name for m in pkgutil.walk_packages(rockdec.__path__, "rockdec.")
                 if m.name not in WITH_FIXTURES and not m.name.endswith("__main__"))  # importing __main__ runs the command line


def test_every_module_is_read():
    assert "rockdec.calibrate.belt" in MODULES and "rockdec.studies.coverage" in MODULES


@pytest.mark.parametrize("module", MODULES)
def test_docstring_examples_run(module):
    mod = importlib.import_module(module)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    for test in doctest.DocTestFinder().find(mod, module):
        if test.examples:
            runner.run(test)
    assert runner.summarize(verbose=False).failed == 0

"""The suite's own hygiene: no test module defines a name twice (the later definition hides
the earlier one, whose test then never runs and never fails)."""

import ast
from pathlib import Path

TESTS = Path(__file__).resolve().parent


def twice_defined(source: str) -> list[str]:
    """The names that ``source``'s module body defines more than once by ``def`` or ``class``."""
    names = [n.name for n in ast.parse(source).body if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef))]
    return sorted({n for n in names if names.count(n) > 1})


def test_a_name_defined_twice_is_found():
    assert twice_defined("def test_a():\n    pass\n\n\ndef test_b():\n    pass\n\n\ndef test_a():\n    pass\n") == ["test_a"]
    assert twice_defined("def test_a():\n    pass\n\n\nclass TestA:\n    pass\n") == []


def test_no_module_of_the_suite_defines_a_name_twice():
    found = {p.relative_to(TESTS).as_posix(): twice_defined(p.read_text()) for p in sorted(TESTS.rglob("*.py"))}
    assert len(found) > 50 and {m: names for m, names in found.items() if names} == {}

"""The CF 1.10 compliance checker (IOOS compliance-checker, a test dependency), as the tests call it.

It needs no system library: its units package ships UDUNITS-2 in its wheel.
"""

from __future__ import annotations

import functools
import warnings

CHECKER = "cf:1.10"


class CheckerRaised(AssertionError):
    """A check of the CF checker raised on a file: that check said nothing about it."""


@functools.cache
def _check_suite() -> type:
    """The checker's ``CheckSuite`` with every installed checker loaded, imported at the first
    check (not when a test module imports this one: about 0.7 s)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)  # the checker's own SOS plugins
        from compliance_checker.suite import CheckSuite

        CheckSuite.load_all_available_checkers()
    return CheckSuite


def cf_findings(path, tmp_path=None) -> dict[str, list[str]]:
    """Every message of the CF 1.10 checker on ``path``, at every priority:
    ``{"errors": [...], "warnings": [...], "notes": [...]}`` (high, medium, low).

    Raises :class:`CheckerRaised` naming each check that raised (the checker itself only
    prints those to standard error and goes on). ``tmp_path`` is not used.
    """
    suite = _check_suite()()
    ds = suite.load_dataset(str(path))
    try:
        groups, raised = suite.run_all(ds, [CHECKER])[CHECKER]
    finally:
        ds.close()
    if raised:
        raise CheckerRaised(f"{path}: " + "; ".join(f"{name}: {err[0]}" for name, err in raised.items()))
    report = suite.dict_output(CHECKER, groups, str(path), limit=1)  # limit 1: every priority
    return {
        kind: [msg for check in report[key] for msg in check["msgs"]]
        for kind, key in (("errors", "high_priorities"), ("warnings", "medium_priorities"), ("notes", "low_priorities"))
    }


NO_FINDINGS = {"errors": [], "warnings": [], "notes": []}
"""What :func:`cf_findings` returns on a clean file."""

"""The CF 1.10 compliance checker (IOOS compliance-checker, a test dependency), as the tests call it.

It needs no system library: its units package ships UDUNITS-2 in its wheel.
"""

from __future__ import annotations

import json
import warnings

with warnings.catch_warnings():
    warnings.simplefilter("ignore", DeprecationWarning)  # the checker's own SOS plugins
    from compliance_checker.runner import CheckSuite, ComplianceChecker

    CheckSuite.load_all_available_checkers()


def cf_findings(path, tmp_path) -> dict[str, list[str]]:
    """The CF 1.10 checker's messages on ``path``: ``{"errors": [...], "warnings": [...]}``."""
    report = tmp_path / f"{path.name}.cf.json"
    ComplianceChecker.run_checker(
        str(path), ["cf:1.10"], verbose=0, criteria="normal", output_filename=str(report), output_format="json"
    )
    result = json.loads(report.read_text())["cf:1.10"]
    return {
        kind: [msg for check in result[key] for msg in check["msgs"]]
        for kind, key in (("errors", "high_priorities"), ("warnings", "medium_priorities"))
    }

"""The shake-table study (rockdec.studies.shake_coverage) on a small grid."""

import pytest

from rockdec.studies import shake_coverage


@pytest.mark.slow
def test_the_study_tallies_each_cell_and_pools_them():
    cells = shake_coverage.run_grid(e_values=(0.95,), peaks=(3.0,), noise=(0.0, 0.01), records=3)
    assert [(c["e"], c["peak"], c["noise"], c["records"]) for c in cells] == [(0.95, 3.0, 0.0, 3), (0.95, 3.0, 0.01, 3)]
    for c in cells:
        assert c["covered"] <= c["answered"] == len(c["widths"]) and c["answered"] + sum(c["why"].values()) == c["records"]
        tails, forced = c["readings"]["tails"], c["readings"]["forced"]
        # the test's e is the tails' where they answer, else the forced reading's
        assert max(tails["answered"], forced["answered"]) <= c["answered"] <= tails["answered"] + forced["answered"]
    # e = 0.95 shaken at 3 uplift levels leaves long tails: most records answer and hold e
    assert sum(c["covered"] for c in cells) >= 4
    text = shake_coverage.markdown(cells)
    assert len(text.splitlines()) == 2 + len(cells) + 1 + len(shake_coverage.READINGS) and "Pooled, forced:" in text

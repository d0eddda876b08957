"""The warnings' study (rockdec.studies.diagnostics_study): its records and its summary, without
calibrations (the study itself runs in the workflow)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from conftest import calibrated_step
from rockdec.record import diagnostics
from rockdec.studies import diagnostics_study as ds
from rockdec.physics.simulate import simulate_block
from rockdec.pipeline.layout import DIAGNOSTICS_E, DIAGNOSTICS_PARTS

E, N = 0.9, 20_000


@pytest.fixture(scope="module")
def step():
    return calibrated_step(E, 1.0, 1.0, ds.POINTS_PER_CYCLE)


def test_a_noisy_record_is_the_clean_one_plus_noise_of_its_share_of_the_rms(step):
    clean = ds.record(E, 11, N, step["dt"], step["burn_in"], None, 0.0, 0.0)
    np.testing.assert_array_equal(clean, ds.simulate(E, 11, N, step["dt"], step["burn_in"]))
    noisy = ds.record(E, 11, N, step["dt"], step["burn_in"], None, 0.0, 0.03)
    assert np.std(noisy - clean) / np.sqrt(np.mean(clean**2)) == pytest.approx(0.03, rel=0.03)


def test_a_coloured_record_is_the_kernels_with_the_same_pole_and_a_lean_pushes_it_one_way(step):
    """Under a low-pass load the clean record equals the compiled kernel's of the same seed and
    pole (drawn apart, rockdec.physics.simulate.simulate_block); a lean of b = 0.3 moves the
    record's median towards the side it weakens and reads as asymmetry."""
    pole = 0.78
    clean = ds.record(E, 13, N, step["dt"], step["burn_in"], None, 0.0, 0.0, pole)
    kernel, _ = simulate_block([13], N, dt=step["dt"], g=1.0, e=E, sigma_p=1.0, burn_in=step["burn_in"], pole=pole)
    np.testing.assert_array_equal(clean, kernel[0])
    leaning = ds.record(E, 13, N, step["dt"], step["burn_in"], "asymmetry", 0.3, 0.0, pole)
    assert np.median(leaning) > np.median(clean)
    asymmetry = (lambda y: diagnostics.asymmetry(diagnostics.sums([y]), None))
    assert asymmetry(leaning) > 0.1 > asymmetry(clean)


def test_a_defect_rides_on_the_same_noise_as_its_clean_record(step):
    """Pairing: the drifting record less the clean one, both at 5 % noise, is the trend alone."""
    clean = ds.record(E, 12, N, step["dt"], step["burn_in"], None, 0.0, 0.05)
    drifting = ds.record(E, 12, N, step["dt"], step["burn_in"], "drift", 1.0, 0.05)
    sigma = np.std(ds.simulate(E, 12, N, step["dt"], step["burn_in"]))
    np.testing.assert_allclose(drifting - clean, sigma * np.linspace(-0.5, 0.5, N), atol=1e-12 * sigma)


def test_the_summary_reads_false_alarms_and_detections_per_noise_level():
    rows = []
    for noise, fires in ((0.0, (True, False, False, False)), (0.05, (False, False, False, False))):
        for seed, fired in enumerate(fires):
            row = {"e_true": E, "noise": noise, "corner": 0.0, "defect": "clean", "size": 0.0, "seed": seed, "e_hat": E, "low": E - 0.02, "high": E + 0.02}
            row.update({f"{c}_fired": fired and c == "drift" for c in diagnostics.CHECKS})
            rows.append(row)
            defective = dict(row, defect="drift", size=1.0, e_hat=E + 0.05 * (noise == 0.0))
            defective.update({f"{c}_fired": c == "drift" and seed < 3 for c in diagnostics.CHECKS})
            rows.append(defective)
    s = ds.summary(pd.DataFrame(rows)).set_index(["check", "noise", "size"])
    assert s.loc[("drift", 0.0, 0.0), "fired_pct"] == 25.0 and s.loc[("drift", 0.05, 0.0), "fired_pct"] == 0.0
    assert s.loc[("drift", 0.0, 1.0), "fired_pct"] == 75.0 and s.loc[("drift", 0.0, 1.0), "matters"]
    assert not s.loc[("drift", 0.05, 1.0), "matters"]  # at 5 % noise the defect does not move e here
    declined = pd.DataFrame([{"e_true": E, "noise": 0.02, "corner": 1.0, "defect": "clean", "size": 0.0, "seed": k, "e_hat": np.nan,
                              "low": np.nan, "high": np.nan, "calibration": np.nan} for k in range(3)])
    empty = ds.summary(declined)  # every record declined: no checks, no rates
    assert list(empty["check"]) == list(diagnostics.CHECKS) and (empty["records"] == 0).all() and empty["fired_pct"].isna().all()


def test_a_record_that_rockdec_estimate_declines_asks_for_no_calibration(step):
    """A record under a low-pass load with its corner at the rocking frequency (below the
    floor at which a calibration tells the colour apart from e) is declined by ``rockdec
    estimate``, so the study builds no calibration for it; a white one gets its settings."""
    from rockdec import estimation
    from rockdec.report.estimate_report import document
    from rockdec.physics.record_model import Load

    pole = Load("lowpass", 1.0).pole(ds.POINTS_PER_CYCLE)
    coloured = ds._cell(E, None, 0.0, 0.0, [14], N, 2.513, 4362, pole)  # the step of 75 samples per cycle under that load
    white = ds._cell(E, None, 0.0, 0.0, [14], N, step["dt"], step["burn_in"], 0.0)
    assert coloured[0][0] is None and white[0][0] is not None
    y = ds.record(E, 14, N, 2.513, 4362, None, 0.0, 0.0, pole)
    assert document(estimation.estimate([ds.Record(y, 2.513, "coloured")], cache_dir=None))["reason"]  # declined, with its reason


def test_the_workflow_parts_together_give_the_rows_of_one_run_of_all(monkeypatch):
    """The workflow's jobs (DIAGNOSTICS_PARTS: one e, load and noise level each) make, put
    together, exactly the rows of one run over every e, load and noise level, each row once.
    (The simulation and the estimates are stood in for: only the cells and their seeds are read.)"""
    monkeypatch.setattr(ds, "_cell", lambda *args: [(None, 0.0, 0.0)] * len(args[4]))
    monkeypatch.setattr(ds, "_estimates", lambda *args: [None] * len(args[4]))
    monkeypatch.setattr(ds, "_step", lambda e, corner, ppc, n, seed0: {"dt": 1.0, "burn_in": 10, "pole": 0.5 * (corner > 0.0)})
    small = {"n_records": 2, "defects": {"drift": (1.0,), "asymmetry": (0.1,)}}
    whole = ds.run(**small)
    parts = pd.concat([ds.run(e_values=(e,), corners=(corner,), noise_levels=(noise,), **small)
                       for e, corner, noise in DIAGNOSTICS_PARTS.values()], ignore_index=True)
    keys = ["e_true", "corner", "noise", "defect", "size", "seed"]
    pd.testing.assert_frame_equal(parts.sort_values(keys).reset_index(drop=True), whole.sort_values(keys).reset_index(drop=True))
    assert not whole.duplicated(keys).any()
    assert set(whole["corner"]) == {0.0, 3.0} and (whole.loc[whole["corner"] == 3.0, "defect"] != "drift").all()


def test_a_run_of_one_e_gives_the_rows_a_run_of_all_gives_it(monkeypatch):
    """The workflow runs the study one ``e`` a job: the records of an ``e`` draw the seeds of
    its place in DIAGNOSTICS_E, whichever values a run holds; an ``e`` that is not the study's is
    refused in one sentence that names where the values live. (The step search, the
    simulation and the estimates are stood in for: only the cells and their seeds are read.)"""
    monkeypatch.setattr(ds, "_step", lambda *args: {"dt": 1.0, "burn_in": 0, "pole": 0.0})
    monkeypatch.setattr(ds, "_cell", lambda *args: [(None, 0.0, 0.0)] * len(args[4]))
    monkeypatch.setattr(ds, "_estimates", lambda *args: [None] * len(args[4]))
    small = {"n_records": 3, "noise_levels": (0.0,), "corners": (0.0,), "defects": {}}
    whole = ds.run(**small)
    one = ds.run(e_values=(DIAGNOSTICS_E[2],), **small)
    pd.testing.assert_frame_equal(one, whole[whole["e_true"] == DIAGNOSTICS_E[2]].reset_index(drop=True))
    assert whole["seed"].nunique() == len(whole)
    with pytest.raises(ValueError, match="DIAGNOSTICS_E"):
        ds.run(e_values=(0.7,), **small)


def test_the_digest_reads_each_checks_false_alarms_and_the_share_caught_where_the_defect_matters():
    """Two noise levels of 40 and 20 clean records (drift fired on 2 and on none) and the
    drift of size 1 that moves e at noise 0 only (fired on 30 of 40): false alarms worst
    5 %, mean (2 + 0) / 60; caught 75 % at size 1 in the one cell where it matters; a check
    with no defect studied says so rather than a rate."""
    rows = []
    for noise, n, alarms in ((0.0, 40, 2), (0.05, 20, 0)):
        for seed in range(n):
            row = {"e_true": E, "noise": noise, "corner": 0.0, "defect": "clean", "size": 0.0, "seed": seed, "e_hat": E, "low": E - 0.02, "high": E + 0.02}
            row.update({f"{c}_fired": c == "drift" and seed < alarms for c in diagnostics.CHECKS})
            rows.append(row)
            defective = dict(row, defect="drift", size=1.0, e_hat=E + 0.05 * (noise == 0.0))
            defective.update({f"{c}_fired": c == "drift" and seed < 30 for c in diagnostics.CHECKS})
            rows.append(defective)
    digest = ds.digest(ds.summary(pd.DataFrame(rows))).set_index("check")
    drift = digest.loc["drift"]
    assert drift["false_white_worst"] == 5.0 and drift["false_white_mean"] == pytest.approx(100 * 2 / 60)
    assert drift["false_white_by_noise"] == "0 %: 5.0; 5 %: 0.0" and np.isnan(drift["false_lowpass_mean"])
    assert drift["caught_mean"] == 75.0 and drift["caught_lowest"] == 75.0 and drift["caught_sizes"] == "1"
    assert not digest.loc["filtered", "defect_studied"] and np.isnan(digest.loc["filtered", "caught_mean"])
    text = ds.digest_markdown(digest.reset_index())
    assert "| `drift` | 5.0 % (3.3 %) |" in text and "its defect is not studied here" in text


def test_a_cell_whose_records_are_all_declined_is_caught_in_full():
    """Every defective record declined (no record checked), some of their clean twins
    declined too: the records that had an e all lost it, so the cell counts as caught."""
    rows = pd.DataFrame({"check": "asymmetry", "e_true": 0.98, "noise": 0.05, "corner": 0.0, "size": [0.0, 0.3], "records": [40, 0],
                         "lost_pct": [0.0, 82.5], "matters": [False, True], "fired_pct": [0.0, np.nan]})
    assert ds.digest(rows).loc[0, "caught_lowest"] == 100.0

"""The shake-table test's front door: :func:`rockdec.shake_table` and ``rockdec estimate --test
shake``, on records of the independent transient generator (tests/transient_reference.py)."""

import json
import math

import jsonschema
import numpy as np
import pandas as pd
import pytest
import xarray as xr

import rockdec
import transient_reference as tr
from cf_check import cf_findings
from rockdec import io
from rockdec.cli import main
from rockdec.free.shake import G0
from rockdec.report import result as result_mod

DT = 1 / tr.FS


@pytest.fixture(scope="module")
def shaken():
    """A record of e = 0.9 with 1 % sensor noise and its base in rad/s^2 (uplift level tr.G)."""
    return tr.transient_with_base(0.9, 1)


def test_the_shake_table_test_is_the_same_result_object(shaken, tmp_path):
    theta, base = shaken
    res = rockdec.shake_table(theta, base, DT, base_units="rad/s2", g_block=tr.G)
    assert res.test == "shake" and res.confidence_interval.low <= 0.9 <= res.confidence_interval.high
    doc = json.loads(json.dumps(res.to_dict()))
    jsonschema.validate(doc, result_mod.schema())
    assert rockdec.RestitutionEstimate.from_dict(doc).to_dict() == res.to_dict()
    table = doc["shake_table"]
    assert len(table["tails"]) >= 1 and all(t["start"] >= table["shaking_end"][0] for t in table["tails"])
    assert sum(t["impacts"] for t in table["tails"]) == len(res.impacts) and (res.impacts["time"] >= table["shaking_end"][0]).all()
    text = res.summary()
    assert text.startswith(f"e = {res.e:.4f}") and "the shaking ends at" in text
    path = io.write_netcdf(res.to_dataset(), tmp_path / "shake.nc")
    assert cf_findings(path) == {"errors": [], "warnings": [], "notes": []}
    assert len(res.plot().axes) == 2


@pytest.mark.slow
def test_the_base_in_any_units_gives_the_same_tails(shaken):
    """Invariance: the base in m/s^2 (level g tan(alpha)) or in g, scaled to the same uplift
    ratio, reads the same shaking end and the same e as in rad/s^2."""
    theta, base = shaken
    ref = rockdec.shake_table(theta, base, DT, base_units="rad/s2", g_block=tr.G)
    theta_cr = 0.2
    level = math.tan(theta_cr)
    in_ms2 = rockdec.shake_table(theta, base / tr.G * G0 * level, DT, base_units="m/s2", theta_cr=theta_cr)
    in_g = rockdec.shake_table(theta, xr.DataArray(base / tr.G * level, dims="time", attrs={"units": "g"}), DT, theta_cr=theta_cr)
    for other in (in_ms2, in_g):
        assert other.to_dict()["shake_table"]["tails"] == ref.to_dict()["shake_table"]["tails"]
        assert other.e == pytest.approx(ref.e, rel=1e-12)


@pytest.mark.slow
def test_records_of_one_block_are_pooled(shaken):
    theta, base = shaken
    other_theta, other_base = tr.transient_with_base(0.9, 0)
    res = rockdec.shake_table([theta, other_theta], [base, other_base], DT, base_units="rad/s2", g_block=tr.G)
    assert sorted({t["record"] for t in res.to_dict()["shake_table"]["tails"]}) == [0, 1]
    assert set(res.impacts["record"]) == {0, 1}


def test_a_base_that_never_lifts_the_block_is_declined_with_its_reason(shaken):
    theta, base = shaken
    res = rockdec.shake_table(theta, 0.5 * base / np.abs(base).max(), DT, base_units="rad/s2", g_block=tr.G)
    assert res.e is None and "never lifts" in res.reason and "not estimated" in res.summary()
    jsonschema.validate(json.loads(json.dumps(res.to_dict())), result_mod.schema())


@pytest.mark.parametrize("bad, match", [
    (dict(), "base_units"),
    (dict(base_units="cm/s2", g_block=tr.G), "cm/s2"),
    (dict(base_units="m/s2"), "critical angle"),
    (dict(base_units="rad/s2"), "g_block"),
])
def test_a_base_without_its_units_or_block_is_refused(shaken, bad, match):
    theta, base = shaken
    with pytest.raises(rockdec.InputError, match=match):
        rockdec.shake_table(theta, base, DT, **bad)


def test_a_base_sampled_otherwise_than_the_angle_is_refused(shaken):
    theta, base = shaken
    coarse = xr.DataArray(base[::2], dims="time", coords={"time": 2 * DT * np.arange(base[::2].size)}, attrs={"units": "rad/s2"})
    with pytest.raises(rockdec.RecordError, match="resample the base"):
        rockdec.shake_table(theta, coarse, DT, g_block=tr.G)
    with pytest.raises(rockdec.RecordError, match="samples"):
        rockdec.shake_table(theta, base[::2], DT, base_units="rad/s2", g_block=tr.G)
    with pytest.raises(rockdec.InputError, match="one base acceleration per record"):
        rockdec.shake_table([theta, theta], [base], DT, base_units="rad/s2", g_block=tr.G)


@pytest.mark.slow
def test_the_command_line_runs_the_shake_table_test(shaken, tmp_path, capsys):
    theta, base = shaken
    time = DT * np.arange(theta.size)
    pd.DataFrame({"time": time, "theta": theta}).to_csv(tmp_path / "theta.csv", index=False)
    xr.Dataset({"base": ("time", base, {"units": "rad s-2"})}, coords={"time": time}).to_netcdf(tmp_path / "base.nc")
    record, base_file = str(tmp_path / "theta.csv"), str(tmp_path / "base.nc")
    assert main(["-q", "estimate", record, "--test", "shake", "--base", base_file, "--g", str(tr.G), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["test"] == "shake" and doc["e"] == rockdec.shake_table(theta, base, DT, base_units="rad/s2", g_block=tr.G).e
    assert main(["estimate", record, "--base", base_file]) == 2
    assert "--test shake" in capsys.readouterr().err
    assert main(["estimate", record, "--test", "shake"]) == 2
    assert "one --base file per record file" in capsys.readouterr().err
    assert main(["estimate", record, "--test", "shake", "--base", base_file, "--base-units", "g", "--block", "1,0.2"]) == 2
    assert "disagrees" in capsys.readouterr().err
    in_g = tmp_path / "base_g.csv"
    pd.DataFrame({"time": time, "base": base / tr.G * math.tan(0.2)}).to_csv(in_g, index=False)
    assert main(["-q", "estimate", record, "--test", "shake", "--base", str(in_g), "--base-units", "g", "--theta-cr", "0.2", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["e"] == pytest.approx(doc["e"], rel=1e-9)  # --theta-cr for a base in g, no Housner needed

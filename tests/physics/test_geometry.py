"""A block's geometry (``block=(H, B)``, ``--block H,B``): the critical angle and Housner's
``e`` against the closed form ``sin^2(atan x) = x^2/(1 + x^2)``, the report's line and the
refusals."""

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import rockdec
from rockdec.physics.geometry import Block, parse_block
from rockdec.report.result import schema
from rockdec.validate import InputError

hostile = pytest.mark.hostile


@settings(deadline=None)  # a loaded machine's first call may pass hypothesis's 200 ms
@given(st.floats(1e-3, 1e3), st.floats(1e-3, 1e3))
def test_housner_e_is_the_closed_form_and_scale_free(height, width):
    x = width / height
    block = Block(height, width)
    assert block.housner_e == pytest.approx(1.0 - 1.5 * x * x / (1.0 + x * x), abs=1e-12)
    assert block.theta_cr == pytest.approx(math.atan(x), rel=1e-12)  # tan near pi/2 would amplify the last bit by x
    assert Block(7.0 * height, 7.0 * width).housner_e == pytest.approx(block.housner_e, abs=1e-12)


BAD_BLOCKS = {
    "text one": "0.6", "text three": "0.6,0.2,1", "text words": "a,b", "text semicolon": "0.6;0.2", "text zero": "0,0.2",
    "text negative": "-1,0.2", "text nan": "nan,0.2", "text inf": "inf,1", "text empty": "",
    "one number": 0.6, "three numbers": (0.6, 0.2, 1.0), "words": ("a", "b"), "zero": (0.0, 0.2), "negative": (0.6, -0.2),
    "nan": (math.nan, 0.2), "inf": (1.0, math.inf), "bool": (True, 0.2), "empty": (),
}


@pytest.mark.parametrize("value", [pytest.param(v, id=k, marks=hostile("numbers", "refused")) for k, v in BAD_BLOCKS.items()])
def test_a_block_that_is_not_a_height_and_a_width_is_refused(value):
    with pytest.raises(InputError, match="height|width") as err:
        parse_block(value)
    assert len(str(err.value).splitlines()) == 1


@pytest.fixture(scope="module")
def release():
    return rockdec.simulate(0.85, 3000, seed=0, sigma_p=0.0, theta0=0.01)


def test_the_free_test_sets_housners_e_beside_the_measured_one(release):
    res = rockdec.free_rocking(release, block=(0.6, 0.2))
    doc = res.to_dict()
    import jsonschema

    jsonschema.validate(json.loads(json.dumps(doc)), schema())
    block = doc["block"]
    assert block["housner_e"] == pytest.approx(1.0 - 1.5 * 0.1, abs=1e-12)  # sin^2(atan(1/3)) = 1/10
    assert block["e_over_housner"] == pytest.approx(res.e / block["housner_e"], rel=1e-12)
    assert "Housner's e = 1 - 1.5 sin^2(theta_cr) = 0.8500" in res.summary()
    assert "block" not in rockdec.free_rocking(release).to_dict()


def test_the_housner_model_takes_its_critical_angle_from_the_block(release):
    res = rockdec.free_rocking(release, model="housner", block=(0.6, 0.2))
    assert res.to_dict()["theta_cr"] == pytest.approx(math.atan(1 / 3), rel=1e-12)
    same = rockdec.free_rocking(release, model="housner", theta_cr=math.atan(1 / 3), block=(0.6, 0.2))
    assert same.e == pytest.approx(res.e, rel=1e-12)


@hostile("numbers", "refused")
@pytest.mark.parametrize("entry", ["free_rocking", "estimate"])
def test_a_critical_angle_that_is_not_the_blocks_is_refused(release, entry):
    with pytest.raises(InputError, match="atan") as err:
        getattr(rockdec, entry)(release, model="housner", theta_cr=0.2, block=(0.6, 0.2))
    assert len(str(err.value).splitlines()) == 1


def test_the_random_tests_document_carries_the_block():
    from rockdec.report.summary import block_lines, with_block

    doc = with_block({"e": None}, Block(1.0, 0.25))
    assert doc["block"]["e_over_housner"] is None and np.isclose(doc["block"]["housner_e"], 1 - 1.5 * 0.25**2 / (1 + 0.25**2))
    assert "measured e" not in block_lines(doc)[0] and "Housner's e" in block_lines(doc)[0]


@pytest.mark.parametrize("argv, words", [
    pytest.param(["--block", "0.6"], ["--block", "H,B"], id="one number", marks=hostile("numbers", "refused")),
    pytest.param(["--block", "0.6,0.2", "--model", "housner", "--theta-cr", "0.1"], ["--theta-cr", "atan(B/H)"], id="other angle",
                 marks=hostile("numbers", "refused")),
])
def test_the_command_refuses_a_bad_block_before_reading_the_record(tmp_path, capsys, argv, words):
    from rockdec.cli import main

    code = main(["estimate", str(tmp_path / "absent.csv"), "--test", "free", *argv])
    err = capsys.readouterr().err
    assert code == 2 and all(w in err for w in words) and "absent" not in err, err


def test_the_command_prints_housners_e(tmp_path, release, capsys):
    from rockdec.cli import main

    release.to_netcdf(tmp_path / "release.nc")
    assert main(["estimate", str(tmp_path / "release.nc"), "--test", "free", "--block", "0.6,0.2", "--model", "housner"]) == 0
    assert "Housner's e = 1 - 1.5 sin^2(theta_cr) = 0.8500" in capsys.readouterr().out

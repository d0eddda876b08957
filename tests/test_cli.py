"""The command line: clear one-sentence errors with exit code 2, no partial files."""

import subprocess
import sys

import numpy as np
import pytest
import xarray as xr

from rockdec.cli import main


def run(args, capsys):
    code = main(args)
    return code, capsys.readouterr().err


@pytest.mark.parametrize(
    "args, names",
    [
        (["--e", "1.5"], "--e 1.5"),
        (["--e", "-0.1"], "--e -0.1"),
        (["--n-points", "-5"], "--n-points -5"),
        (["--burn-in", "-1"], "--burn-in -1"),
        (["--seeds", "3-1"], "--seeds '3-1'"),
        (["--scene", "nope", "--config", "config/config.yaml"], "unknown scene 'nope'"),
        (["--config", "no/such.yaml", "--scene", "paper"], "cannot read the config file"),
    ],
)
def test_bad_simulate_input_names_the_field_and_exits_2(tmp_path, capsys, args, names):
    out = tmp_path / "out.nc"
    code, err = run(["simulate", "--out", str(out), *args], capsys)
    assert code == 2
    assert names in err
    assert "Traceback" not in err
    assert not out.exists() and not list(tmp_path.iterdir())


def test_unwritable_or_existing_output_is_refused(tmp_path, capsys):
    code, err = run(["simulate", "--out", str(tmp_path / "missing" / "x.nc")], capsys)
    assert code == 2 and "does not exist" in err
    existing = tmp_path / "x.nc"
    existing.write_text("keep me")
    code, err = run(["simulate", "--out", str(existing)], capsys)
    assert code == 2 and "--overwrite" in err
    assert existing.read_text() == "keep me"


def test_e_one_needs_an_explicit_step(tmp_path, capsys):
    code, err = run(["simulate", "--out", str(tmp_path / "x.nc"), "--e", "1"], capsys)
    assert code == 2 and "--dt" in err


def test_free_response_run_writes_the_analytic_start(tmp_path, capsys):
    out = tmp_path / "free.nc"
    code, _ = run(
        ["simulate", "--out", str(out), "--sigma-p", "0", "--theta0", "1", "--burn-in", "0",
         "--seeds", "0", "--n-points", "100", "--e", "0.9", "--nu", "1", "--theta-cr", "1"],
        capsys,
    )
    assert code == 0
    with xr.open_dataset(out, decode_times=False) as ds:  # time in s from the end of the burn-in
        assert ds.theta.dtype == "float32"
        assert ds.theta.attrs["units"] == "rad"
        dt = ds.attrs["dt"]
        t = ds.time.values
        # before the first impact (t1 = sqrt(2), g = 1) the parabola 1 - t^2/2
        before = t < 2**0.5
        assert abs(ds.theta.values[0, before] - (1 - t[before] ** 2 / 2)).max() < 1e-6
        assert dt == pytest.approx(4 * 2**0.5 / 75)  # eq. 5 at amplitude 1, 75 points per cycle


def test_console_script_exit_code_is_2_without_traceback(tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "rockdec.cli", "simulate", "--out", str(tmp_path / "x.nc"), "--e", "2"],
        capture_output=True, text=True,
    )
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr and "--e 2" in proc.stderr


def test_simulate_signatures_estimates_chain_gives_e_with_an_error_bar(tmp_path, capsys):
    sim, sig, est = (tmp_path / n for n in ("sim.nc", "sig.nc", "est.nc"))
    assert main(["simulate", "--out", str(sim), "--seeds", "0-59", "--scene", "tiny"]) == 0
    assert main(["signatures", str(sim), "--out", str(sig)]) == 0
    capsys.readouterr()
    assert main(["estimates", str(sig), "--out", str(est)]) == 0
    printed = capsys.readouterr().out
    assert "e_v:" in printed and "+-" in printed
    with xr.open_dataset(est) as ds:
        e_v = float(ds.e_hat0.sel(estimator="e_v", replicate=0))
        assert abs(e_v - 0.95) < 0.02  # 60 series: the D_v estimate scatters ~0.005


def test_signatures_refuses_a_file_without_the_record(tmp_path, capsys):
    bad = tmp_path / "bad.nc"
    xr.Dataset({"x": ("time", [0.0, 1.0])}).to_netcdf(bad)
    code, err = run(["signatures", str(bad), "--out", str(tmp_path / "o.nc")], capsys)
    assert code == 2 and "--variable" in err
    code, err = run(["estimates", str(bad), "--out", str(tmp_path / "o.nc")], capsys)
    assert code == 2 and "not a signature file" in err
    code, err = run(["signatures", str(tmp_path / "none.nc"), "--out", str(tmp_path / "o.nc")], capsys)
    assert code == 2 and "does not exist" in err


@pytest.mark.parametrize("model", ["simplified", "housner"])
def test_model_option_chooses_the_model_the_file_records(tmp_path, model):
    out = tmp_path / "sim.nc"
    args = ["simulate", "--out", str(out), "--seeds", "0-1", "--n-points", "100", "--dt", "0.01", "--burn-in", "0"]
    assert main([*args, "--scene", "tiny", "--model", model]) == 0  # the option overrides the scene's auto
    with xr.open_dataset(out) as ds:
        assert ds.attrs["model"] == model and ds.attrs["model_reason"] == "requested"


def test_unknown_model_names_the_option_and_writes_nothing(tmp_path, capsys):
    code, err = run(["simulate", "--out", str(tmp_path / "x.nc"), "--model", "rigid"], capsys)
    assert code == 2 and "--model 'rigid'" in err and "housner" in err
    assert not list(tmp_path.iterdir())


def test_group_size_one_keeps_the_seeds_and_estimates_accepts_the_cube(tmp_path, capsys):
    sim, per_seed, pooled, est = (tmp_path / n for n in ("sim.nc", "per_seed.nc", "pooled.nc", "est.nc"))
    assert main(["simulate", "--out", str(sim), "--seeds", "3,5,8", "--scene", "tiny"]) == 0
    assert main(["signatures", str(sim), "--out", str(per_seed), "--group-size", "1"]) == 0
    assert main(["signatures", str(sim), "--out", str(pooled), "--group-size", "3"]) == 0
    with xr.open_dataset(per_seed) as cube, xr.open_dataset(pooled) as whole:
        assert cube["signature"].dims == ("seed", "trigger", "window", "lag")
        assert "group" not in cube.dims and cube["seed"].values.tolist() == [3, 5, 8]
        # the per-seed sums pool exactly into the 3-series signature (eq. 8)
        assert (cube["count"].sum("seed") == whole["count"].isel(group=0)).all()
        assert abs(cube["signature_sum"].sum("seed") - whole["signature_sum"].isel(group=0)).max() < 1e-12
    capsys.readouterr()
    assert main(["estimates", str(per_seed), "--out", str(est)]) == 0
    assert "e_v:" in capsys.readouterr().out
    with xr.open_dataset(est) as ds:
        assert ds["e_hat"].sizes["replicate"] == 1 and ds["e_hat"].sizes["estimator"] == 7
        assert np.isfinite(ds["e_hat0"].sel(estimator="e_v")).all()

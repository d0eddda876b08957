"""Traceable products: CF 1.10 compliance, history appended from the inputs, input files named."""

from __future__ import annotations

import os
import threading

import numpy as np
import pandas as pd
import pytest
import xarray as xr

from rockdec.pipeline import config, layout, series
from rockdec import io
from rockdec.physics import run
from rockdec.cli import main

from cf_check import NO_FINDINGS, CheckerRaised, cf_findings


@pytest.fixture(scope="module")
def chain(tmp_path_factory):
    """simulate -> signatures -> estimates on 10 series of the tiny scene, through the CLI."""
    root = tmp_path_factory.mktemp("chain")
    paths = {name: root / f"{name}.nc" for name in ("sim", "sig", "est")}
    assert main(["simulate", "--out", str(paths["sim"]), "--seeds", "0-9", "--scene", "tiny"]) == 0
    assert main(["signatures", str(paths["sim"]), "--out", str(paths["sig"])]) == 0
    assert main(["estimates", str(paths["sig"]), "--out", str(paths["est"])]) == 0
    return paths


@pytest.mark.parametrize("name", ["sim", "sig", "est"])
def test_every_product_passes_every_check_of_the_cf_checker_without_a_finding(chain, name):
    assert cf_findings(chain[name]) == NO_FINDINGS


def test_the_cf_test_fails_when_a_check_of_the_checker_raises(tmp_path):
    # a coordinate variable of variable-length strings: the monotonicity check raises on it
    path = tmp_path / "strings.nc"
    xr.Dataset({"y": ("k", [1.0, 2.0], {"units": "1", "long_name": "y"})}, coords={"k": ["a", "b"]}).to_netcdf(path)
    with pytest.raises(CheckerRaised, match="monotonicity"):
        cf_findings(path)


def test_label_coordinates_are_stored_as_characters_and_read_back_as_the_same_index(tmp_path):
    ds = xr.Dataset(
        {"e_hat": (("estimator", "trigger"), np.arange(6.0).reshape(3, 2), {"units": "1", "long_name": "estimate"})},
        coords={"estimator": ["e_g", "e1", "e_v"], "trigger": ["a", "v"]},
        attrs=io.provenance("estimates"),
    )
    # a label index made by pandas (NumPy's StringDType under pandas 3), as the readings are
    ds = xr.concat([ds, ds + 10.0], dim=pd.Index(["pooled", "per_series"], name="reading"), combine_attrs="override")
    path = io.write_netcdf(ds, tmp_path / "labels.nc")
    with xr.open_dataset(path) as back:  # plain xarray, no rockdec decoding
        assert back["estimator"].values.tolist() == ["e_g", "e1", "e_v"]
        assert float(back["e_hat"].sel(estimator="e_v", trigger="a", reading="per_series")) == 14.0
    assert cf_findings(path) == NO_FINDINGS


def test_series_files_opened_together_keep_the_replicate_of_every_series(tmp_path):
    scene = config.validate_scene(
        {"excitation": {"dt": 0.0034, "burn_in": 10}, "records": {"n_points": 50, "replicates": 2, "series_per_replicate": 3, "chunk_seeds": 2, "store_series": "all"},
         "estimates": {"compare_readings": False}}
    )
    contract = run.from_scene(scene)
    paths = layout.replicate_files(tmp_path, scene["records"])
    (tmp_path / "series").mkdir()
    for r, path in enumerate(paths):
        series.write_replicate(contract, scene["records"], r, path)
    with xr.open_mfdataset(paths, combine="nested", concat_dim="seed", data_vars="minimal", coords="minimal", compat="override") as ds:
        assert ds["replicate"].values.tolist() == [0, 0, 0, 1, 1, 1]
        assert ds["seed"].values.tolist() == list(range(6))
    for path in paths:
        assert cf_findings(path) == NO_FINDINGS


def test_history_is_appended_along_the_chain_and_inputs_are_named(chain):
    attrs = {name: xr.open_dataset(path).attrs for name, path in chain.items()}
    sim, sig, est = (attrs[k]["history"].splitlines() for k in ("sim", "sig", "est"))
    assert len(sim) == 1 and sim[0].endswith("simulate")
    assert sig[:1] == sim and sig[1].endswith(f"signatures {chain['sim']}") and len(sig) == 2
    assert est[:2] == sig and est[2].endswith(f"estimates {chain['sig']}") and len(est) == 3
    assert "source_files" not in attrs["sim"]
    assert attrs["sig"]["source_files"] == str(chain["sim"])
    assert attrs["est"]["source_files"] == str(chain["sig"])
    assert all(a["title"] and a["Conventions"] == "CF-1.10" for a in attrs.values())


def test_time_coordinate_reads_back_as_seconds_from_the_end_of_the_burn_in(chain):
    with xr.open_dataset(chain["sim"]) as ds:
        seconds = (ds["time"] - ds["time"][0]) / np.timedelta64(1, "s")
        assert seconds.values[1] == pytest.approx(ds.attrs["dt"], rel=1e-6)
        assert ds["time"].attrs["standard_name"] == "time"
    with xr.open_dataset(chain["sim"], decode_times=False) as raw:
        assert raw["time"].values[0] == 0.0
        assert "_FillValue" not in raw["time"].encoding


def test_history_of_several_inputs_keeps_each_line_once_oldest_first(tmp_path):
    common = "2000-01-01T00:00:00Z: rockdec x simulate"
    a, b = tmp_path / "a.nc", tmp_path / "b.nc"
    for path, line in ((a, "2000-01-02T00:00:00Z: rockdec x estimates"), (b, "2000-01-03T00:00:00Z: rockdec x readings")):
        io.write_netcdf(xr.Dataset({"x": ("n", [1.0, 2.0])}, attrs={"history": f"{common}\n{line}"}), path)
    attrs = io.provenance("table_readings", {"k": 1}, inputs=[a, b])
    lines = attrs["history"].splitlines()
    assert lines[:3] == [common, "2000-01-02T00:00:00Z: rockdec x estimates", "2000-01-03T00:00:00Z: rockdec x readings"]
    assert len(lines) == 4 and lines[3].endswith(f"table_readings {a} {b}")
    assert attrs["source_files"].splitlines() == [str(a), str(b)]
    assert attrs["title"] == io.TITLES["table_readings"]


def test_the_inputs_history_waits_for_another_thread_that_holds_the_hdf5_lock(tmp_path):
    """The campaign's estimate steps and the workflow's signature step read their inputs'
    history on Snakemake's threads while another step writes a NetCDF file; the HDF5 library
    under netCDF4 crashes the process when two threads use it at once (a segmentation fault
    seen in `snakemake --cores 2 campaign`). The read waits for the lock, and a holder may
    take it again."""
    from rockdec import locks

    path = io.write_netcdf(xr.Dataset({"x": ("n", [1.0, 2.0])}, attrs={"history": "2000-01-01T00:00:00Z: rockdec x simulate"}),
                           tmp_path / "a.nc")
    got = []
    with locks.HDF5:
        reader = threading.Thread(target=lambda: got.append(io.input_history([path])))
        reader.start()
        reader.join(0.5)
        assert reader.is_alive() and not got  # waiting for the lock
        with locks.HDF5:  # taken again by its holder (the calibration cache's reads take it too)
            assert io.input_history([path]) == ["2000-01-01T00:00:00Z: rockdec x simulate"]
    reader.join(10)
    assert got == [["2000-01-01T00:00:00Z: rockdec x simulate"]]


def test_coordinates_are_written_without_fill_values(tmp_path):
    ds = xr.Dataset({"y": ("x", [1.0, np.nan])}, coords={"x": ("x", [0.5, 1.5]), "label": ("x", [2.0, 3.0])})
    path = io.write_netcdf(ds, tmp_path / "c.nc")
    with xr.open_dataset(path) as back:
        assert "_FillValue" not in back["x"].encoding and "_FillValue" not in back["label"].encoding
        assert np.isnan(back["y"].encoding["_FillValue"])  # data variables keep NaN as missing


def test_a_lock_is_never_seen_without_its_owner_while_runs_claim_it(tmp_path):
    """Another run that reads the lock at any moment finds a live owner in it, never an empty
    file it would take for a stale lock and take over. At least 300 claims, and more until
    the reader has read the lock (on a loaded machine its thread can miss 300 short claims)."""
    path = tmp_path / "out.nc"
    lock = path.with_name(f".{path.name}.lock")
    seen, done = [], threading.Event()

    def read():
        while not done.is_set():
            try:
                seen.append(lock.read_text())
            except FileNotFoundError:
                pass

    reader = threading.Thread(target=read)
    reader.start()
    try:
        claims = 0
        while claims < 300 or (not seen and claims < 30_000):
            with io.claimed(path):
                pass
            claims += 1
    finally:
        done.set()
        reader.join()
    assert seen, "the reader never saw the lock"
    assert set(seen) == {f"{os.getpid()}\n"}
    assert sorted(p.name for p in tmp_path.iterdir()) == [], "a claim left a file behind"


def test_a_lazy_series_beyond_float32_is_refused_after_every_chunk_is_written_and_leaves_no_file(tmp_path):
    # the first chunk is beyond the range and the others are slow: a refusal raised inside its
    # Dask task would end the write while the others still wrote, and one of them reopened
    # (so recreated) the removed temporary file
    import time

    import dask.array as da

    def slow(block, block_info=None):
        if block_info[None]["chunk-location"][0]:
            time.sleep(0.02)
        return block

    data = da.zeros(4000, chunks=100).map_blocks(slow, dtype=float)
    data = da.concatenate([da.full(100, 1e300, chunks=100), data[100:]])
    ds = xr.Dataset({"theta": ("time", data)})
    with pytest.raises(io.OutputError, match="beyond the float32 range"):
        io.write_netcdf(ds, tmp_path / "o.nc", float32=("theta",))
    time.sleep(0.3)  # any task still running would have written by now
    assert list(tmp_path.iterdir()) == []

"""Every series on disk (`store_series: all`): the files, and signatures equal either way."""

import netCDF4
import numpy as np
import pytest

from rockdec import engine
from rockdec.pipeline import config, layout, replicates, series
from rockdec.physics import run, simulate

READINGS = replicates.READINGS


@pytest.fixture(scope="module")
def stored(tmp_path_factory):
    """2 replicates of 10 series written to disk; Dask chunks of 4 seeds straddle the replicates."""
    scene = config.validate_scene(
        {
            "excitation": {"dt": 0.0034, "burn_in": 2000},
            "records": {"n_points": 3000, "replicates": 2, "series_per_replicate": 10, "chunk_seeds": 4, "store_series": "all"},
            "signatures": {"windows": [0.5, 1.0]},
        }
    )
    contract = run.from_scene(scene)
    folder = tmp_path_factory.mktemp("scene")
    paths = layout.replicate_files(folder, scene["records"])
    (folder / "series").mkdir()
    with engine.session(2):
        for r, path in enumerate(paths):
            series.write_replicate(contract, scene["records"], r, path)
    return {"scene": scene, "run": contract, "paths": paths}


def test_replicate_file_holds_its_seeds_as_float32_chunked_by_seed_and_compressed(stored):
    scene, contract = stored["scene"], stored["run"]
    seeds = layout.scene_seeds(scene["records"])[1]
    with netCDF4.Dataset(stored["paths"][1]) as nc:
        var = nc["theta"]
        assert var.dtype == np.float32
        assert var.chunking() == [4, scene["records"]["n_points"]]
        assert var.filters()["zlib"]
        assert nc["seed"][:].tolist() == seeds.tolist()
        assert nc.getncattr("replicate") == 1 and nc.getncattr("dt") == contract.dt
        assert run.Run.from_attrs(nc.__dict__) == contract
        theta = var[:].data
    exact, _ = simulate.simulate_block(
        seeds, scene["records"]["n_points"], dt=contract.dt, g=contract.g, e=contract.e, sigma_p=contract.sigma_p,
        burn_in=contract.burn_in,
    )
    assert np.array_equal(theta, exact.astype(np.float32))
    assert not np.array_equal(theta.astype(np.float64), exact)  # float32 does round


@pytest.mark.parametrize("reading", READINGS)
def test_signatures_from_the_files_equal_those_from_the_seeds_bit_for_bit(stored, reading):
    scene, contract = stored["scene"], stored["run"]
    rec, sig = scene["records"], scene["signatures"]
    from_seeds = replicates.scene_cubes(contract, rec, sig, [reading], threads=2)[reading]
    from_files = replicates.scene_cubes(contract, rec, sig, [reading], stored["paths"], threads=2)[reading]
    assert int(from_seeds["count"].sum()) > 0
    assert list(from_seeds.data_vars) == list(from_files.data_vars)
    for name in from_seeds.data_vars:
        assert np.array_equal(from_seeds[name].values, from_files[name].values, equal_nan=True), name


def test_signatures_from_the_seeds_are_those_of_the_rounded_series(stored):
    """The regenerated series are analysed as float32 stores them, not as computed."""
    scene, contract = stored["scene"], stored["run"]
    group, rep = replicates.reading_groups(layout.scene_seeds(scene["records"]), "pooled")
    theta = contract.dataset(layout.scene_seeds(scene["records"]).ravel(), scene["records"]["n_points"], chunk_seeds=4)["theta"]
    scales = {"sigma_y": contract.sigma_y, "sigma_ydot": contract.sigma_ydot, "g": contract.g}
    cube = replicates.scene_cubes(contract, scene["records"], scene["signatures"], ["pooled"])["pooled"]
    with engine.session(2):
        rounded = replicates.scene_signatures(series.as_recorded(theta), scene["signatures"], **scales, group=group, replicate_of_group=rep).compute()
        unrounded = replicates.scene_signatures(theta, scene["signatures"], **scales, group=group, replicate_of_group=rep).compute()
    assert np.array_equal(cube["signature_sum"].values, rounded["signature_sum"].values, equal_nan=True)
    assert not np.array_equal(cube["signature_sum"].values, unrounded["signature_sum"].values, equal_nan=True)


def test_a_seed_missing_from_the_files_is_named(stored):
    with pytest.raises(ValueError, match="no series for 10 seeds"):
        series.stored_theta(stored["paths"][:1], np.arange(20), 4)

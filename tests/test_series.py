"""Every series on disk (`store_series: all`): the files, and signatures equal either way."""

import dask
import netCDF4
import numpy as np
import pytest

from rockdec import config, replicates, series, simulate

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
    params = simulate.scene_parameters(scene)
    attrs = {**params, "n_points": scene["records"]["n_points"], "theta0": 0.0, "theta_dot0": 0.0}
    folder = tmp_path_factory.mktemp("scene")
    paths = series.replicate_files(folder, scene)
    (folder / "series").mkdir()
    with dask.config.set(scheduler="threads", num_workers=2):
        for r, path in enumerate(paths):
            series.write_replicate(attrs, scene, r, path)
    return {"scene": scene, "attrs": attrs, "paths": paths}


def test_store_series_is_a_count_or_all(tmp_path):
    with pytest.raises(config.ConfigError, match="store_series"):
        config.validate_scene({"records": {"store_series": "most"}})
    scene = config.validate_scene({"records": {"replicates": 3, "store_series": 5}})
    assert series.replicate_files(tmp_path, scene) == []
    assert series.simulation_seeds(scene).tolist() == [0, 1, 2, 3, 4]
    scene["records"]["store_series"] = "all"
    assert [p.name for p in series.replicate_files(tmp_path, scene)] == ["replicate_0.nc", "replicate_1.nc", "replicate_2.nc"]
    assert series.simulation_seeds(scene).size == series.FIGURE_SERIES


def test_replicate_file_holds_its_seeds_as_float32_chunked_by_seed_and_compressed(stored):
    scene, attrs = stored["scene"], stored["attrs"]
    seeds = simulate.scene_seeds(scene)[1]
    with netCDF4.Dataset(stored["paths"][1]) as nc:
        var = nc["theta"]
        assert var.dtype == np.float32
        assert var.chunking() == [4, scene["records"]["n_points"]]
        assert var.filters()["zlib"]
        assert nc["seed"][:].tolist() == seeds.tolist()
        assert nc.getncattr("replicate") == 1 and nc.getncattr("dt") == attrs["dt"]
        theta = var[:].data
    exact, _ = simulate.simulate_block(
        seeds, scene["records"]["n_points"], dt=attrs["dt"], g=attrs["g"], e=attrs["e"], sigma_p=attrs["sigma_p"], burn_in=attrs["burn_in"]
    )
    assert np.array_equal(theta, exact.astype(np.float32))
    assert not np.array_equal(theta.astype(np.float64), exact)  # float32 does round


@pytest.mark.parametrize("reading", READINGS)
def test_signatures_from_the_files_equal_those_from_the_seeds_bit_for_bit(stored, reading):
    scene, attrs = stored["scene"], stored["attrs"]
    with dask.config.set(scheduler="threads", num_workers=2):
        from_seeds = replicates.reading_cube(attrs, scene, reading).compute()
        from_files = replicates.reading_cube(attrs, scene, reading, stored["paths"]).compute()
    assert int(from_seeds["count"].sum()) > 0
    assert list(from_seeds.data_vars) == list(from_files.data_vars)
    for name in from_seeds.data_vars:
        assert np.array_equal(from_seeds[name].values, from_files[name].values, equal_nan=True), name


def test_signatures_from_the_seeds_are_those_of_the_rounded_series(stored):
    """The regenerated series are analysed as float32 stores them, not as computed."""
    scene, attrs = stored["scene"], stored["attrs"]
    used, group, rep = replicates.grouping(simulate.scene_seeds(scene), "pooled")
    theta = simulate.regenerate(attrs, used, chunk_seeds=4)["theta"]
    with dask.config.set(scheduler="threads", num_workers=2):
        cube = replicates.reading_cube(attrs, scene, "pooled").compute()
        rounded = replicates.scene_signatures(series.as_recorded(theta), scene, attrs, group, rep).compute()
        unrounded = replicates.scene_signatures(theta, scene, attrs, group, rep).compute()
    assert np.array_equal(cube["signature_sum"].values, rounded["signature_sum"].values, equal_nan=True)
    assert not np.array_equal(cube["signature_sum"].values, unrounded["signature_sum"].values, equal_nan=True)


def test_a_seed_missing_from_the_files_is_named(stored):
    with pytest.raises(ValueError, match="no series for 10 seeds"):
        series.stored_theta(stored["paths"][:1], np.arange(20), 4)

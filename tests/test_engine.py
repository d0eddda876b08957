"""The Dask engine (rockdec.engine): one setting, and the same numbers on every engine."""

import tempfile
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from rockdec import engine
from rockdec.pipeline import config, replicates, series
from rockdec.physics import run


@pytest.mark.slow
def test_the_threads_engine_computes_without_loading_dask_distributed():
    """The threads engine names Dask's threaded scheduler by its function: looking up the name
    "threads" would import dask.distributed (a second of imports) to look for a client. The
    probe is a ``python -c`` child of the Snakemake fork server, which this module's worker
    runs anyway (tests/conftest.py, :data:`conftest.WORKFLOW_MODULES`) and which has not
    imported dask.distributed (were it loaded there, the probe would fail, not pass)."""
    from conftest import FORKS

    probe = """
import sys
import dask.array as da
from rockdec import engine
print(engine.compute(da.ones(10, chunks=5).sum(), threads=2)[0], "distributed" in sys.modules)
"""
    code, out, err = FORKS.script(probe, timeout=120)
    assert code == 0, err
    assert out.split() == ["10.0", "False"]


def test_the_setting_names_an_engine_or_says_what_is_accepted(monkeypatch):
    monkeypatch.delenv(engine.VARIABLE, raising=False)
    assert engine.setting() == ("threads", None)
    assert engine.setting("processes:3") == ("processes", 3)
    assert engine.setting(" tcp://10.0.0.5:8786 ") == ("address", "tcp://10.0.0.5:8786")
    monkeypatch.setenv(engine.VARIABLE, "processes:2")
    assert engine.setting() == ("processes", 2)
    for bad in ("thread", "processes:0", "processes:two", "tcp://", "slurm"):
        with pytest.raises(engine.SchedulerError, match="threads.*processes:N.*tcp://"):
            engine.setting(bad)


def test_compute_in_place_gives_computes_numbers_in_numpy_arrays(monkeypatch):
    """Chunks stored into arrays allocated up front: the values (bit for bit), dtypes,
    coordinates and attributes of dask.compute, NumPy arrays, the lazy input untouched; in a
    session of another engine, compute itself."""
    import dask.array as da

    monkeypatch.setenv(engine.VARIABLE, "threads")
    rng = np.random.default_rng(3)
    lazy = xr.Dataset(
        {
            "x": (("a", "b"), (da.from_array(rng.standard_normal((7, 5)), chunks=(3, 2)) ** 2).cumsum(axis=0), {"units": "m"}),
            "n": (("a",), da.arange(7, chunks=3, dtype=np.int64) * 3),
            "plain": (("b",), np.arange(5.0)),
        },
        coords={"a": np.arange(7) * 10},
        attrs={"title": "t"},
    )
    (stored,) = engine.compute_in_place(lazy, threads=2)
    (computed,) = engine.compute(lazy, threads=2)
    assert stored.identical(computed) and stored["x"].attrs == {"units": "m"}
    assert all(isinstance(stored[name].data, np.ndarray) for name in stored.variables)
    assert stored["x"].values.tobytes() == computed["x"].values.tobytes() and stored["n"].dtype == np.int64
    assert isinstance(lazy["x"].data, da.Array)
    with engine.session(scheduler="threads"):  # inside a session: the session's engine computes
        assert engine.compute_in_place(lazy)[0].identical(computed)


@pytest.fixture(scope="module")
def small():
    """Two replicates of 12 series in chunks of 5 seeds (chunks straddle the replicates);
    Dask's worker processes forked (tests/snakemake_forks.py)."""
    from snakemake_forks import fork_dask_workers

    fork_dask_workers()
    scene = config.validate_scene(
        {
            "excitation": {"dt": 0.0034, "burn_in": 2000},
            "records": {"n_points": 3000, "replicates": 2, "series_per_replicate": 12, "chunk_seeds": 5},
            "signatures": {"windows": [0.5, 1.0]},
        }
    )
    return scene, run.from_scene(scene)


def cubes_on(scene, contract, scheduler, monkeypatch):
    monkeypatch.setenv(engine.VARIABLE, scheduler)
    return replicates.scene_cubes(contract, scene["records"], scene["signatures"], ["pooled", "groups_of_10"], threads=2)


@pytest.fixture(scope="module")
def threads(small):
    """The cubes and the first replicate's series file of :func:`small` on the threads engine."""
    scene, contract = small
    with pytest.MonkeyPatch.context() as monkeypatch:
        cubes = cubes_on(scene, contract, "threads", monkeypatch)
        with engine.session():  # the threads engine cubes_on set
            return cubes, replicate_file(scene, contract)


def replicate_file(scene, contract):
    """The first replicate written by :func:`rockdec.pipeline.series.write_replicate` (rule
    ``series``) on the session's engine, read back."""
    with tempfile.TemporaryDirectory() as folder:
        path = series.write_replicate(contract, scene["records"], 0, Path(folder) / "replicate_0.nc")
        with xr.open_dataset(path) as ds:
            return ds.load()


def assert_identical(a: dict, b: dict):
    for reading in a:
        for name in ("signature_sum", "count", "skipped", "free_response"):
            assert np.array_equal(a[reading][name].values, b[reading][name].values, equal_nan=True), (reading, name)


@pytest.mark.slow
def test_a_local_cluster_of_two_worker_processes_gives_the_threads_numbers_bit_for_bit(small, threads, monkeypatch):
    scene, contract = small
    cubes, written = threads
    assert int(cubes["pooled"]["count"].sum()) > 0
    monkeypatch.setenv(engine.VARIABLE, "processes:2")
    with engine.session():  # one cluster for both: the inner computations use it
        assert_identical(cubes, cubes_on(scene, contract, "processes:2", monkeypatch))
        assert replicate_file(scene, contract).equals(written)  # the series file, bit for bit


@pytest.mark.slow
@pytest.mark.dask_scheduler
def test_a_running_scheduler_given_by_its_address_gives_the_same_numbers(small, threads, monkeypatch, dask_scheduler):
    """On the session's running scheduler (tests/conftest.py, two worker processes on loopback)."""
    scene, contract = small
    assert_identical(threads[0], cubes_on(scene, contract, dask_scheduler, monkeypatch))
    with engine.session():  # the address set by cubes_on
        assert replicate_file(scene, contract).equals(threads[1])  # the series file, bit for bit


def test_a_session_inside_a_session_starts_no_second_engine(monkeypatch):
    import dask

    monkeypatch.setenv(engine.VARIABLE, "threads")
    with engine.session(2):
        assert dask.config.get("num_workers") == 2
        with engine.session(1):  # the inner request is served by the outer engine
            assert dask.config.get("num_workers") == 2


@pytest.mark.hostile("engines", "refused")
@pytest.mark.parametrize("bad", ["processes:²", "processes:٣", "processes:½", "processes: 2", "processes:-1", "processes:2.0"])
def test_a_worker_count_not_written_in_ascii_digits_is_refused(bad):
    """Issue 38: ``'²'.isdigit()`` is true but ``int('²')`` fails: an internal error before."""
    with pytest.raises(engine.SchedulerError, match="threads.*processes:N.*tcp://"):
        engine.setting(bad)

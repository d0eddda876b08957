"""Every series of a scene on disk (``records.store_series: all``), and the series a signature sees.

By default a scene's ``stored_series.nc`` keeps ``store_series`` series and every rule that
needs the others regenerates them from their seeds (:meth:`rockdec.physics.run.Run.dataset`).
With ``store_series: all`` every series is also written, one file per replicate
(``series/replicate_{r}.nc``: ``theta(seed, time)``, float32, zlib, one on-disk chunk per
``chunk_seeds`` seeds), and the signature rules read those files instead.

Stored series are float32, the simulator computes float64. So that a signature does not
depend on where its series came from, the signature rules always analyse the series as
stored: regenerated series are rounded to float32 first (:func:`as_recorded`). Rounding is
exact to reproduce (IEEE round-to-nearest) and is what a float32 record of the response
holds, so the signatures from the files and from the seeds are equal bit for bit -- not
merely within a tolerance -- when both are cut into the same Dask chunks of
``chunk_seeds`` seeds (the sums over seeds then run in the same order). The rounding moves
a sample by at most 6e-8 of its size, so only a trigger within that of a window edge can
flip: on 4 of the paper scene's replicates, 2 of 2.1 million triggers did, and no estimate
moved by more than 3e-7.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr

from rockdec import io
from rockdec.pipeline.layout import scene_seeds
from rockdec.physics.run import Run

__all__ = ["as_recorded", "stored_theta", "write_replicate"]

def replicate_dataset(run: Run, records: dict, replicate: int) -> xr.Dataset:
    """Lazy ``theta(seed, time)`` of every series of one replicate, as the scene simulates them.

    The file's attributes hold the run (:meth:`rockdec.physics.run.Run.to_attrs`, so one file says
    how to regenerate its series) and the replicate number; the coordinate ``replicate(seed)``
    holds it for each series too, so the files opened together (``xarray.open_mfdataset``,
    concatenated along ``seed``) still say which replicate each series belongs to.
    """
    seeds = scene_seeds(records)[replicate]
    ds = run.dataset(seeds, records["n_points"], chunk_seeds=records["chunk_seeds"])[["theta"]]
    ds = ds.assign_coords(replicate=("seed", np.full(seeds.size, replicate, dtype=np.int64),
                                     {"long_name": "replicate of the series", "units": "1"}))
    ds.attrs = {**run.to_attrs(), **io.provenance("series", records), "replicate": int(replicate)}
    return ds


def write_replicate(run: Run, records: dict, replicate: int, path: str | Path) -> Path:
    """Simulate one replicate and write it: float32, compressed, chunked by ``chunk_seeds`` seeds."""
    ds = replicate_dataset(run, records, replicate)
    return io.write_netcdf(ds, path, float32=("theta",), chunks={"seed": records["chunk_seeds"]})


def as_recorded(theta: xr.DataArray) -> xr.DataArray:
    """``theta`` rounded to float32 and back to float64: the values a series file stores."""
    return theta.astype(np.float32).astype(np.float64)


def stored_theta(paths, seeds, chunk_seeds: int) -> xr.DataArray:
    """Lazy float64 ``theta(seed, time)`` of ``seeds`` read from per-replicate series files.

    Cut into Dask chunks of ``chunk_seeds`` seeds over ``seeds``, as
    :meth:`rockdec.physics.run.Run.dataset` cuts the same seeds, so reductions over seeds sum
    in the same order either way. A seed that no file holds raises ``ValueError``.
    """
    paths = [Path(p) for p in paths]
    for path in paths:
        io.open_dataset(path).close()  # a clear error for a missing or unreadable file
    ds = xr.open_mfdataset(
        paths, engine="netcdf4", combine="nested", concat_dim="seed", chunks={},
        data_vars="minimal", coords="minimal", compat="override",
    )
    seeds = np.asarray(seeds, dtype=np.int64)
    missing = np.setdiff1d(seeds, ds["seed"].values)
    if missing.size:
        raise ValueError(
            f"the series files hold no series for {missing.size} seeds (first {missing[0]}); "
            "rerun the workflow so that rule `series` writes every replicate"
        )
    return ds["theta"].sel(seed=seeds).astype(np.float64).chunk({"seed": chunk_seeds, "time": -1})

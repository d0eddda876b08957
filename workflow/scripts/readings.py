"""Rule `readings`: the readings of the paper's sizes other than the scene's own, end to end."""

import sys

import dask
import pandas as pd
import xarray as xr
from dask.diagnostics import ProgressBar

from rockdec import io, replicates

sys.stderr = open(snakemake.log[0], "w")
scene = snakemake.params.scene
with io.open_dataset(snakemake.input.sim) as sim:
    attrs = dict(sim.attrs)
others = [r for r in replicates.READINGS if r != scene["estimates"]["reading"]]
results = []
for reading in others:
    print(f"reading {reading}", file=sys.stderr)
    cube = replicates.reading_cube(attrs, scene, reading, snakemake.input.series)
    with dask.config.set(scheduler="threads", num_workers=snakemake.threads), ProgressBar(out=sys.stderr, dt=0.5):
        cube = cube.compute()
    results.append(replicates.replicate_estimates(cube, **replicates.estimate_options(scene))[["e_hat0", "e_hat0_stderr"]])
combined = xr.concat(results, dim=pd.Index(others, name="reading"))
combined.attrs.update(io.provenance("readings", scene["estimates"], inputs=snakemake.input))
io.write_netcdf(combined, snakemake.output[0])

"""Rule `signatures`: the scene's signature cube for its reading."""

import sys

import dask
from dask.diagnostics import ProgressBar

from rockdec import io, replicates

sys.stderr = open(snakemake.log[0], "w")
with io.open_dataset(snakemake.input.sim) as sim:
    attrs = dict(sim.attrs)
cube = replicates.reading_cube(attrs, snakemake.params.scene, snakemake.params.reading, snakemake.input.series)
cube.attrs.update(io.provenance("signatures", snakemake.params.scene["signatures"], inputs=snakemake.input))
with dask.config.set(scheduler="threads", num_workers=snakemake.threads), ProgressBar(out=sys.stderr, dt=0.5):
    cube = cube.compute()
io.write_netcdf(cube, snakemake.output[0])

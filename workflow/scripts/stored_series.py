"""Rule `stored_series`: the series the scene keeps (fig. 2), simulated under its run."""

import sys

from rockdec import engine, io, layout
from rockdec.run import Run

sys.stderr = open(snakemake.log[0], "w")
records = snakemake.params.records
ds = Run.read(snakemake.input[0]).dataset(layout.simulation_seeds(records), records["n_points"], records["chunk_seeds"])
ds.attrs.update(io.provenance("stored_series", records, inputs=snakemake.input))
with engine.session(snakemake.threads):
    io.write_netcdf(ds, snakemake.output[0], float32=("theta", "theta_dot"))

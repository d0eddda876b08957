"""Rule `estimates`: estimators per replicate, extrapolation, table beside the paper."""

import sys

from rockdec import io, replicates, tables

sys.stderr = open(snakemake.log[0], "w")
options = snakemake.params.options
with io.open_dataset(snakemake.input[0]) as cube:
    cube = cube.load()
est, table = replicates.scene_estimates(cube, options)
est.attrs.update(io.provenance("estimates", options, inputs=snakemake.input))
io.write_netcdf(est, snakemake.output.estimates)
tables.write_table(table, snakemake.output.csv, snakemake.output.md)

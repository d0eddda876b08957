"""Rule `amplitude`: the simplified and Housner models over sigma_Y/theta_cr."""

import sys

from rockdec import amplitude, io, tables

sys.stderr = open(snakemake.log[0], "w")
scene = snakemake.params.scene
ds = amplitude.sweep(scene, threads=snakemake.threads)
ds.attrs.update(io.provenance("amplitude", scene))
io.write_netcdf(ds, snakemake.output.estimates)
tables.write_table(amplitude.sweep_table(ds), snakemake.output.csv, snakemake.output.md)

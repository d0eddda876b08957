"""Rule `choices`: the scene's estimates under one changed analysis choice at a time."""

import sys

from rockdec import io, sensitivity, tables

sys.stderr = open(snakemake.log[0], "w")
scene = snakemake.params.scene
with io.open_dataset(snakemake.input.sim) as sim:
    attrs = dict(sim.attrs)
est = sensitivity.choice_estimates(attrs, scene, threads=snakemake.threads, series_files=snakemake.input.series)
est.attrs.update(io.provenance("choices", {"choices": {k: list(v) for k, v in sensitivity.CHOICES.items()}}, inputs=snakemake.input))
io.write_netcdf(est, snakemake.output.estimates)
table = sensitivity.choice_table(est, scene["system"]["e"])
tables.write_table(table, snakemake.output.csv, snakemake.output.md)

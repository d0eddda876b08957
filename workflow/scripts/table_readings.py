"""Rule `table_readings`: all readings of the paper's sizes in one dataset and one table."""

import sys

from rockdec import io, replicates, tables

sys.stderr = open(snakemake.log[0], "w")
scene = snakemake.params.scene
with io.open_dataset(snakemake.input.own) as own, io.open_dataset(snakemake.input.other) as other:
    combined, table = replicates.readings_estimates(own.load(), other.load(), scene)
combined.attrs = io.provenance("table_readings", scene["estimates"], inputs=snakemake.input)
io.write_netcdf(combined, snakemake.output.estimates)
tables.write_table(table, snakemake.output.csv, snakemake.output.md)

"""Rule `table_readings`: every reading of the paper's sizes in one dataset and one table."""

import sys

from rockdec import io, replicates, tables

sys.stderr = open(snakemake.log[0], "w")
with io.open_dataset(snakemake.input[0]) as curves:
    combined, table = replicates.readings_estimates(curves.load(), snakemake.params.weights)
combined.attrs.update(io.provenance("table_readings", {"weights": snakemake.params.weights}, inputs=snakemake.input))
io.write_netcdf(combined, snakemake.output.estimates)
tables.write_table(table, snakemake.output.csv, snakemake.output.md)

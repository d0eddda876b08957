"""Rule `table_readings`: every reading of the paper's sizes in one dataset and one table."""

import sys

from rockdec import steps

sys.stderr = open(snakemake.log[0], "w")
out = snakemake.output
steps.table_readings(snakemake.input[0], out.estimates, out.csv, out.md, snakemake.params.weights)

"""Rule `coverage_table`: the study's summary table."""

import sys

import pandas as pd
import xarray as xr

from rockdec import coverage, tables

sys.stderr = open(snakemake.log[0], "w")
table = pd.concat([coverage.summary(xr.load_dataset(path)) for path in snakemake.input], ignore_index=True)
table.to_csv(snakemake.output.csv, index=False)
with open(snakemake.output.md, "w") as f:
    f.write(tables.to_markdown(table))

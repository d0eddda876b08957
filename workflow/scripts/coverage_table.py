"""Rule `coverage_table`: the study's summary table."""

import sys

import pandas as pd
import xarray as xr

from rockdec import coverage, tables

sys.stderr = open(snakemake.log[0], "w")
table = pd.concat([coverage.summary(xr.load_dataset(path)) for path in snakemake.input.cases], ignore_index=True)
tables.write_table(table, snakemake.output.csv, snakemake.output.md)

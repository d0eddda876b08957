"""Rule `coverage_table`: the study's summary table."""

import pandas as pd
import xarray as xr

from rockdec import coverage, job, tables


def main(smk):
    table = pd.concat([coverage.summary(xr.load_dataset(path)) for path in smk.input.cases], ignore_index=True)
    tables.write_table(table, smk.output.csv, smk.output.md)


if __name__ == "__main__":
    job.run(main, snakemake)

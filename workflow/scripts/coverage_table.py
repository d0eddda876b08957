"""Rule `coverage_table`: the study's table, one row per cell."""

import xarray as xr

from rockdec.studies import coverage
from rockdec.pipeline import job
from rockdec.report import tables


def main(smk):
    table = coverage.table([xr.load_dataset(path) for path in smk.input.cases])
    tables.write_table(table, smk.output.csv, smk.output.md, coverage.markdown(table))


if __name__ == "__main__":
    job.run(main, snakemake)

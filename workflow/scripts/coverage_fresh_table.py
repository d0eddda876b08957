"""Rule `coverage_fresh_table`: each cell's coverage on its own records beside its calibrations' on fresh records."""

import pandas as pd
import xarray as xr

from rockdec.studies import coverage
from rockdec.pipeline import job
from rockdec.report import tables


def main(smk):
    rows = pd.DataFrame([coverage.fresh_summary(xr.load_dataset(cell), pd.read_csv(fresh, keep_default_na=True).fillna({"calibration": "", "estimator": ""}))
                         for cell, fresh in zip(smk.input.cases, smk.input.fresh)])
    tables.write_table(rows, smk.output.csv, smk.output.md, coverage.fresh_markdown(rows))


if __name__ == "__main__":
    job.run(main, snakemake)

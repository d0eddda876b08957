"""Rule `coverage_fresh_table`: each cell's coverage on its own records beside its calibrations' on fresh records."""

import pandas as pd
import xarray as xr

from rockdec.studies import coverage
from rockdec.pipeline import job
from rockdec.report import tables


def main(smk):
    rows, calibrations = [], []
    for cell, fresh in zip(smk.input.cases, smk.input.fresh):
        ds = xr.load_dataset(cell)
        records = pd.read_csv(fresh, keep_default_na=True).fillna({"calibration": "", "estimator": ""})
        rows.append(coverage.fresh_summary(ds, records))
        calibrations.append(coverage.fresh_calibrations(ds, records))
    rows, calibrations = pd.DataFrame(rows), pd.concat(calibrations, ignore_index=True)
    tables.write_table(rows, smk.output.csv, smk.output.md, coverage.fresh_markdown(rows, calibrations))
    calibrations.to_csv(smk.output.calibrations, index=False)


if __name__ == "__main__":
    job.run(main, snakemake)

"""Rule `coverage_fresh`: a cell's calibrations judged on fresh records of its route."""

from pathlib import Path

import xarray as xr

from rockdec.studies import coverage
from rockdec import engine
from rockdec.pipeline import job


def main(smk):
    ds = xr.load_dataset(smk.input.cell)
    with engine.session(smk.threads):
        fresh = coverage.fresh_coverage(ds, smk.params.cache, smk.params.records, simulate=coverage.simulator_of(smk.wildcards.case, getattr(smk.input, "reference", None)))
    Path(smk.output[0]).parent.mkdir(parents=True, exist_ok=True)
    fresh.to_csv(smk.output[0], index=False)


if __name__ == "__main__":
    job.run(main, snakemake)

"""Rule `coverage_case`: one cell of the coverage study."""

import functools
import sys
from pathlib import Path

from rockdec.studies import coverage
from rockdec.pipeline import engine, job, layout
from rockdec import io


def simulator(smk):
    """The cell's simulator: the kernel, or the reference under tests/ of the checkout."""
    if layout.COVERAGE_CASES[smk.wildcards.case][0] == "kernel":
        return coverage.kernel_records
    sys.path.insert(0, str(Path(smk.input.reference).resolve().parent))
    import rocking_vectorised

    return functools.partial(rocking_vectorised.simulate_records, g=1.0, sigma_p=1.0)


def main(smk):
    reference = layout.COVERAGE_CASES[smk.wildcards.case][0] == "reference"
    with engine.session(smk.threads):  # the reference steps all records of a batch at once: larger batches
        ds = coverage.run_cell(smk.wildcards.case, smk.params.records, smk.params.n_points, smk.params.cache,
                               simulate=simulator(smk), batch=50 if reference else 10)
    ds.attrs.update(io.provenance("coverage", {"case": smk.wildcards.case, "records": smk.params.records}))
    io.write_netcdf(ds, smk.output[0])


if __name__ == "__main__":
    job.run(main, snakemake)

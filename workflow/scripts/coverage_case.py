"""Rule `coverage_case`: one cell of the coverage study."""

from pathlib import Path

from rockdec.studies import coverage
from rockdec.pipeline import engine, job, layout
from rockdec import io


def reference_dir(smk):
    """The folder of the reference simulator of a reference cell (tests/ of the checkout)."""
    return Path(smk.input.reference).resolve().parent if hasattr(smk.input, "reference") else None


def main(smk):
    reference = layout.COVERAGE_CASES[smk.wildcards.case][0] == "reference"
    with engine.session(smk.threads):  # the reference steps all records of a batch at once: larger batches
        ds = coverage.run_cell(smk.wildcards.case, smk.params.records, smk.params.n_points, smk.params.cache,
                               simulate=coverage.simulator_of(smk.wildcards.case, reference_dir(smk)), batch=50 if reference else 10)
    ds.attrs.update(io.provenance("coverage", {"case": smk.wildcards.case, "records": smk.params.records}))
    io.write_netcdf(ds, smk.output[0])


if __name__ == "__main__":
    job.run(main, snakemake)

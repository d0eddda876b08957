"""Rule `coverage_case`: one cell of the coverage study."""

from rockdec.studies import coverage
from rockdec import engine
from rockdec.pipeline import job, layout
from rockdec import io


def main(smk):
    reference = layout.COVERAGE_CASES[smk.wildcards.case][0] == "reference"
    with engine.session(smk.threads):  # the reference steps all records of a batch at once: larger batches
        ds = coverage.run_cell(smk.wildcards.case, smk.params.records, smk.params.n_points, smk.params.cache,
                               simulate=coverage.simulator_of(smk.wildcards.case, getattr(smk.input, "reference", None)), batch=50 if reference else 10)
    ds.attrs.update(io.provenance("coverage", {"case": smk.wildcards.case, "records": smk.params.records}))
    io.write_netcdf(ds, smk.output[0])


if __name__ == "__main__":
    job.run(main, snakemake)

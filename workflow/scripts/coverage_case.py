"""Rule `coverage_case`: one case of the coverage study."""

from rockdec import coverage, engine, io, job, layout


def main(smk):
    n_points, corner = layout.COVERAGE_CASES[smk.wildcards.case]
    with engine.session(smk.threads):
        ds = coverage.run(coverage.E_VALUES, coverage.RECORDS_PER_E, n_points, smk.params.cache, corner=corner)
    ds.attrs.update(io.provenance("coverage", {"case": smk.wildcards.case}))
    io.write_netcdf(ds, smk.output[0])


if __name__ == "__main__":
    job.run(main, snakemake)

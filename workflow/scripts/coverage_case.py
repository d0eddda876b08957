"""Rule `coverage_case`: one case of the coverage study."""

import sys

from rockdec import coverage, engine, io, layout

sys.stderr = open(snakemake.log[0], "w")
n_points, corner = layout.COVERAGE_CASES[snakemake.wildcards.case]
with engine.session(snakemake.threads):
    ds = coverage.run(coverage.E_VALUES, coverage.RECORDS_PER_E, n_points, snakemake.params.cache, corner=corner)
ds.attrs.update(io.provenance("coverage", {"case": snakemake.wildcards.case}))
io.write_netcdf(ds, snakemake.output[0])

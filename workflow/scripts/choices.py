"""Rule `choices`: the scene's estimates under one changed analysis choice at a time."""

import sys

from rockdec import io, sensitivity, tables
from rockdec.run import Run

sys.stderr = open(snakemake.log[0], "w")
est = sensitivity.choice_estimates(
    Run.read(snakemake.input.run), snakemake.params.records, snakemake.params.signatures, snakemake.params.estimates,
    threads=snakemake.threads, series_files=snakemake.input.series,
)
est.attrs.update(io.provenance("choices", {"choices": {k: list(v) for k, v in sensitivity.CHOICES.items()}}, inputs=snakemake.input))
io.write_netcdf(est, snakemake.output.estimates)
tables.write_table(sensitivity.choice_table(est, est.attrs["e_target"]), snakemake.output.csv, snakemake.output.md)

"""Rule `series`: every series of one replicate, written for the archive (`store_series: all`)."""

import sys

from rockdec import engine, series
from rockdec.run import Run

sys.stderr = open(snakemake.log[0], "w")
replicate = int(snakemake.wildcards.replicate)
print(f"replicate {replicate} -> {snakemake.output[0]}", file=sys.stderr)
with engine.session(snakemake.threads):
    series.write_replicate(Run.read(snakemake.input[0]), snakemake.params.records, replicate, snakemake.output[0])

"""Rule `estimates`: estimators per replicate, extrapolation, table beside the paper."""

import sys

from rockdec import steps

sys.stderr = open(snakemake.log[0], "w")
out = snakemake.output
steps.estimates(snakemake.input[0], out.estimates, out.csv, out.md, snakemake.params.options)

"""Rule `fig2`: paper fig. 2, two stored series and their pooled free-response estimate."""

import sys

from rockdec import steps

sys.stderr = open(snakemake.log[0], "w")
steps.fig2(snakemake.input.sim, snakemake.input.sig, [snakemake.output.png, snakemake.output.pdf])

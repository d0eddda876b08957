"""Rule `fig4`: paper fig. 4, e1..e4 of every replicate against the window size."""

import sys

from rockdec import steps

sys.stderr = open(snakemake.log[0], "w")
steps.fig4(snakemake.input.est, [snakemake.output.png, snakemake.output.pdf])

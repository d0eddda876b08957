"""Rule `fig3`: paper fig. 3, e_g and e_0 against the window size."""

import sys

from rockdec import steps

sys.stderr = open(snakemake.log[0], "w")
steps.fig3(snakemake.input.est, [snakemake.output.png, snakemake.output.pdf])

"""Rule `fig1b`: paper fig. 1b, the free-rocking periods of eqs. 3 and 5 (no input data)."""

import sys

from rockdec import steps

sys.stderr = open(snakemake.log[0], "w")
steps.fig1b([snakemake.output.png, snakemake.output.pdf])

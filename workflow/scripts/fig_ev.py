"""Rule `fig_ev`: the D_v signature and the estimator e_v (the paper's section 6 proposal)."""

import sys

from rockdec import steps

sys.stderr = open(snakemake.log[0], "w")
steps.fig_ev(snakemake.input.sig, snakemake.input.est, [snakemake.output.png, snakemake.output.pdf])

"""Rule `fig_ev`: the D_v signature and the estimator e_v (the paper's section 6 proposal)."""

import sys

from rockdec import figures, io

sys.stderr = open(snakemake.log[0], "w")
with io.open_dataset(snakemake.input.sig) as sig, io.open_dataset(snakemake.input.est) as est:
    fig = figures.fig_ev(sig.load(), est.load(), e_target=est.attrs["e_target"])
figures.save(fig, [snakemake.output.png, snakemake.output.pdf])

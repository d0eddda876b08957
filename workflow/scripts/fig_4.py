"""Rule `fig4`: paper fig. 4, e1..e4 of every replicate against the window size."""

import sys

from rockdec import figures, io

sys.stderr = open(snakemake.log[0], "w")
with io.open_dataset(snakemake.input.est) as est:
    fig = figures.fig4(est.load(), e_target=est.attrs["e_target"])
figures.save(fig, [snakemake.output.png, snakemake.output.pdf])

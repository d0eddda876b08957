"""Rule `fig3`: paper fig. 3, e_g and e_0 against the window size."""

import sys

from rockdec import figures, io

sys.stderr = open(snakemake.log[0], "w")
with io.open_dataset(snakemake.input.est) as est:
    fig = figures.fig3(est.load(), e_target=est.attrs["e_target"])
figures.save(fig, [snakemake.output.png, snakemake.output.pdf])

"""Rule `fig2`: paper fig. 2, two stored series and their pooled free-response estimate."""

import sys

from rockdec import figures, io

sys.stderr = open(snakemake.log[0], "w")
with io.open_dataset(snakemake.input.sim) as sim, io.open_dataset(snakemake.input.sig) as sig:
    fig = figures.fig2(sim.load(), sig.load())
figures.save(fig, [snakemake.output.png, snakemake.output.pdf])

"""Rule `fig_tradeoff`: the Pareto plot of the speed/accuracy study (reads the study only)."""

import sys

from rockdec import figures, io, tradeoff

sys.stderr = open(snakemake.log[0], "w")
with io.open_dataset(snakemake.input.nc) as ds:
    table = tradeoff.study_table(ds.load())
figures.save(figures.pareto_figure(table), [snakemake.output.png, snakemake.output.pdf])

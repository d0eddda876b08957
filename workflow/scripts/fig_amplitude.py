"""Rule `fig_amplitude`: estimates of both models against sigma_Y/theta_cr (target e from the data)."""

import sys

from rockdec import figures, io

sys.stderr = open(snakemake.log[0], "w")
with io.open_dataset(snakemake.input.nc) as ds:
    fig = figures.fig_amplitude(ds.load())
figures.save(fig, [snakemake.output.png, snakemake.output.pdf])

"""Rule `fig_amplitude`: estimates of both models against sigma_Y/theta_cr."""

import sys

from rockdec import figures, io

sys.stderr = open(snakemake.log[0], "w")
with io.open_dataset(snakemake.input[0]) as ds:
    fig = figures.fig_amplitude(ds.load(), e_target=snakemake.params.e_target)
figures.save(fig, [snakemake.output.png, snakemake.output.pdf])

"""Rule `fig_coverage`: coverage and bias against the load's corner frequency."""

import sys

import pandas as pd

from rockdec import figures

sys.stderr = open(snakemake.log[0], "w")
figures.save(figures.fig_coverage(pd.read_csv(snakemake.input[0])), [snakemake.output.png, snakemake.output.pdf])

"""Rule `series`: every series of one replicate, written for the archive (`store_series: all`)."""

import sys

import dask

from rockdec import io, series

sys.stderr = open(snakemake.log[0], "w")
with io.open_dataset(snakemake.input[0]) as sim:
    attrs = dict(sim.attrs)
replicate = int(snakemake.wildcards.replicate)
print(f"replicate {replicate} -> {snakemake.output[0]}", file=sys.stderr)
with dask.config.set(scheduler="threads", num_workers=snakemake.threads):
    series.write_replicate(attrs, snakemake.params.scene, replicate, snakemake.output[0])

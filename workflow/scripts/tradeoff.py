"""Rule `tradeoff`: each knob moved from the scene; CPU cost and accuracy per configuration."""

import sys

from rockdec import io, tables, tradeoff

sys.stderr = open(snakemake.log[0], "w")
scene = snakemake.params.scene
ds = tradeoff.run_study(scene, threads=snakemake.threads, progress=lambda text: print(text, file=sys.stderr, flush=True))
ds.attrs.update(io.provenance("tradeoff", scene))
io.write_netcdf(ds, snakemake.output.nc)
table = tradeoff.study_table(ds)
recommendations = {criterion: tradeoff.recommend(table, criterion=criterion) for criterion in tradeoff.CRITERIA}
tables.write_table(table, snakemake.output.csv, snakemake.output.md, markdown=tables.tradeoff_markdown(table, recommendations))

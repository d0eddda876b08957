"""Rule `estimates`: estimators per replicate, extrapolation, table beside the paper."""

import sys

from rockdec import io, replicates, tables

sys.stderr = open(snakemake.log[0], "w")
scene = snakemake.params.scene
with io.open_dataset(snakemake.input[0]) as cube:
    est = replicates.replicate_estimates(cube.load(), **replicates.estimate_options(scene))
est.attrs.update(io.provenance("estimates", scene["estimates"]))
io.write_netcdf(est, snakemake.output.estimates)
table = tables.summary_table(est["e_hat0"], scene["system"]["e"])
table.to_csv(snakemake.output.csv, index=False)
with open(snakemake.output.md, "w") as f:
    f.write(tables.to_markdown(table))

"""Rule `estimates`: estimators per replicate, extrapolation, table beside the paper."""

import sys

from rockdec import io, replicates, tables

sys.stderr = open(snakemake.log[0], "w")
scene = snakemake.params.scene
options = replicates.estimate_options(scene)
with io.open_dataset(snakemake.input[0]) as cube:
    cube = cube.load()
est = replicates.replicate_estimates(cube, **options)
other_weights = "count" if options["weights"] == "window" else "window"
alternative = replicates.replicate_estimates(cube, **{**options, "weights": other_weights})
est.attrs.update(io.provenance("estimates", scene["estimates"], inputs=snakemake.input))
io.write_netcdf(est, snakemake.output.estimates)
e_target = scene["system"]["e"]
table = tables.summary_table(est["e_hat0"], e_target)
table = tables.with_alternative(table, alternative["e_hat0"], f"{other_weights}_weights", e_target)
table.to_csv(snakemake.output.csv, index=False)
with open(snakemake.output.md, "w") as f:
    f.write(tables.to_markdown(table))

"""Rule `readings`: the other readings of the paper's sizes end to end, beside the scene's own."""

import sys

import dask
import pandas as pd
import xarray as xr
from dask.diagnostics import ProgressBar

from rockdec import io, replicates, tables

sys.stderr = open(snakemake.log[0], "w")
scene = snakemake.params.scene
own = scene["estimates"]["reading"]
with io.open_dataset(snakemake.input.simulations) as sim:
    attrs = dict(sim.attrs)
with io.open_dataset(snakemake.input.estimates) as est:
    results = {own: est[["e_hat0", "e_hat0_stderr"]].load()}
for reading in replicates.READINGS:
    if reading == own:
        continue
    print(f"reading {reading}", file=sys.stderr)
    cube = replicates.reading_cube(attrs, scene, reading)
    with dask.config.set(scheduler="threads", num_workers=snakemake.threads), ProgressBar(out=sys.stderr, dt=5.0):
        cube = cube.compute()
    results[reading] = replicates.replicate_estimates(cube, **replicates.estimate_options(scene))[["e_hat0", "e_hat0_stderr"]]
names = list(replicates.READINGS)
combined = xr.concat([results[r] for r in names], dim=pd.Index(names, name="reading"))
combined.attrs.update(io.provenance("readings", scene["estimates"]))
io.write_netcdf(combined, snakemake.output.estimates)
e_target = scene["system"]["e"]
table = pd.concat(
    [tables.summary_table(results[r]["e_hat0"], e_target).assign(reading=r) for r in names], ignore_index=True
)
table = table[["reading"] + [c for c in table.columns if c != "reading"]]
table.to_csv(snakemake.output.csv, index=False)
with open(snakemake.output.md, "w") as f:
    f.write(tables.to_markdown(table))

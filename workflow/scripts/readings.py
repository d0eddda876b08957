"""Rule `readings`: each reading of the paper's sizes end to end, compared in one table."""

import sys

import dask
import pandas as pd
import xarray as xr
from dask.diagnostics import ProgressBar

from rockdec import io, replicates, tables

sys.stderr = open(snakemake.log[0], "w")
scene = snakemake.params.scene
with io.open_dataset(snakemake.input[0]) as sim:
    attrs = dict(sim.attrs)
results, rows = [], []
for reading in replicates.READINGS:
    print(f"reading {reading}", file=sys.stderr)
    cube = replicates.reading_cube(attrs, scene, reading)
    with dask.config.set(scheduler="threads", num_workers=snakemake.threads), ProgressBar(out=sys.stderr, dt=5.0):
        cube = cube.compute()
    est = replicates.replicate_estimates(cube, **replicates.estimate_options(scene))
    results.append(est[["e_hat0", "e_hat0_stderr"]])
    rows.append(tables.summary_table(est["e_hat0"], scene["system"]["e"]).assign(reading=reading))
combined = xr.concat(results, dim=pd.Index(list(replicates.READINGS), name="reading"))
combined.attrs.update(io.provenance("readings", scene["estimates"]))
io.write_netcdf(combined, snakemake.output.estimates)
table = pd.concat(rows, ignore_index=True)
table = table[["reading"] + [c for c in table.columns if c != "reading"]]
table.to_csv(snakemake.output.csv, index=False)
with open(snakemake.output.md, "w") as f:
    f.write(tables.to_markdown(table))

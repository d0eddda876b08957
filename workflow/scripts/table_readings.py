"""Rule `table_readings`: all readings of the paper's sizes in one dataset and one table."""

import sys

import pandas as pd
import xarray as xr

from rockdec import io, replicates, tables

sys.stderr = open(snakemake.log[0], "w")
scene = snakemake.params.scene
with io.open_dataset(snakemake.input.own) as own, io.open_dataset(snakemake.input.other) as other:
    own_reading = own[["e_hat0", "e_hat0_stderr"]].load().expand_dims(reading=[scene["estimates"]["reading"]])
    combined = xr.concat([own_reading, other.load()], dim="reading").sel(reading=list(replicates.READINGS))
combined.attrs = io.provenance("table_readings", scene["estimates"], inputs=snakemake.input)
io.write_netcdf(combined, snakemake.output.estimates)
e_target = scene["system"]["e"]
table = pd.concat(
    [tables.summary_table(combined["e_hat0"].sel(reading=r), e_target).assign(reading=r) for r in replicates.READINGS],
    ignore_index=True,
)
table = table[["reading"] + [c for c in table.columns if c != "reading"]]
table.to_csv(snakemake.output.csv, index=False)
with open(snakemake.output.md, "w") as f:
    f.write(tables.to_markdown(table))

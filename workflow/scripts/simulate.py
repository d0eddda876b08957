"""Rule `simulate`: calibrate dt, write the stored series and the scene's provenance."""

import sys

import dask

from rockdec import io, series, simulate

sys.stderr = open(snakemake.log[0], "w")
scene = snakemake.params.scene
params = simulate.scene_parameters(scene)
print(f"calibration: {params}", file=sys.stderr)
seeds = series.simulation_seeds(scene)
with dask.config.set(scheduler="threads", num_workers=snakemake.threads):
    io.write_netcdf(simulate.scene_dataset(scene, params, seeds), snakemake.output[0], float32=("theta", "theta_dot"))

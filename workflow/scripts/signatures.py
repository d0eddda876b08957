"""Rule `signatures`: one pass over the series; the scene's cube and every reading's window curves."""

import sys

from dask.diagnostics import ProgressBar

from rockdec import io, replicates
from rockdec.run import Run

sys.stderr = open(snakemake.log[0], "w")
settings = snakemake.params.settings
with ProgressBar(out=sys.stderr, dt=0.5):
    cubes = replicates.scene_cubes(
        Run.read(snakemake.input.run), snakemake.params.records, settings["signatures"], settings["readings"],
        snakemake.input.series, threads=snakemake.threads,
    )
cube = cubes[settings["readings"][0]]
cube.attrs.update(io.provenance("signatures", settings["signatures"], inputs=snakemake.input))
io.write_netcdf(cube, snakemake.output.cube)
curves = replicates.reading_curves(cubes, settings["fit_points"])
curves.attrs.update(io.provenance("readings", settings, inputs=snakemake.input))
io.write_netcdf(curves, snakemake.output.readings)

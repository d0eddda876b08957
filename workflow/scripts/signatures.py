"""Rules `signatures` and `signature_part`: one pass over the series (or the gathered jobs of
one); the scene's cube and every reading's window curves."""

import sys

from rockdec import console, io, replicates
from rockdec.run import Run

sys.stderr = open(snakemake.log[0], "w")
settings = snakemake.params.settings
inputs = snakemake.input
if snakemake.rule == "signatures" and inputs.cubes:
    print(f"gathering {len(inputs.cubes)} signature jobs", file=sys.stderr)
    loaded = {}
    for path in [*inputs.cubes, *inputs.curves]:
        with io.open_dataset(path) as ds:
            loaded[path] = ds.load()
    cube, curves = replicates.gathered([loaded[p] for p in inputs.cubes], [loaded[p] for p in inputs.curves])
else:
    print(f"signature pass over {snakemake.params.records['replicates']} replicates", file=sys.stderr)
    with console.progress("signatures"):  # a bar on a terminal only: this log gets no frames
        cubes = replicates.scene_cubes(
            Run.read(inputs.run), snakemake.params.records, settings["signatures"], settings["readings"],
            inputs.series, threads=snakemake.threads, first_replicate=snakemake.params.first_replicate,
        )
    cube = cubes[settings["readings"][0]]
    curves = replicates.reading_curves(cubes, settings["fit_points"])
cube.attrs.update(io.provenance(snakemake.rule, settings["signatures"], inputs=inputs))
io.write_netcdf(cube, snakemake.output.cube)
curves.attrs.update(io.provenance("readings", settings, inputs=inputs))
io.write_netcdf(curves, snakemake.output.readings)

"""Rules `signatures` and `signature_part`: one pass over the series (or the gathered jobs of
one); the scene's cube and every reading's window curves."""

import sys

from rockdec import io
from rockdec.pipeline import job, replicates
from rockdec.physics.run import Run


def main(smk):
    settings = smk.params.settings
    inputs = smk.input
    if smk.rule == "signatures" and inputs.cubes:
        print(f"gathering {len(inputs.cubes)} signature jobs", file=sys.stderr)
        loaded = {}
        for path in [*inputs.cubes, *inputs.curves]:
            with io.open_dataset(path) as ds:
                loaded[path] = ds.load()
        cube, curves = replicates.gathered([loaded[p] for p in inputs.cubes], [loaded[p] for p in inputs.curves])
    else:
        records = smk.params.records
        label = f"{smk.rule}: {records['replicates']} replicates x {records['series_per_replicate']} series"
        with job.progress(label):
            cubes = replicates.scene_cubes(
                Run.read(inputs.run), records, settings["signatures"], settings["readings"],
                inputs.series, threads=smk.threads, first_replicate=smk.params.first_replicate,
            )
        cube = cubes[settings["readings"][0]]
        curves = replicates.reading_curves(cubes, settings["fit_points"])
    cube.attrs.update(io.provenance(smk.rule, settings["signatures"], inputs=inputs))
    io.write_netcdf(cube, smk.output.cube)
    curves.attrs.update(io.provenance("readings", settings, inputs=inputs))
    io.write_netcdf(curves, smk.output.readings)


if __name__ == "__main__":
    job.run(main, snakemake)

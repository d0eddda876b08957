"""Rule `estimates`: estimators per replicate, extrapolation, table beside the paper."""

from rockdec import io, job, replicates, tables


def main(smk):
    options = smk.params.options
    with io.open_dataset(smk.input[0]) as cube:
        cube = cube.load()
    est, table = replicates.scene_estimates(cube, options)
    est.attrs.update(io.provenance("estimates", options, inputs=smk.input))
    io.write_netcdf(est, smk.output.estimates)
    tables.write_table(table, smk.output.csv, smk.output.md)


if __name__ == "__main__":
    job.run(main, snakemake)

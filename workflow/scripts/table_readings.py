"""Rule `table_readings`: every reading of the paper's sizes in one dataset and one table."""

from rockdec import io, job, replicates, tables


def main(smk):
    with io.open_dataset(smk.input[0]) as curves:
        combined, table = replicates.readings_estimates(curves.load(), smk.params.weights)
    combined.attrs.update(io.provenance("table_readings", {"weights": smk.params.weights}, inputs=smk.input))
    io.write_netcdf(combined, smk.output.estimates)
    tables.write_table(table, smk.output.csv, smk.output.md)


if __name__ == "__main__":
    job.run(main, snakemake)

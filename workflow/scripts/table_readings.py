"""Rule `table_readings`: every reading of the paper's sizes in one dataset and one table."""

from rockdec import job, steps


def main(smk):
    out = smk.output
    steps.table_readings(smk.input[0], out.estimates, out.csv, out.md, smk.params.weights)


if __name__ == "__main__":
    job.run(main, snakemake)

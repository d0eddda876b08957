"""Rule `estimates`: estimators per replicate, extrapolation, table beside the paper."""

from rockdec import job, steps


def main(smk):
    out = smk.output
    steps.estimates(smk.input[0], out.estimates, out.csv, out.md, smk.params.options)


if __name__ == "__main__":
    job.run(main, snakemake)

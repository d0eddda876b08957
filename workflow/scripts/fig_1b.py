"""Rule `fig1b`: paper fig. 1b, the free-rocking periods of eqs. 3 and 5 (no input data)."""

from rockdec import job, steps


def main(smk):
    steps.fig1b([smk.output.png, smk.output.pdf])


if __name__ == "__main__":
    job.run(main, snakemake)

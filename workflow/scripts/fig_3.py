"""Rule `fig3`: paper fig. 3, e_g and e_0 against the window size."""

from rockdec import job, steps


def main(smk):
    steps.fig3(smk.input.est, [smk.output.png, smk.output.pdf])


if __name__ == "__main__":
    job.run(main, snakemake)

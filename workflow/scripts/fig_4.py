"""Rule `fig4`: paper fig. 4, e1..e4 of every replicate against the window size."""

from rockdec import job, steps


def main(smk):
    steps.fig4(smk.input.est, [smk.output.png, smk.output.pdf])


if __name__ == "__main__":
    job.run(main, snakemake)

"""Rule `fig2`: paper fig. 2, two stored series and their pooled free-response estimate."""

from rockdec import job, steps


def main(smk):
    steps.fig2(smk.input.sim, smk.input.sig, [smk.output.png, smk.output.pdf])


if __name__ == "__main__":
    job.run(main, snakemake)

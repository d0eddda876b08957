"""Rule `fig_ev`: the D_v signature and the estimator e_v (the paper's section 6 proposal)."""

from rockdec import job, steps


def main(smk):
    steps.fig_ev(smk.input.sig, smk.input.est, [smk.output.png, smk.output.pdf])


if __name__ == "__main__":
    job.run(main, snakemake)

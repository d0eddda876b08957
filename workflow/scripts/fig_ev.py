"""Rule `fig_ev`: the D_v signature and the estimator e_v (the paper's section 6 proposal)."""

from rockdec import figures, io, job


def main(smk):
    with io.open_dataset(smk.input.sig) as sig, io.open_dataset(smk.input.est) as est:
        fig = figures.fig_ev(sig.load(), est.load(), e_target=est.attrs["e_target"])
    figures.save(fig, [smk.output.png, smk.output.pdf])


if __name__ == "__main__":
    job.run(main, snakemake)

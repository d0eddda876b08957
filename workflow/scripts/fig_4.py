"""Rule `fig4`: paper fig. 4, e1..e4 of every replicate against the window size."""

from rockdec import figures, io, job


def main(smk):
    with io.open_dataset(smk.input.est) as est:
        fig = figures.fig4(est.load(), e_target=est.attrs["e_target"])
    figures.save(fig, [smk.output.png, smk.output.pdf])


if __name__ == "__main__":
    job.run(main, snakemake)

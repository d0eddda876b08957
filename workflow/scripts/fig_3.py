"""Rule `fig3`: paper fig. 3, e_g and e_0 against the window size."""

from rockdec import figures, io, job


def main(smk):
    with io.open_dataset(smk.input.est) as est:
        fig = figures.fig3(est.load(), e_target=est.attrs["e_target"])
    figures.save(fig, [smk.output.png, smk.output.pdf])


if __name__ == "__main__":
    job.run(main, snakemake)

"""Rule `fig2`: paper fig. 2, two stored series and their pooled free-response estimate."""

from rockdec import figures, io, job


def main(smk):
    with io.open_dataset(smk.input.sim) as sim, io.open_dataset(smk.input.sig) as sig:
        fig = figures.fig2(sim.load(), sig.load())
    figures.save(fig, [smk.output.png, smk.output.pdf])


if __name__ == "__main__":
    job.run(main, snakemake)

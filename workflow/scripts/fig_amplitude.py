"""Rule `fig_amplitude`: estimates of both models against sigma_Y/theta_cr (target e from the data)."""

from rockdec.report import figures
from rockdec import io
from rockdec.pipeline import job


def main(smk):
    with io.open_dataset(smk.input.nc) as ds:
        fig = figures.fig_amplitude(ds.load())
    figures.save(fig, [smk.output.png, smk.output.pdf])


if __name__ == "__main__":
    job.run(main, snakemake)

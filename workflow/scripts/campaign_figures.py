"""Rule `campaign_figures`: the forest plot of e, the record models and the diagnostics."""

from rockdec import io
from rockdec.pipeline import job
from rockdec.report import campaign_figures, figures


def main(smk):
    with io.open_dataset(smk.input.nc) as ds:
        ds = ds.load()
    for name, draw in campaign_figures.FIGURES.items():
        figures.save(draw(ds), smk.output[name])


if __name__ == "__main__":
    job.run(main, snakemake)

"""Rule `fig_tradeoff`: the Pareto plot of the speed/accuracy study (reads the study only)."""

from rockdec.report import figures
from rockdec import io
from rockdec.pipeline import job
from rockdec.studies import tradeoff


def main(smk):
    with io.open_dataset(smk.input.nc) as ds:
        table = tradeoff.study_table(ds.load())
    figures.save(figures.pareto_figure(table), [smk.output.png, smk.output.pdf])


if __name__ == "__main__":
    job.run(main, snakemake)

"""Rule `fig_tradeoff`: the Pareto plot of the speed/accuracy study (reads the study only)."""

from rockdec.report import figures
from rockdec import io
from rockdec.pipeline import job
from rockdec.studies import tradeoff
from rockdec.studies.figures import pareto_figure


def main(smk):
    with io.open_dataset(smk.input.nc) as ds:
        table = tradeoff.study_table(ds.load())
    figures.save(pareto_figure(table), [smk.output.png, smk.output.pdf])


if __name__ == "__main__":
    job.run(main, snakemake)

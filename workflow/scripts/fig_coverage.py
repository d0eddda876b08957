"""Rule `fig_coverage`: coverage and corrected bias per condition and e."""

import pandas as pd

from rockdec.report import figures
from rockdec.studies.figures import fig_coverage
from rockdec.pipeline import job


def main(smk):
    figures.save(fig_coverage(pd.read_csv(smk.input[0])), [smk.output.png, smk.output.pdf])


if __name__ == "__main__":
    job.run(main, snakemake)

"""Rule `shake_coverage`: the shake-table study's grid of cells, as a Markdown table."""

from pathlib import Path

from rockdec.pipeline import job
from rockdec.studies import shake_coverage


def main(smk):
    Path(smk.output.md).write_text(shake_coverage.markdown(shake_coverage.run_grid()) + "\n")


if __name__ == "__main__":
    job.run(main, snakemake)

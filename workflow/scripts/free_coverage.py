"""Rule `free_coverage`: the free-rocking study's grid of cells, as a Markdown table."""

from pathlib import Path

from rockdec.pipeline import job
from rockdec.studies import free_coverage


def main(smk):
    Path(smk.output.md).write_text(free_coverage.markdown(free_coverage.run_grid()) + "\n")


if __name__ == "__main__":
    job.run(main, snakemake)

"""Rule `diagnostics_table`: false alarms and detections per check, e and defect size, below a digest per check."""

import pandas as pd

from rockdec.studies import diagnostics_study
from rockdec.pipeline import job
from rockdec.report import tables


def main(smk):
    records = pd.concat([pd.read_csv(path) for path in smk.input.records], ignore_index=True)
    summary = diagnostics_study.summary(records)
    markdown = diagnostics_study.digest_markdown(diagnostics_study.digest(summary)) + "\n" + tables.to_markdown(summary)
    tables.write_table(summary, smk.output.csv, smk.output.md, markdown)


if __name__ == "__main__":
    job.run(main, snakemake)

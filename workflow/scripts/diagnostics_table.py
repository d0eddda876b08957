"""Rule `diagnostics_table`: false alarms and detections per check, e and defect size."""

import pandas as pd

from rockdec.studies import diagnostics_study
from rockdec.pipeline import job
from rockdec.report import tables


def main(smk):
    records = pd.concat([pd.read_csv(path) for path in smk.input.records], ignore_index=True)
    tables.write_table(diagnostics_study.summary(records), smk.output.csv, smk.output.md)


if __name__ == "__main__":
    job.run(main, snakemake)

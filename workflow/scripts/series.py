"""Rule `series`: every series of one replicate, written for the archive (`store_series: all`)."""

import sys

from rockdec.pipeline import engine, job, series
from rockdec.physics.run import Run


def main(smk):
    replicate = int(smk.wildcards.replicate)
    print(f"replicate {replicate} -> {smk.output[0]}", file=sys.stderr)
    with engine.session(smk.threads):
        series.write_replicate(Run.read(smk.input[0]), smk.params.records, replicate, smk.output[0])


if __name__ == "__main__":
    job.run(main, snakemake)

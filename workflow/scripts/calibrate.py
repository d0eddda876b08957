"""Rule `calibrate`: the scene's run contract (model, step, burn-in, stationary statistics)."""

import sys

from rockdec.pipeline import job
from rockdec.physics import run


def main(smk):
    contract = run.calibrate(smk.params.physics)
    print(f"run: {contract}", file=sys.stderr)
    contract.write(smk.output[0])


if __name__ == "__main__":
    job.run(main, snakemake)

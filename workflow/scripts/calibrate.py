"""Rule `calibrate`: the scene's run contract (model, step, burn-in, stationary statistics)."""

import sys

from rockdec import run

sys.stderr = open(snakemake.log[0], "w")
contract = run.calibrate(snakemake.params.physics)
print(f"run: {contract}", file=sys.stderr)
contract.write(snakemake.output[0])

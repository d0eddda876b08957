"""Rule `stored_signature`: signatures of the stored series pooled into one group (fig. 2c)."""

import sys

import numpy as np

from rockdec import io
from rockdec.pipeline import job, replicates
from rockdec.physics.run import Run


def main(smk):
    with io.open_dataset(smk.input[0]) as sim:
        run = Run.from_attrs(sim.attrs)
        theta = sim["theta"].astype(np.float64).load().assign_attrs(dt=run.dt)
    n = theta.sizes["seed"]
    print(f"signature of {n} stored series x {theta.sizes['time']} points", file=sys.stderr)
    cube = replicates.scene_signatures(
        theta, smk.params.signatures, sigma_y=run.sigma_y, sigma_ydot=run.sigma_ydot, g=run.g,
        group=np.zeros(n, dtype=np.int64), replicate_of_group=[0],
    )
    cube.attrs.update({**run.to_attrs(), **io.provenance("stored_signature", smk.params.signatures, inputs=smk.input)})
    io.write_netcdf(cube, smk.output[0])


if __name__ == "__main__":
    job.run(main, snakemake)

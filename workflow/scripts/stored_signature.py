"""Rule `stored_signature`: signatures of the stored series pooled into one group (fig. 2c)."""

import sys

import numpy as np

from rockdec import io, replicates

sys.stderr = open(snakemake.log[0], "w")
scene = snakemake.params.scene
with io.open_dataset(snakemake.input[0]) as sim:
    attrs = dict(sim.attrs)
    theta = sim["theta"].astype(np.float64).load().assign_attrs(dt=attrs["dt"])
n = theta.sizes["seed"]
print(f"signature of {n} stored series x {theta.sizes['time']} points", file=sys.stderr)
cube = replicates.scene_signatures(theta, scene, attrs, group=np.zeros(n, dtype=np.int64), replicate_of_group=[0])
cube.attrs.update(io.provenance("stored_signature", scene["signatures"], inputs=snakemake.input))
io.write_netcdf(cube, snakemake.output[0])

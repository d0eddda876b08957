"""Rule `campaign_simulate`: a record of the demonstration campaign, simulated with its known e."""

import json

import numpy as np
import xarray as xr

from rockdec import io
from rockdec.physics.record_model import Load
from rockdec.physics.simulate import default_burn_in
from rockdec.pipeline import job
from rockdec.studies import coverage


def main(smk):
    row = smk.params.row
    recipe, e, dt = row["simulate"], row["true_e"], row["dt"]
    load = Load() if recipe["corner"] is None else Load("lowpass", recipe["corner"])
    # the coverage study's records: the compiled kernel (g = sigma_p = 1), the load's pole and the
    # sensor noise placed at its samples per cycle
    theta = coverage.kernel_records([recipe["seed"]], recipe["n_points"], dt=dt, e=e, pole=load.pole(coverage.POINTS_PER_CYCLE),
                                    noise=recipe["noise"], burn_in=default_burn_in(e, coverage.POINTS_PER_CYCLE))[0]
    ds = xr.Dataset(
        {"theta": ("time", theta, {"units": "rad", "long_name": "rocking angle"})},
        coords={"time": ("time", np.arange(theta.size) * dt, {"units": "s", "standard_name": "time", "long_name": "time", "axis": "T"})},
    )
    ds.attrs.update(io.provenance("campaign_simulate", {"record": row["record"], "true_e": e, "dt": dt, **recipe}))
    ds.attrs["true_e"] = e
    io.write_netcdf(ds, smk.output[0])
    print(f"simulated {row['record']}: e = {e}, {json.dumps(recipe, sort_keys=True)}", file=__import__("sys").stderr)


if __name__ == "__main__":
    job.run(main, snakemake)

"""Rule `stored_series`: the series the scene keeps (fig. 2), simulated under its run."""

from rockdec.pipeline import engine, job, layout
from rockdec import io
from rockdec.physics.run import Run


def main(smk):
    records = smk.params.records
    ds = Run.read(smk.input[0]).dataset(layout.simulation_seeds(records), records["n_points"], records["chunk_seeds"])
    ds.attrs.update(io.provenance("stored_series", records, inputs=smk.input))
    with engine.session(smk.threads):
        io.write_netcdf(ds, smk.output[0], float32=("theta", "theta_dot"))


if __name__ == "__main__":
    job.run(main, snakemake)

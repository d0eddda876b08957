"""Rule `amplitude`: the simplified and Housner models over sigma_Y/theta_cr."""

from rockdec.studies import amplitude
from rockdec import io
from rockdec.pipeline import job
from rockdec.report import tables


def main(smk):
    scene = smk.params.scene
    ds = amplitude.sweep(scene, threads=smk.threads)
    ds.attrs.update(io.provenance("amplitude", scene))
    io.write_netcdf(ds, smk.output.estimates)
    tables.write_table(amplitude.sweep_table(ds), smk.output.csv, smk.output.md)


if __name__ == "__main__":
    job.run(main, snakemake)

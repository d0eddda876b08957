"""Rule `choices`: the scene's estimates under one changed analysis choice at a time."""

from rockdec import io
from rockdec.pipeline import job
from rockdec.studies import sensitivity
from rockdec.report import tables
from rockdec.physics.run import Run


def main(smk):
    est = sensitivity.choice_estimates(
        Run.read(smk.input.run), smk.params.records, smk.params.signatures, smk.params.estimates,
        threads=smk.threads, series_files=smk.input.series,
    )
    est.attrs.update(io.provenance("choices", {"choices": {k: list(v) for k, v in sensitivity.CHOICES.items()}}, inputs=smk.input))
    io.write_netcdf(est, smk.output.estimates)
    tables.write_table(sensitivity.choice_table(est, est.attrs["e_target"]), smk.output.csv, smk.output.md)


if __name__ == "__main__":
    job.run(main, snakemake)

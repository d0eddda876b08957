"""Rule `tradeoff`: each knob moved from the scene; CPU cost and accuracy per configuration."""

import sys

from rockdec import io
from rockdec.pipeline import job
from rockdec.report import tables
from rockdec.studies import tradeoff


def main(smk):
    scene = smk.params.scene
    ds = tradeoff.run_study(scene, threads=smk.threads, progress=lambda text: print(text, file=sys.stderr, flush=True))
    ds.attrs.update(io.provenance("tradeoff", scene))
    io.write_netcdf(ds, smk.output.nc)
    table = tradeoff.study_table(ds)
    recommendations = {criterion: tradeoff.recommend(table, criterion=criterion) for criterion in tradeoff.CRITERIA}
    tables.write_table(table, smk.output.csv, smk.output.md, markdown=tables.tradeoff_markdown(table, recommendations))


if __name__ == "__main__":
    job.run(main, snakemake)

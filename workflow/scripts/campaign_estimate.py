"""Rules `campaign_record` and `campaign_block`: the estimate of a record, or of a block's
records pooled, as `rockdec estimate --json` prints it, and as CF NetCDF."""

import json
import sys

from rockdec import io
from rockdec.pipeline import campaign, job


def main(smk):
    rows = smk.params.rows
    doc = campaign.estimate_unit(rows, smk.params.options, smk.params.cache)
    with open(smk.input.plan) as f:
        planned = json.load(f)["calibration"]
    used = (doc.get("calibration") or {}).get("file")
    if used != planned:  # the plan reads the engine's own request: a mismatch is a bug, not the user's
        raise RuntimeError(f"{smk.wildcards.unit}: the estimate used {used}, its plan asked for {planned}")
    with open(smk.output.json, "w") as f:
        f.write(json.dumps(doc, indent=2) + "\n")
    ds = campaign.unit_dataset(smk.wildcards.unit, rows, doc)
    ds.attrs.update(io.provenance(smk.rule, {"rows": rows, "options": smk.params.options}, inputs=list(smk.input.records)))
    io.write_netcdf(ds, smk.output.nc)
    print(f"{smk.wildcards.unit}: e = {doc.get('e')}", file=sys.stderr)


if __name__ == "__main__":
    job.run(main, snakemake)

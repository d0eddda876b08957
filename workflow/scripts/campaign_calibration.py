"""Rule `campaign_calibration`: one calibration into the cache `rockdec estimate` reads."""

import json
import sys
from pathlib import Path

from rockdec.pipeline import campaign, engine, job


def main(smk):
    with open(smk.input.plan) as f:
        settings = json.load(f)["settings"]
    with engine.session(smk.threads):
        path = campaign.build_calibration(settings, Path(smk.output[0]).parent)
    print(f"calibration {path}", file=sys.stderr)


if __name__ == "__main__":
    job.run(main, snakemake)

"""Rule `campaign_plan`: which calibration the estimate of a record or a block needs."""

import json
import sys

from rockdec.pipeline import campaign, job


def main(smk):
    plan = campaign.plan(smk.params.rows, smk.params.options)
    with open(smk.output[0], "w") as f:
        json.dump(plan, f, indent=2, sort_keys=True)
    print(f"{smk.wildcards.unit}: {plan['calibration'] or 'no calibration'}" + (f" ({plan['error']})" if plan["error"] else ""), file=sys.stderr)


if __name__ == "__main__":
    job.run(main, snakemake)

# The campaign's sheet, checked before any job, and the helpers that turn it into file names
# (the rules: campaign.smk).
import json
import os
from pathlib import Path

import rockdec  # the front door, which the estimate steps call (its modules load on first use)
from rockdec.cache import default_cache
from rockdec.pipeline import campaign as rockdec_campaign

CAMPAIGN = config["campaign"]["name"]
CAMPAIGN_CACHE = os.path.abspath(
    os.path.expanduser(config["campaign"]["cache"] or str(default_cache()))
)


def campaign_sheet():
    """The sheet's path: relative to the working directory, else to the workflow's folder
    (a workflow deployed elsewhere, or run by `rockdec workflow`)."""
    sheet = Path(os.path.expanduser(config["campaign"]["sheet"]))
    if sheet.is_absolute() or sheet.exists():
        return str(sheet)
    return str(Path(workflow.basedir) / sheet)


# The sheet is checked before any job (a dry run too): a bad row is refused in one sentence
# naming its row and column, exit code 2.
try:
    if CAMPAIGN in SCENES:
        raise rockdec_config.ConfigError(
            f"config field 'campaign.name': '{CAMPAIGN}' is also a scene's name, and both write results/{CAMPAIGN}/; rename the campaign."
        )
    CAMPAIGN_ROWS = rockdec_campaign.read_sheet(campaign_sheet(), simulated=f"results/{CAMPAIGN}/simulated")
except rockdec_campaign.InputError as exc:
    print(f"rockdec: error: {exc}", file=sys.stderr)
    sys.exit(2)

CAMPAIGN_UNITS = rockdec_campaign.units(CAMPAIGN_ROWS)
CAMPAIGN_RECORDS = {row["record"]: row for row in CAMPAIGN_ROWS}
# The simulation, the plans, the calibrations and the estimates run inside the Snakemake
# process (rockdec.pipeline.in_snakemake.campaign); their code input is what that reaches,
# the public estimate they are handed included.
CAMPAIGN_CODE = code_fingerprint(
    "campaign", [find_spec("rockdec.pipeline.in_snakemake").origin, *package_sources("rockdec.pipeline.campaign", "rockdec.api")]
)


wildcard_constraints:
    campaign=CAMPAIGN,
    unit="|".join(CAMPAIGN_UNITS),
    calhash="[0-9a-f]{16}",


def unit_rows(wildcards):
    """The sheet's rows of a record or block (its job's params: a changed row reruns it alone)."""
    return CAMPAIGN_UNITS[wildcards.unit]


def unit_options(wildcards):
    """The estimate options of a record or block (its first row's: a block's rows share them)."""
    return rockdec_campaign.options(CAMPAIGN_UNITS[wildcards.unit][0])


def unit_records(wildcards):
    """The record files a record's or a block's estimate reads (a shake-table test's base files too)."""
    rows = CAMPAIGN_UNITS[wildcards.unit]
    return list(dict.fromkeys([row["path"] for row in rows] + [row["base"] for row in rows if row.get("base")]))


def _calibrations(plan_file):
    """The calibration files a plan (rockdec.pipeline.campaign.plan) names, in the cache."""
    return [f"{CAMPAIGN_CACHE}/{name}" for name in json.loads(Path(plan_file).read_text())["calibrations"]]


def first_calibration(wildcards):
    """The calibration the estimate of a record or block asks for first, once its first plan
    is made (none for a record the estimate declines, refuses, or a free-rocking test)."""
    return _calibrations(checkpoints.campaign_first_plan.get(**wildcards).output[0])


def planned_calibration(wildcards):
    """Every calibration the estimate of a record or block reads, once its plan is made."""
    return _calibrations(checkpoints.campaign_plan.get(**wildcards).output[0])


def calibration_settings(wildcards):
    """The settings of the calibration ``calhash``, from a plan of a record or block that asks
    for it (the calibration job's params: the same settings whichever plan they are read from).
    Read from the plans on disk: the job joins the run only once a plan that asks for it is made."""
    name = f"calibration-{wildcards.calhash}.nc"
    for unit in CAMPAIGN_UNITS:
        for stage in ("first.json", "json"):
            path = Path(f"results/{CAMPAIGN}/plans/{unit}.{stage}")
            if path.is_file():
                plan = json.loads(path.read_text())
                if name in plan["calibrations"]:
                    return plan["calibrations"][name]
    raise ValueError(f"no plan of the campaign '{CAMPAIGN}' asks for {name}")


def campaign_units(kind):
    """The records' (``record``) or the blocks' (``block``) estimates (JSON)."""
    return [f"results/{CAMPAIGN}/estimates/{unit}.json" for unit in CAMPAIGN_UNITS if unit.startswith(f"{kind}_")]


def campaign_products():
    """What the archive of the campaign holds: each estimate (JSON and NetCDF), the table and
    its NetCDF; each with the rule that writes it (under results/<campaign>/)."""
    files = {}
    for unit in CAMPAIGN_UNITS:
        rule_name = "campaign_record" if unit.startswith("record_") else "campaign_block"
        files.update({f"estimates/{unit}.{fmt}": rule_name for fmt in ("json", "nc")})
    files.update({name: "campaign_table" for name in ("estimates.nc", "estimates.csv", "estimates.md")})
    return files


CAMPAIGN_FIGURES = ("forest", "record_model", "diagnostics")

# A test campaign of measured records (config: campaign; the sheet: config/records.tsv,
# workflow/schemas/records.schema.yaml): one estimate job per record and per block of two or
# more records (pooled), the calibrations they ask for as jobs of their own, keyed by their
# content and kept in the cache `rockdec estimate` reads, then the table, the figures and
# the archive under results/<campaign>/ (`snakemake --cores 2 campaign`).
import json
import os
from pathlib import Path

from rockdec.pipeline import campaign as rockdec_campaign

CAMPAIGN = config["campaign"]["name"]
CAMPAIGN_CACHE = os.path.abspath(
    os.path.expanduser(config["campaign"]["cache"] or rockdec_campaign.default_cache())
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
# process (rockdec.pipeline.in_snakemake.campaign); their code input is what that reaches.
CAMPAIGN_CODE = code_fingerprint(
    "campaign", [find_spec("rockdec.pipeline.in_snakemake").origin, *package_sources("rockdec.pipeline.campaign")]
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
    """The record files a record's or a block's estimate reads."""
    return [row["path"] for row in CAMPAIGN_UNITS[wildcards.unit]]


def planned_calibration(wildcards):
    """The calibration file a record's or block's estimate reads, once its plan is made
    (none for a record the estimate declines, refuses, or a free-rocking test)."""
    plan = json.loads(Path(checkpoints.campaign_plan.get(**wildcards).output[0]).read_text())
    return [f"{CAMPAIGN_CACHE}/{plan['calibration']}"] if plan["calibration"] else []


def calibration_plan(wildcards):
    """The plan (of the first record or block in the sheet's order) that asks for the
    calibration ``calhash``: the calibration job reads its settings there. The plan's date
    does not matter (ancient): a calibration is keyed by its content."""
    name = f"calibration-{wildcards.calhash}.nc"
    for unit in CAMPAIGN_UNITS:
        path = Path(f"results/{CAMPAIGN}/plans/{unit}.json")
        if path.is_file() and json.loads(path.read_text())["calibration"] == name:
            return ancient(str(path))
    raise ValueError(f"no plan of the campaign '{CAMPAIGN}' asks for {name}")


def campaign_units(kind):
    """The records' (``record``) or the blocks' (``block``) estimates (NetCDF)."""
    return [f"results/{CAMPAIGN}/estimates/{unit}.nc" for unit in CAMPAIGN_UNITS if unit.startswith(f"{kind}_")]


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


rule campaign_simulate:
    """A record of the demonstration campaign, simulated with its known e (a row with `simulate`)."""
    input:
        code=CAMPAIGN_CODE,
    output:
        "results/{campaign}/simulated/{record}.nc",
    log:
        "results/{campaign}/logs/simulate_{record}.log",
    benchmark:
        "results/{campaign}/benchmarks/simulate_{record}.tsv"
    wildcard_constraints:
        record="|".join(r for r, row in CAMPAIGN_RECORDS.items() if row.get("simulate")) or "(?!x)x",
    threads: 1
    resources:
        mem_mb=1000,
        runtime=10,
    params:
        row=lambda w: CAMPAIGN_RECORDS[w.record],
    run:
        in_snakemake.campaign(rule, log[0], params.row, output[0])


checkpoint campaign_plan:
    """Which calibration the estimate of a record (or of a block's records pooled) needs: the
    engine's own settings, read by running it up to that point (rockdec.pipeline.campaign.plan)."""
    input:
        records=unit_records,
        code=CAMPAIGN_CODE,
    output:
        "results/{campaign}/plans/{unit}.json",
    log:
        "results/{campaign}/logs/plan_{unit}.log",
    benchmark:
        "results/{campaign}/benchmarks/plan_{unit}.tsv"
    threads: 1
    resources:
        mem_mb=2000,
        runtime=10,
    params:
        rows=unit_rows,
        options=unit_options,
    run:
        in_snakemake.campaign(rule, log[0], params.rows, params.options, output[0])


rule campaign_calibration:
    """One calibration, built once however many records and blocks ask for it, into the cache
    `rockdec estimate` reads (rockdec.calibrate.calibration.load_or_build); on the configured
    Dask engine (ROCKDEC_DASK_SCHEDULER)."""
    input:
        plan=calibration_plan,
        code=CAMPAIGN_CODE,
    output:
        f"{CAMPAIGN_CACHE}/calibration-{{calhash}}.nc",
    log:
        f"results/{CAMPAIGN}/logs/calibration_{{calhash}}.log",
    benchmark:
        f"results/{CAMPAIGN}/benchmarks/calibration_{{calhash}}.tsv"
    threads: 2
    resources:
        mem_mb=4000,
        runtime=60,
    run:
        in_snakemake.campaign(rule, log[0], input.plan, output[0], threads)


rule campaign_record:
    """The estimate of one record: what `rockdec estimate --json` prints for its file and
    options, and the same as CF NetCDF."""
    input:
        records=unit_records,
        plan="results/{campaign}/plans/{unit}.json",
        calibration=planned_calibration,
        code=CAMPAIGN_CODE,
    output:
        json="results/{campaign}/estimates/{unit}.json",
        nc="results/{campaign}/estimates/{unit}.nc",
    log:
        "results/{campaign}/logs/{unit}.log",
    benchmark:
        "results/{campaign}/benchmarks/{unit}.tsv"
    wildcard_constraints:
        unit="record_[A-Za-z][A-Za-z0-9_]*",
    threads: 1
    resources:
        mem_mb=2000,
        runtime=15,
    params:
        rows=unit_rows,
        options=unit_options,
        cache=CAMPAIGN_CACHE,
    run:
        in_snakemake.campaign(rule, log[0], wildcards.unit, params.rows, params.options, params.cache, input.plan, output.json, output.nc, rule)


rule campaign_block:
    """The estimate of one block: its records pooled, as `rockdec estimate` pools the files
    given together."""
    input:
        records=unit_records,
        plan="results/{campaign}/plans/{unit}.json",
        calibration=planned_calibration,
        code=CAMPAIGN_CODE,
    output:
        json="results/{campaign}/estimates/{unit}.json",
        nc="results/{campaign}/estimates/{unit}.nc",
    log:
        "results/{campaign}/logs/{unit}.log",
    benchmark:
        "results/{campaign}/benchmarks/{unit}.tsv"
    wildcard_constraints:
        unit="block_[A-Za-z][A-Za-z0-9_]*",
    threads: 1
    resources:
        mem_mb=2000,
        runtime=15,
    params:
        rows=unit_rows,
        options=unit_options,
        cache=CAMPAIGN_CACHE,
    run:
        in_snakemake.campaign(rule, log[0], wildcards.unit, params.rows, params.options, params.cache, input.plan, output.json, output.nc, rule)


rule campaign_table:
    """Every record's and block's estimate side by side: estimates.nc (CF), .csv and .md."""
    input:
        records=campaign_units("record"),
        blocks=campaign_units("block"),
        code=step_code("campaign_table.py"),
    output:
        nc="results/{campaign}/estimates.nc",
        csv=report("results/{campaign}/estimates.csv", category="Campaign", caption="../report/campaign_table.rst", labels={"table": "estimates"}),
        md="results/{campaign}/estimates.md",
    log:
        "results/{campaign}/logs/table.log",
    benchmark:
        "results/{campaign}/benchmarks/table.tsv"
    threads: 1
    params:
        units=lambda w: list(CAMPAIGN_UNITS),
    conda:
        "../envs/rockdec.yaml"
    script:
        "../scripts/campaign_table.py"


rule campaign_figures:
    """The forest plot of e, the record model of each record and its diagnostics."""
    input:
        nc="results/{campaign}/estimates.nc",
        code=step_code("campaign_figures.py"),
    output:
        **{
            name: report(
                f"results/{{campaign}}/figures/{name}.png",
                category="Campaign",
                caption=f"../report/campaign_{name}.rst",
                labels={"figure": name},
            )
            for name in CAMPAIGN_FIGURES
        },
    log:
        "results/{campaign}/logs/figures.log",
    benchmark:
        "results/{campaign}/benchmarks/figures.tsv"
    threads: 1
    conda:
        "../envs/rockdec.yaml"
    script:
        "../scripts/campaign_figures.py"


rule campaign_archive:
    """The campaign's estimates and table, with the workflow, a manifest and its RO-Crate."""
    input:
        products=lambda w: [f"results/{w.campaign}/{name}" for name in campaign_products()],
        workflow=[f"{workflow.basedir}/{name}" for name in workflow_sources(workflow.basedir)],
    output:
        manifest="results/{campaign}/archive/manifest.json",
        crate="results/{campaign}/archive/ro-crate-metadata.json",
    log:
        "results/{campaign}/logs/archive.log",
    threads: 1
    params:
        name=CAMPAIGN,
        kind="campaign",
        scene=lambda w: {"sheet": campaign_sheet(), "records": {row["record"]: row for row in CAMPAIGN_ROWS}},
        producers=lambda w: campaign_products(),
        root=lambda w: workflow.basedir,
    conda:
        "../envs/rockdec.yaml"
    script:
        "../scripts/archive.py"


rule campaign:
    """The whole campaign (`snakemake --cores 2 campaign`): table, figures and archive."""
    input:
        f"results/{CAMPAIGN}/estimates.csv",
        f"results/{CAMPAIGN}/estimates.md",
        expand("results/{campaign}/figures/{name}.png", campaign=CAMPAIGN, name=CAMPAIGN_FIGURES),
        f"results/{CAMPAIGN}/archive/manifest.json",

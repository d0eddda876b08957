# A test campaign of measured records (config: campaign; the sheet: config/records.tsv,
# workflow/schemas/records.schema.yaml): one estimate job per record and per block of two or
# more records (pooled), the calibrations they ask for as jobs of their own, keyed by their
# content and kept in the cache `rockdec estimate` reads, then the table, the figures and
# the archive under results/<campaign>/ (`snakemake --cores 2 campaign`). The helpers:
# campaign_common.smk.


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


checkpoint campaign_first_plan:
    """The first calibration the estimate of a record (or of a block's records pooled) reads:
    the estimate itself, run up to the first calibration it asks for (rockdec.pipeline.campaign.plan)."""
    input:
        records=unit_records,
        code=CAMPAIGN_CODE,
    output:
        "results/{campaign}/plans/{unit}.first.json",
    log:
        "results/{campaign}/logs/first_plan_{unit}.log",
    benchmark:
        "results/{campaign}/benchmarks/first_plan_{unit}.tsv"
    threads: 1
    resources:
        mem_mb=2000,
        runtime=10,
    params:
        rows=unit_rows,
        options=unit_options,
    run:  # it reads no calibration, and so no cache
        in_snakemake.campaign(rule, log[0], params.rows, params.options, None, None, output[0])


checkpoint campaign_plan:
    """Every calibration the estimate reads: the estimate run again on the first plan's
    calibration, its repair deciding whether it reads the high-passed records' too (the
    first plan as is when it needs no calibration)."""
    input:
        records=unit_records,
        first="results/{campaign}/plans/{unit}.first.json",
        calibration=first_calibration,
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
        cache=CAMPAIGN_CACHE,
    run:
        in_snakemake.campaign(rule, log[0], params.rows, params.options, params.cache, input.first, output[0])


rule campaign_calibration:
    """One calibration, built once however many records and blocks ask for it, into the cache
    `rockdec estimate` reads (rockdec.calibrate.calibration.load_or_build); on the configured
    Dask engine (ROCKDEC_DASK_SCHEDULER). It takes its settings as params, and no input: its
    file is named by its content (the calibration's code included), so neither a new plan that
    asks for it nor an edit elsewhere rebuilds it."""
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
    params:
        settings=calibration_settings,
    run:
        in_snakemake.campaign(rule, log[0], params.settings, output[0], threads)


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
        in_snakemake.campaign(
            rule, log[0], wildcards.unit, params.rows, params.options, params.cache, input.plan, output.json, output.nc, rule, api=rockdec
        )


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
        unit="block_[A-Za-z][A-Za-z0-9_]*(-free|-shake)?",
    threads: 1
    resources:
        mem_mb=2000,
        runtime=15,
    params:
        rows=unit_rows,
        options=unit_options,
        cache=CAMPAIGN_CACHE,
    run:
        in_snakemake.campaign(
            rule, log[0], wildcards.unit, params.rows, params.options, params.cache, input.plan, output.json, output.nc, rule, api=rockdec
        )


rule campaign_table:
    """Every record's and block's estimate side by side: estimates.nc (CF), .csv and .md."""
    input:
        records=campaign_units("record"),
        blocks=campaign_units("block"),
        code=CAMPAIGN_CODE,
    output:
        nc="results/{campaign}/estimates.nc",
        csv=report("results/{campaign}/estimates.csv", category="Campaign", caption="../report/campaign_table.rst", labels={"table": "estimates"}),
        md="results/{campaign}/estimates.md",
    log:
        "results/{campaign}/logs/table.log",
    benchmark:
        "results/{campaign}/benchmarks/table.tsv"
    threads: IN_PROCESS_THREADS
    params:
        units=lambda w: CAMPAIGN_UNITS,
    run:
        in_snakemake.campaign(rule, log[0], [*input.records, *input.blocks], output.nc, output.csv, output.md, params.units)


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
        workflow=WORKFLOW_CODE,
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

rule estimates:
    """Estimators per replicate, zero-window extrapolation, and the table beside the paper."""
    input:
        "results/{scene}/signatures.nc",
        code=STEPS_CODE,
    output:
        estimates="results/{scene}/estimates.nc",
        csv=report("results/{scene}/table.csv", category="Tables", caption="../report/table.rst"),
        md="results/{scene}/table.md",
    log:
        "results/{scene}/logs/estimates.log",
    benchmark:
        "results/{scene}/benchmarks/estimates.tsv"
    threads: IN_PROCESS_THREADS
    params:
        options=lambda w: estimate_options(w.scene),
    run:
        in_snakemake.step(rule, log[0], input[0], output.estimates, output.csv, output.md, params.options)


rule table_readings:
    """Every reading side by side: the scene's own estimates beside the other readings'."""
    input:
        "results/{scene}/readings.nc",
        code=STEPS_CODE,
    output:
        estimates="results/{scene}/estimates_readings.nc",
        csv=report("results/{scene}/table_readings.csv", category="Tables", caption="../report/table_readings.rst"),
        md="results/{scene}/table_readings.md",
    log:
        "results/{scene}/logs/table_readings.log",
    benchmark:
        "results/{scene}/benchmarks/table_readings.tsv"
    threads: IN_PROCESS_THREADS
    params:
        weights=lambda w: scene(w.scene)["estimates"]["weights"],
    run:
        in_snakemake.step(rule, log[0], input[0], output.estimates, output.csv, output.md, params.weights)


rule choices:
    """One unstated choice at a time (lag range, mirrored triggers, level): what moves which estimator."""
    input:
        run="results/{scene}/run.json",
        series=lambda w: series_files(w.scene),
        code=step_code("choices.py"),
    output:
        estimates="results/{scene}/estimates_choices.nc",
        csv=report("results/{scene}/table_choices.csv", category="Tables", caption="../report/table_choices.rst"),
        md="results/{scene}/table_choices.md",
    log:
        "results/{scene}/logs/choices.log",
    benchmark:
        "results/{scene}/benchmarks/choices.tsv"
    threads: 2
    resources:
        mem_mb=6000,
        runtime=60,
    params:
        records=lambda w: records(w.scene),
        signatures=lambda w: scene(w.scene)["signatures"],
        estimates=lambda w: scene(w.scene)["estimates"],
    conda:
        "../envs/rockdec.yaml"
    script:
        "../scripts/choices.py"

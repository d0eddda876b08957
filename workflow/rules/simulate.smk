rule calibrate:
    """The run contract of the scene: model, step and burn-in from pilot simulations, and the
    stationary statistics that set every trigger level. Inside the Snakemake process
    (rockdec.pipeline.in_snakemake.calibrate): a second of work after imports the tables need anyway."""
    input:
        code=CALIBRATE_CODE,
    output:
        "results/{scene}/run.json",
    log:
        "results/{scene}/logs/calibrate.log",
    benchmark:
        "results/{scene}/benchmarks/calibrate.tsv"
    threads: 1
    priority: 20  # the head of every path of the DAG
    params:
        physics=lambda w: physics(w.scene),
    run:
        in_snakemake.calibrate(log[0], params.physics, output[0])


rule stored_series:
    """The series the scene keeps (fig. 2), simulated under its run: a handful of series,
    inside the Snakemake process (rockdec.pipeline.steps.stored_series)."""
    input:
        "results/{scene}/run.json",
        code=STEPS_CODE,
    output:
        "results/{scene}/stored_series.nc",
    log:
        "results/{scene}/logs/stored_series.log",
    benchmark:
        "results/{scene}/benchmarks/stored_series.tsv"
    threads: IN_PROCESS_THREADS
    params:
        records=lambda w: records(w.scene),
    run:
        in_snakemake.step(rule, log[0], input[0], output[0], params.records)


rule series:
    """Every series of one replicate (scenes with `store_series: all`): float32, chunked by seed.
    Inside the Snakemake process on the rule's threads (rockdec.pipeline.steps.series): the
    simulator's kernels are loaded there by `calibrate`, where a script would start Python and
    load them again for each replicate."""
    input:
        "results/{scene}/run.json",
        code=STEPS_CODE,
    output:
        "results/{scene}/series/replicate_{replicate}.nc",
    log:
        "results/{scene}/logs/series_{replicate}.log",
    benchmark:
        "results/{scene}/benchmarks/series_{replicate}.tsv"
    threads: 2
    params:
        records=lambda w: records(w.scene),
    run:
        in_snakemake.step(rule, log[0], input[0], output[0], params.records, int(wildcards.replicate), threads)

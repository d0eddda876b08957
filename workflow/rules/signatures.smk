rule signatures:
    """One pass over every series: the signature cube of the scene's reading, and the window
    curves of every reading it compares (signature sums pool exactly by adding). A scene
    with `replicates_per_job` gathers its jobs' results instead. Inside the Snakemake process, on
    the rule's threads (rockdec.pipeline.in_snakemake.signatures)."""
    input:
        run="results/{scene}/run.json",
        series=lambda w: [] if part_files(w.scene, "signatures") else series_files(w.scene),
        cubes=lambda w: part_files(w.scene, "signatures"),
        curves=lambda w: part_files(w.scene, "readings"),
        code=SIGNATURES_CODE,
    output:
        cube="results/{scene}/signatures.nc",
        readings="results/{scene}/readings.nc",
    log:
        "results/{scene}/logs/signatures.log",
    benchmark:
        "results/{scene}/benchmarks/signatures.tsv"
    threads: 2
    priority: 10  # the longest path of the paper's DAG: start it as soon as the run exists
    resources:
        mem_mb=lambda w: signature_memory_mb(w.scene),
        runtime=60,
    params:
        records=lambda w: records(w.scene),
        settings=lambda w: signature_settings(w.scene),
        first_replicate=0,
    run:
        in_snakemake.signatures(rule, log[0], input, output, params.records, params.settings, params.first_replicate, threads)


rule signature_part:
    """The signature pass over one job's replicates (scenes with `replicates_per_job`)."""
    input:
        run="results/{scene}/run.json",
        series=lambda w: part_series(w.scene, w.part),
        code=SIGNATURES_CODE,
    output:
        cube="results/{scene}/parts/signatures_{part}.nc",
        readings="results/{scene}/parts/readings_{part}.nc",
    log:
        "results/{scene}/logs/signatures_{part}.log",
    benchmark:
        "results/{scene}/benchmarks/signatures_{part}.tsv"
    wildcard_constraints:
        part=r"\d+",
    threads: 2
    resources:
        mem_mb=lambda w: signature_memory_mb(w.scene, int(w.part)),
        runtime=60,
    params:
        records=lambda w: layout.part_records(records(w.scene), int(w.part))[0],
        settings=lambda w: signature_settings(w.scene),
        first_replicate=lambda w: layout.part_records(records(w.scene), int(w.part))[1],
    run:
        in_snakemake.signatures(rule, log[0], input, output, params.records, params.settings, params.first_replicate, threads)

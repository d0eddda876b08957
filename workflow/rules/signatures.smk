rule signatures:
    """One pass over every series: the signature cube of the scene's reading, and the window
    curves of every reading it compares (signature sums pool exactly by adding)."""
    input:
        run="results/{scene}/run.json",
        series=lambda w: series_files(w.scene),
    output:
        cube="results/{scene}/signatures.nc",
        readings="results/{scene}/readings.nc",
    log:
        "results/{scene}/logs/signatures.log",
    benchmark:
        "results/{scene}/benchmarks/signatures.tsv"
    threads: 2
    params:
        records=lambda w: records(w.scene),
        settings=lambda w: signature_settings(w.scene),
    script:
        "../scripts/signatures.py"

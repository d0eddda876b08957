rule signatures:
    """RDD signature cube of every series of the scene, pooled per group of its reading."""
    input:
        sim="results/{scene}/simulations.nc",
        series=lambda w: series_files(w.scene),
    output:
        "results/{scene}/signatures.nc",
    log:
        "results/{scene}/logs/signatures.log",
    benchmark:
        "results/{scene}/benchmarks/signatures.tsv"
    threads: 1  # runs beside `readings`: one core each is the better schedule on 2 cores
    params:
        scene=lambda w: scene(w.scene),
        reading=lambda w: scene(w.scene)["estimates"]["reading"],
    script:
        "../scripts/signatures.py"

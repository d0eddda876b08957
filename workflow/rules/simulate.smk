rule simulate:
    """Calibrate the step and write the scene's stored series with its full provenance."""
    output:
        "results/{scene}/simulations.nc",
    log:
        "results/{scene}/logs/simulate.log",
    benchmark:
        "results/{scene}/benchmarks/simulate.tsv"
    threads: 2
    params:
        scene=lambda w: scene(w.scene),
    script:
        "../scripts/simulate.py"


rule series:
    """Every series of one replicate (scenes with `store_series: all`): float32, chunked by seed."""
    input:
        "results/{scene}/simulations.nc",
    output:
        "results/{scene}/series/replicate_{replicate}.nc",
    log:
        "results/{scene}/logs/series_{replicate}.log",
    benchmark:
        "results/{scene}/benchmarks/series_{replicate}.tsv"
    threads: 1
    params:
        scene=lambda w: scene(w.scene),
    script:
        "../scripts/series.py"

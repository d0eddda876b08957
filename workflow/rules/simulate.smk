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

rule estimates:
    """Estimators per replicate, zero-window extrapolation, and the table beside the paper."""
    input:
        "results/{scene}/signatures.nc",
    output:
        estimates="results/{scene}/estimates.nc",
        csv=report("results/{scene}/table.csv", category="Tables", caption="../report/table.rst"),
        md="results/{scene}/table.md",
    log:
        "results/{scene}/logs/estimates.log",
    benchmark:
        "results/{scene}/benchmarks/estimates.tsv"
    threads: 1
    params:
        scene=lambda w: scene(w.scene),
    script:
        "../scripts/estimates.py"


rule readings:
    """The other readings of the paper's sizes, end to end in memory (runs beside `signatures`)."""
    input:
        sim="results/{scene}/simulations.nc",
        series=lambda w: series_files(w.scene),
    output:
        "results/{scene}/estimates_other_readings.nc",
    log:
        "results/{scene}/logs/readings.log",
    benchmark:
        "results/{scene}/benchmarks/readings.tsv"
    threads: 1  # its cost is the GIL-bound fits of eq. 27; one core leaves the other to `signatures`
    params:
        scene=lambda w: scene(w.scene),
    script:
        "../scripts/readings.py"


rule table_readings:
    """Every reading side by side: the scene's own estimates beside the other readings'."""
    input:
        own="results/{scene}/estimates.nc",
        other="results/{scene}/estimates_other_readings.nc",
    output:
        estimates="results/{scene}/estimates_readings.nc",
        csv=report("results/{scene}/table_readings.csv", category="Tables", caption="../report/table_readings.rst"),
        md="results/{scene}/table_readings.md",
    log:
        "results/{scene}/logs/table_readings.log",
    benchmark:
        "results/{scene}/benchmarks/table_readings.tsv"
    threads: 1
    params:
        scene=lambda w: scene(w.scene),
    script:
        "../scripts/table_readings.py"


rule choices:
    """One unstated choice at a time (lag range, mirrored triggers, level): what moves which estimator."""
    input:
        sim="results/{scene}/simulations.nc",
        series=lambda w: series_files(w.scene),
    output:
        estimates="results/{scene}/estimates_choices.nc",
        csv=report("results/{scene}/table_choices.csv", category="Tables", caption="../report/table_choices.rst"),
        md="results/{scene}/table_choices.md",
    log:
        "results/{scene}/logs/choices.log",
    benchmark:
        "results/{scene}/benchmarks/choices.tsv"
    threads: 2
    params:
        scene=lambda w: scene(w.scene),
    script:
        "../scripts/choices.py"

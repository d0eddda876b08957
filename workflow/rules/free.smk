# Coverage of the free-rocking (free-decay) interval on simulated releases of known e
# (rockdec.studies.free_coverage): e x sensor noise x model, 50 records a cell.


rule free_coverage:
    """Coverage of the free-rocking interval and per-impact bias, per cell."""
    input:
        code=step_code("free_coverage.py"),
    output:
        md="results/studies/free_coverage/table.md",
    log:
        "results/studies/free_coverage/logs/table.log",
    benchmark:
        "results/studies/free_coverage/benchmarks/table.tsv"
    threads: 1
    resources:
        mem_mb=1000,
        runtime=30,
    conda:
        "../envs/rockdec.yaml"
    script:
        "../scripts/free_coverage.py"

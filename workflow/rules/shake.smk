# How often the shake-table test answers and how often its interval holds e, on simulated
# shake-table tests of known e (rockdec.studies.shake_coverage): e x shaking x sensor noise.


rule shake_coverage:
    """Answers and coverage of the shake-table test, per cell."""
    input:
        code=step_code("shake_coverage.py"),
    output:
        md="results/studies/shake_coverage/table.md",
    log:
        "results/studies/shake_coverage/logs/table.log",
    benchmark:
        "results/studies/shake_coverage/benchmarks/table.tsv"
    threads: 1
    resources:
        mem_mb=1000,
        runtime=30,
    conda:
        "../envs/rockdec.yaml"
    script:
        "../scripts/shake_coverage.py"

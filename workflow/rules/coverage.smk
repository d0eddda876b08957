# Coverage of `rockdec estimate`'s interval on simulated records of known e (white and coloured load).
from rockdec.layout import COVERAGE_CASES as CASES


rule coverage_case:
    """One case of the study: records of known e through `rockdec estimate`'s pipeline."""
    input:
        code=step_code("coverage_case.py"),
    output:
        "results/studies/coverage/{case}.nc",
    log:
        "results/studies/coverage/logs/{case}.log",
    benchmark:
        "results/studies/coverage/benchmarks/{case}.tsv"
    wildcard_constraints:
        case="|".join(CASES),
    threads: 2
    resources:
        mem_mb=4000,
        runtime=60,
    params:
        cache="results/studies/coverage/calibration",
    conda:
        "../envs/rockdec.yaml"
    script:
        "../scripts/coverage_case.py"


rule coverage_table:
    """Bias, spread, interval width and coverage per case, e and estimator."""
    input:
        cases=expand("results/studies/coverage/{case}.nc", case=CASES),
        code=step_code("coverage_table.py"),
    output:
        csv=report("results/studies/coverage/table.csv", category="Measured records", caption="../report/coverage.rst"),
        md="results/studies/coverage/table.md",
    log:
        "results/studies/coverage/logs/table.log",
    benchmark:
        "results/studies/coverage/benchmarks/table.tsv"
    threads: 1
    conda:
        "../envs/rockdec.yaml"
    script:
        "../scripts/coverage_table.py"


rule fig_coverage:
    """Coverage and bias of each estimator against the load's corner frequency."""
    input:
        "results/studies/coverage/table.csv",
    output:
        png=report("results/studies/coverage/coverage.png", category="Measured records", caption="../report/coverage.rst"),
        pdf="results/studies/coverage/coverage.pdf",
    log:
        "results/studies/coverage/logs/fig_coverage.log",
    benchmark:
        "results/studies/coverage/benchmarks/fig_coverage.tsv"
    threads: 1
    conda:
        "../envs/rockdec.yaml"
    script:
        "../scripts/fig_coverage.py"


rule coverage:
    """The whole coverage study (`snakemake --cores 2 coverage`)."""
    input:
        rules.coverage_table.output,
        rules.fig_coverage.output,

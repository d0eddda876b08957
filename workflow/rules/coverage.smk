# Coverage of `rockdec estimate`'s interval on simulated records of known e, over conditions
# (sensor noise, load colour, both) and two simulators: one job per cell.
import re

from rockdec.pipeline.layout import COVERAGE_CASES as CASES


rule coverage_case:
    """One cell of the study: records of known e through `rockdec estimate`'s path."""
    input:
        unpack(coverage_inputs),
    output:
        "results/studies/coverage/cells/{case}.nc",
    log:
        "results/studies/coverage/logs/{case}.log",
    benchmark:
        "results/studies/coverage/benchmarks/{case}.tsv"
    wildcard_constraints:
        case="|".join(re.escape(c) for c in CASES),
    threads: 2
    resources:
        mem_mb=4000,
        runtime=120,
    params:
        cache="results/studies/coverage/calibration",
        records=lambda wildcards: coverage_records(wildcards.case),
        n_points=config["coverage"]["n_points"],
    conda:
        "../envs/rockdec.yaml"
    script:
        "../scripts/coverage_case.py"


rule coverage_table:
    """Coverage, corrected bias, spread, interval width and width / (3.92 sd), nulls and warnings per cell, and the
    cells read against chance and the target."""
    input:
        cases=expand("results/studies/coverage/cells/{case}.nc", case=CASES),
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
    """Coverage and corrected bias per condition and e, the 92-98 % band shown."""
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


rule coverage_fresh:
    """A cell's calibrations judged on fresh records of its route (rockdec.studies.coverage.fresh_coverage)."""
    input:
        unpack(coverage_fresh_inputs),
    output:
        "results/studies/coverage/fresh/{case}.csv",
    log:
        "results/studies/coverage/logs/fresh_{case}.log",
    benchmark:
        "results/studies/coverage/benchmarks/fresh_{case}.tsv"
    wildcard_constraints:
        case="|".join(re.escape(c) for c in CASES),
    threads: 2
    resources:
        mem_mb=2000,
        runtime=60,
    params:
        cache="results/studies/coverage/calibration",
        records=config["coverage"]["fresh_records"],
    conda:
        "../envs/rockdec.yaml"
    script:
        "../scripts/coverage_fresh.py"


rule coverage_fresh_table:
    """Each cell's coverage and width / (3.92 sd) on its own records beside its calibrations' on fresh records,
    both read against chance, and each calibration's check on the fresh records it served."""
    input:
        cases=expand("results/studies/coverage/cells/{case}.nc", case=CASES),
        fresh=expand("results/studies/coverage/fresh/{case}.csv", case=CASES),
        code=step_code("coverage_fresh_table.py"),
    output:
        csv="results/studies/coverage/fresh/table.csv",
        md="results/studies/coverage/fresh/table.md",
        calibrations="results/studies/coverage/fresh/calibrations.csv",
    log:
        "results/studies/coverage/logs/fresh_table.log",
    benchmark:
        "results/studies/coverage/benchmarks/fresh_table.tsv"
    threads: 1
    conda:
        "../envs/rockdec.yaml"
    script:
        "../scripts/coverage_fresh_table.py"

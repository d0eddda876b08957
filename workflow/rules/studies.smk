# Studies beyond the paper, under results/studies/ (apart from the per-scene results/{scene}/).
# Each compute rule lists the source of every rockdec module its numbers come from
# (step_code, in common.smk), so a change to the study's code reruns it; each plot
# rule lists only the drawing code (rockdec.report.figures) and the study's data, so a change to
# a plot never reruns the study.

import re

from rockdec.pipeline.layout import DIAGNOSTICS_PARTS


rule amplitude:
    """Simplified vs Housner model over sigma_Y/theta_cr: where the simplified model's estimates drift."""
    input:
        code=step_code("amplitude.py"),
    output:
        estimates="results/studies/amplitude/amplitude.nc",
        csv=report("results/studies/amplitude/table.csv", category="Amplitude", caption="../report/amplitude.rst"),
        md="results/studies/amplitude/table.md",
    log:
        "results/studies/amplitude/logs/amplitude.log",
    benchmark:
        "results/studies/amplitude/benchmarks/amplitude.tsv"
    threads: 2
    resources:
        mem_mb=4000,
        runtime=60,
    params:
        scene=scene("amplitude"),
    conda:
        "../envs/rockdec.yaml"
    script:
        "../scripts/amplitude.py"


rule fig_amplitude:
    """Estimates of both models against the amplitude ratio."""
    input:
        code=FIGURES_CODE,
        nc="results/studies/amplitude/amplitude.nc",
    output:
        png=report("results/studies/amplitude/figures/amplitude.png", category="Amplitude", caption="../report/amplitude.rst"),
        pdf="results/studies/amplitude/figures/amplitude.pdf",
    log:
        "results/studies/amplitude/logs/fig_amplitude.log",
    benchmark:
        "results/studies/amplitude/benchmarks/fig_amplitude.tsv"
    threads: 1
    conda:
        "../envs/rockdec.yaml"
    script:
        "../scripts/fig_amplitude.py"


rule amplitude_study:
    """The whole amplitude sweep, table and figure (`snakemake --cores 2 amplitude_study`)."""
    input:
        rules.amplitude.output,
        rules.fig_amplitude.output,


rule diagnostics_records:
    """Records of known e (one job per e, load and noise level), clean and with each defect at growing sizes, through `rockdec estimate`'s checks."""
    input:
        code=step_code("diagnostics_records.py"),
    output:
        "results/studies/diagnostics/records_{part}.csv",
    log:
        "results/studies/diagnostics/logs/records_{part}.log",
    benchmark:
        "results/studies/diagnostics/benchmarks/records_{part}.tsv"
    wildcard_constraints:
        part="|".join(re.escape(name) for name in DIAGNOSTICS_PARTS),
    threads: 2
    resources:
        mem_mb=4000,
        runtime=150,
    params:
        cache="results/studies/diagnostics/calibration",
    conda:
        "../envs/rockdec.yaml"
    script:
        "../scripts/diagnostics_records.py"


rule diagnostics_table:
    """Per check, e and defect size: the shift of e, false alarms and detections."""
    input:
        records=expand("results/studies/diagnostics/records_{part}.csv", part=DIAGNOSTICS_PARTS),
        code=step_code("diagnostics_table.py"),
    output:
        csv=report("results/studies/diagnostics/table.csv", category="Measured records", caption="../report/diagnostics.rst"),
        md="results/studies/diagnostics/table.md",
    log:
        "results/studies/diagnostics/logs/table.log",
    benchmark:
        "results/studies/diagnostics/benchmarks/table.tsv"
    threads: 1
    conda:
        "../envs/rockdec.yaml"
    script:
        "../scripts/diagnostics_table.py"


rule diagnostics:
    """The warnings' false-alarm and detection study (`snakemake --cores 2 diagnostics`)."""
    input:
        rules.diagnostics_table.output,

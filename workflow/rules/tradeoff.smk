# Speed against accuracy (scene `tradeoff`): every knob of rockdec.studies.tradeoff.KNOBS moved one at a
# time from the scene; one compute rule writes the study, one plot rule only reads it
# (package_sources: workflow/rules/common.smk).


rule tradeoff:
    """CPU cost and bias/std/RMSE of every estimator for each configuration of the study."""
    input:
        code=step_code("tradeoff.py"),
    output:
        nc="results/studies/tradeoff/tradeoff.nc",
        csv=report(
            "results/studies/tradeoff/table.csv",
            category="Speed vs accuracy",
            caption="../report/tradeoff_table.rst",
        ),
        md="results/studies/tradeoff/table.md",
    log:
        "results/studies/tradeoff/logs/tradeoff.log",
    benchmark:
        "results/studies/tradeoff/benchmarks/tradeoff.tsv"
    threads: 2
    resources:
        mem_mb=8000,
        runtime=120,
    params:
        scene=lambda w: scene("tradeoff"),
    conda:
        "../envs/rockdec.yaml"
    script:
        "../scripts/tradeoff.py"


rule fig_tradeoff:
    """Pareto plot: CPU seconds per replicate against RMSE, one marker per configuration."""
    input:
        code=FIGURES_CODE,
        nc="results/studies/tradeoff/tradeoff.nc",
    output:
        **{
            fmt: report(
                f"results/studies/tradeoff/figures/pareto.{fmt}",
                caption="../report/tradeoff_pareto.rst",
                category="Speed vs accuracy",
                labels={"figure": "pareto", "format": fmt.upper()},
            )
            for fmt in ("png", "pdf")
        },
    log:
        "results/studies/tradeoff/logs/fig_tradeoff.log",
    benchmark:
        "results/studies/tradeoff/benchmarks/fig_tradeoff.tsv"
    threads: 1
    conda:
        "../envs/rockdec.yaml"
    script:
        "../scripts/fig_tradeoff.py"


rule tradeoff_study:
    """The whole speed/accuracy study, table and Pareto plot (`snakemake --cores 2 tradeoff_study`)."""
    input:
        rules.tradeoff.output,
        rules.fig_tradeoff.output,

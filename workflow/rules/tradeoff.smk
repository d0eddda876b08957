# Speed against accuracy (scene `tradeoff`): every knob of rockdec.tradeoff.KNOBS moved one at a
# time from the scene; one compute rule writes the study, one plot rule only reads it.
from importlib.util import find_spec

TRADEOFF_CODE = find_spec("rockdec.tradeoff").origin


# results/tradeoff/table.csv|md are also a pattern of rule `estimates` (scene tradeoff):
# the study's tables are the ones meant under results/tradeoff/.
ruleorder: tradeoff > estimates


rule tradeoff:
    """CPU cost and bias/std/RMSE of every estimator for each configuration of the study."""
    output:
        nc="results/tradeoff/tradeoff.nc",
        csv=report(
            "results/tradeoff/table.csv",
            category="Speed vs accuracy",
            caption="../report/tradeoff_table.rst",
        ),
        md="results/tradeoff/table.md",
    log:
        "results/tradeoff/logs/tradeoff.log",
    benchmark:
        "results/tradeoff/benchmarks/tradeoff.tsv"
    threads: 2
    params:
        scene=lambda w: scene("tradeoff"),
    script:
        "../scripts/tradeoff.py"


rule fig_tradeoff:
    """Pareto plot: CPU seconds per replicate against RMSE, one marker per configuration."""
    input:
        code=TRADEOFF_CODE,
        nc="results/tradeoff/tradeoff.nc",
    output:
        **{
            fmt: report(
                f"results/tradeoff/figures/pareto.{fmt}",
                caption="../report/tradeoff_pareto.rst",
                category="Speed vs accuracy",
                labels={"figure": "pareto", "format": fmt.upper()},
            )
            for fmt in ("png", "pdf")
        },
    log:
        "results/tradeoff/logs/fig_tradeoff.log",
    benchmark:
        "results/tradeoff/benchmarks/fig_tradeoff.tsv"
    threads: 1
    script:
        "../scripts/fig_tradeoff.py"

# rockdec: the coefficient of restitution of a rocking block by the Random Decrement technique.
# `snakemake --cores 2` rebuilds every figure and table of the default scene (config/config.yaml).

report: "workflow/report/workflow.rst"


configfile: "config/config.yaml"


include: "workflow/rules/common.smk"
include: "workflow/rules/simulate.smk"
include: "workflow/rules/signatures.smk"
include: "workflow/rules/estimates.smk"
include: "workflow/rules/figures.smk"
include: "workflow/rules/studies.smk"
include: "workflow/rules/tradeoff.smk"
include: "workflow/rules/coverage.smk"
include: "workflow/rules/archive.smk"


rule all:
    default_target: True
    input:
        default_products(),

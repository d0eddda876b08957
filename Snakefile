# rockdec: the coefficient of restitution of a rocking block by the Random Decrement technique.
# `snakemake --cores 2` rebuilds every figure and table of the default scene (config/config.yaml).

configfile: "config/config.yaml"


include: "workflow/rules/common.smk"
include: "workflow/rules/simulate.smk"


rule all:
    default_target: True
    input:
        default_products(),

# rockdec: the coefficient of restitution of a rocking block by the Random Decrement technique.
# `snakemake --cores 2` rebuilds every figure and table of the default scene (config/config.yaml).

from snakemake.utils import min_version

min_version("9.0")


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
include: "workflow/rules/free.smk"
include: "workflow/rules/shake.smk"
include: "workflow/rules/archive.smk"
include: "workflow/rules/campaign_common.smk"
include: "workflow/rules/campaign.smk"


# Figures, tables and the archive read finished products and take seconds: on a cluster
# they run on the submitting node instead of waiting in the queue.
localrules:
    all,
    archive,
    archive_scene,
    estimates,
    table_readings,
    fig1b,
    fig2,
    fig3,
    fig4,
    fig_ev,
    amplitude_study,
    fig_amplitude,
    tradeoff_study,
    fig_tradeoff,
    coverage,
    coverage_table,
    coverage_fresh_table,
    fig_coverage,
    campaign,
    campaign_table,
    campaign_figures,
    campaign_archive,


# A signal stops the signature pass inside Snakemake's process as it stops a script job
# (rockdec.pipeline.in_snakemake.stop_on_signals): set after Snakemake's own handlers.
onstart:
    in_snakemake.stop_on_signals()


# The scheduler's last re-evaluation timer would keep the process alive for up to a second
# after the last job (rockdec.pipeline.in_snakemake.end_of_run).
onsuccess:
    in_snakemake.end_of_run()


onerror:
    in_snakemake.end_of_run()


rule all:
    default_target: True
    input:
        default_products(),

# Studies beyond the paper; each writes data, and its figure rule only reads it.

# results/amplitude/table.csv|md also match rule `estimates` (scene amplitude): the study's are meant.
ruleorder: amplitude > estimates


rule amplitude:
    """Simplified vs Housner model over sigma_Y/theta_cr: where the simplified model's estimates drift."""
    output:
        estimates="results/amplitude/amplitude.nc",
        csv=report("results/amplitude/table.csv", category="Amplitude", caption="../report/amplitude.rst"),
        md="results/amplitude/table.md",
    log:
        "results/amplitude/logs/amplitude.log",
    benchmark:
        "results/amplitude/benchmarks/amplitude.tsv"
    threads: 2
    params:
        scene=scene("amplitude"),
    script:
        "../scripts/amplitude.py"


rule fig_amplitude:
    """Estimates of both models against the amplitude ratio."""
    input:
        "results/amplitude/amplitude.nc",
    output:
        png=report("results/amplitude/figures/amplitude.png", category="Amplitude", caption="../report/amplitude.rst"),
        pdf="results/amplitude/figures/amplitude.pdf",
    log:
        "results/amplitude/logs/fig_amplitude.log",
    benchmark:
        "results/amplitude/benchmarks/fig_amplitude.tsv"
    threads: 1
    params:
        e_target=scene("amplitude")["system"]["e"],
    script:
        "../scripts/fig_amplitude.py"

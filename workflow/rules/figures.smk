# Figures: the signature of the stored series (paper fig. 2c) and one plot rule per figure.
# Plot rules only read NetCDF products, so changing a plot never reruns a simulation; each
# also lists the plotting module, so editing it redraws every figure. The stored series'
# signature runs inside the Snakemake process (run: with rockdec.pipeline.in_snakemake.step,
# common.smk); each figure rule hands its figure to one of two worker processes started with
# the run's first figure (rockdec.pipeline.in_snakemake.draw), so matplotlib loads once for
# all of them and two figures draw at once.
rule stored_signature:
    """Signature cube of the stored series pooled into one group (the estimate of fig. 2c)."""
    input:
        "results/{scene}/stored_series.nc",
        code=STEPS_CODE,
    output:
        "results/{scene}/stored_signature.nc",
    log:
        "results/{scene}/logs/stored_signature.log",
    benchmark:
        "results/{scene}/benchmarks/stored_signature.tsv"
    threads: IN_PROCESS_THREADS
    params:
        signatures=lambda w: scene(w.scene)["signatures"],
    run:
        in_snakemake.step(rule, log[0], input[0], output[0], params.signatures)


rule fig1b:
    """Paper fig. 1b: free-rocking period of eqs. 3 and 5 against amplitude (no data)."""
    input:
        code=FIGURES_CODE,
    output:
        **figure_outputs("fig1b"),
    log:
        "results/{scene}/logs/fig1b.log",
    benchmark:
        "results/{scene}/benchmarks/fig1b.tsv"
    threads: IN_PROCESS_THREADS
    run:
        in_snakemake.draw(rule, log[0], [output.png, output.pdf])


rule fig2:
    """Paper fig. 2: two simulated responses and the free-response estimate of the stored series."""
    input:
        code=FIGURES_CODE,
        sim="results/{scene}/stored_series.nc",
        sig="results/{scene}/stored_signature.nc",
    output:
        **figure_outputs("fig2"),
    log:
        "results/{scene}/logs/fig2.log",
    benchmark:
        "results/{scene}/benchmarks/fig2.tsv"
    threads: IN_PROCESS_THREADS
    run:
        in_snakemake.draw(rule, log[0], input.sim, input.sig, [output.png, output.pdf])


rule fig3:
    """Paper fig. 3: e_g and e_0 against the window size, extrapolated to zero."""
    input:
        code=FIGURES_CODE,
        est="results/{scene}/estimates.nc",
    output:
        **figure_outputs("fig3"),
    log:
        "results/{scene}/logs/fig3.log",
    benchmark:
        "results/{scene}/benchmarks/fig3.tsv"
    threads: IN_PROCESS_THREADS
    run:
        in_snakemake.draw(rule, log[0], input.est, [output.png, output.pdf])


rule fig4:
    """Paper fig. 4: e1..e4 of every replicate against the window size."""
    input:
        code=FIGURES_CODE,
        est="results/{scene}/estimates.nc",
    output:
        **figure_outputs("fig4"),
    log:
        "results/{scene}/logs/fig4.log",
    benchmark:
        "results/{scene}/benchmarks/fig4.tsv"
    threads: IN_PROCESS_THREADS
    run:
        in_snakemake.draw(rule, log[0], input.est, [output.png, output.pdf])


rule fig_ev:
    """The paper's section 6 proposal: the D_v signature and the estimator e_v."""
    input:
        code=FIGURES_CODE,
        sig="results/{scene}/signatures.nc",
        est="results/{scene}/estimates.nc",
    output:
        **figure_outputs("fig_ev"),
    log:
        "results/{scene}/logs/fig_ev.log",
    benchmark:
        "results/{scene}/benchmarks/fig_ev.tsv"
    threads: IN_PROCESS_THREADS
    run:
        in_snakemake.draw(rule, log[0], input.sig, input.est, [output.png, output.pdf])

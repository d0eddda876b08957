# Archive: every NetCDF the tables and figures of a scene are made from, the tables, and a
# manifest (size, SHA-256, producing rule, settings, versions, commit) that
# `rockdec verify` re-checks.


rule archive:
    """The archive of the default scene: results/<default scene>/archive."""
    input:
        f"results/{config['default_scene']}/archive",


rule archive_scene:
    """Copy the scene's NetCDF products and tables into one folder with manifest.json."""
    input:
        lambda w: [f"results/{w.scene}/{name}" for name in archive_files(w.scene)],
    output:
        directory("results/{scene}/archive"),
    log:
        "results/{scene}/logs/archive.log",
    threads: 1
    params:
        scene=lambda w: scene(w.scene),
        producers=lambda w: archive_files(w.scene),
    conda:
        "../envs/rockdec.yaml"
    script:
        "../scripts/archive.py"

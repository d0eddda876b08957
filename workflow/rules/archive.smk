# Archive: every NetCDF the tables and figures of a scene are made from, the tables, the
# workflow's own files, a manifest (size, SHA-256, producing rule, settings, versions,
# commit, times) that `rockdec verify` re-checks, and the Workflow Run Crate derived from it.

from rockdec.pipeline.layout import workflow_sources

# The workflow's own files, which an archive holds, as one input (common.smk, code_fingerprint).
WORKFLOW_CODE = code_fingerprint("workflow", [f"{workflow.basedir}/{name}" for name in workflow_sources(workflow.basedir)])


rule archive:
    """The archive of the default scene: results/<default scene>/archive."""
    input:
        f"results/{config['default_scene']}/archive/manifest.json",


rule archive_scene:
    """Copy the scene's NetCDF products, tables and workflow into one folder with
    manifest.json and ro-crate-metadata.json."""
    input:
        products=lambda w: [f"results/{w.scene}/{name}" for name in archive_files(w.scene)],
        workflow=WORKFLOW_CODE,
    output:
        # the folder's two files of its own, not the folder: Snakemake would leave in a
        # directory() output a marker file the manifest does not list
        manifest="results/{scene}/archive/manifest.json",
        crate="results/{scene}/archive/ro-crate-metadata.json",
    log:
        "results/{scene}/logs/archive.log",
    threads: 1
    params:
        name=lambda w: w.scene,
        kind="scene",
        scene=lambda w: scene(w.scene),
        producers=lambda w: archive_files(w.scene),
        root=lambda w: workflow.basedir,  # the Snakefile's folder; a local rule, so it runs where that folder is
    conda:
        "../envs/rockdec.yaml"
    script:
        "../scripts/archive.py"

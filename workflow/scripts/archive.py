"""Rules `archive_scene` and `campaign_archive`: the products, tables and workflow, with
manifest.json and the Workflow Run Crate derived from it (ro-crate-metadata.json)."""

import sys
from pathlib import Path

from rockdec.pipeline import archive

sys.stderr = open(snakemake.log[0], "w")
folder = Path(snakemake.output.manifest).parent
params = snakemake.params
manifest = archive.write_archive(folder, folder.parent, params.producers, params.name, params.scene, params.root, kind=params.kind)
print(f"{len(params.producers)} products and the workflow -> {manifest}", file=sys.stderr)

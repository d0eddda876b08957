"""Rule `archive_scene`: the scene's NetCDF products and tables, with manifest.json."""

import sys
from pathlib import Path

from rockdec import archive

sys.stderr = open(snakemake.log[0], "w")
folder = Path(snakemake.output[0])
manifest = archive.write_archive(
    folder, folder.parent, snakemake.params.producers, snakemake.wildcards.scene, snakemake.params.scene
)
print(f"{len(snakemake.params.producers)} files -> {manifest}", file=sys.stderr)

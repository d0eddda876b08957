# Config validation and the helpers that turn a scene into file names.
import sys
from importlib.util import find_spec

from rockdec import config as rockdec_config
from rockdec import series as rockdec_series

# Name the file the user passed (--configfile), not always the default one; one sentence, exit code 2.
try:
    rockdec_config.validate(config, source=", ".join(map(str, workflow.overwrite_configfiles)) or rockdec_config.DEFAULT_PATH)
except rockdec_config.ConfigError as exc:
    print(f"rockdec: error: {exc}", file=sys.stderr)
    sys.exit(2)

SCENES = sorted(config["scenes"])


wildcard_constraints:
    scene="|".join(SCENES),
    replicate=r"\d+",


def scene(name):
    """The completed settings of scene ``name``."""
    return config["scenes"][name]


def figure_names(name):
    """The figures scene ``name`` can draw: fig. 2 needs at least one stored series."""
    figures = ["fig1b", "fig2", "fig3", "fig4", "fig_ev"]
    if rockdec_series.simulation_seeds(scene(name)).size < 1:
        figures.remove("fig2")
    return figures


def series_files(name):
    """The per-replicate series files of scene ``name`` (none unless `store_series: all`)."""
    return [str(path) for path in rockdec_series.replicate_files(f"results/{name}", scene(name))]


def archive_files(name):
    """What the archive of scene ``name`` holds: every NetCDF its tables and figures are made
    from, and the tables; each with the rule that writes it (under results/{name}/)."""
    files = {"simulations.nc": "simulate"}
    files.update({str(path): "series" for path in rockdec_series.replicate_files("", scene(name))})
    files.update({"signatures.nc": "signatures", "estimates.nc": "estimates", "table.csv": "estimates", "table.md": "estimates"})
    if "fig2" in figure_names(name):
        files["stored_signature.nc"] = "stored_signature"
    if scene(name)["estimates"]["compare_readings"]:
        files["estimates_other_readings.nc"] = "readings"
        files.update({f: "table_readings" for f in ("estimates_readings.nc", "table_readings.csv", "table_readings.md")})
    return files


def default_products():
    """Every product of the default scene: its tables and its figures (PNG and PDF)."""
    name = config["default_scene"]
    tables = ["table.csv", "table.md"]
    if scene(name)["estimates"]["compare_readings"]:
        tables += ["table_readings.csv", "table_readings.md"]
    figures = [f"figures/{fig}.{fmt}" for fig in figure_names(name) for fmt in ("png", "pdf")]
    return [f"results/{name}/{product}" for product in tables + figures]


FIGURES_CODE = find_spec("rockdec.figures").origin


def figure_outputs(name):
    """PNG and PDF of figure ``name`` for the scene, both tagged for the report."""
    return {
        fmt: report(
            f"results/{{scene}}/figures/{name}.{fmt}",
            caption=f"../report/{name}.rst",
            category="Figures",
            labels={"figure": name, "format": fmt.upper()},
        )
        for fmt in ("png", "pdf")
    }

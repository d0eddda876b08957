# Config validation and the helpers that turn a scene into file names.
import sys
from importlib.util import find_spec

from rockdec.pipeline import config as rockdec_config
from rockdec.pipeline import figure_workers, in_snakemake, layout
from rockdec.sources import fingerprint_file, package_sources

# Values given with --config arrive as text: read them as YAML 1.2 values. An error names where
# the bad field was set (--config, or the file the user passed with --configfile); one
# sentence, exit code 2, before any job (so `snakemake -n` refuses too).
try:
    overrides = dict(workflow.config_settings.config)  # --config KEY=VALUE alone (overwrite_config adds --configfile)
    for path in workflow.configfiles:  # Snakemake reads them as YAML 1.1: refuse what YAML 1.2 reads otherwise
        rockdec_config.check_yaml11(path)
    rockdec_config.validate(
        rockdec_config.apply_overrides(config, overrides),
        source=", ".join(map(str, workflow.overwrite_configfiles)) or rockdec_config.DEFAULT_PATH,
        overrides=overrides,
    )
except rockdec_config.ConfigError as exc:
    print(f"rockdec: error: {exc}", file=sys.stderr)
    sys.exit(2)

SCENES = sorted(config["scenes"])


wildcard_constraints:
    scene="|".join(SCENES),
    replicate=r"\d+",


def scene(name):
    """The completed settings of scene ``name``, keys sorted: a rule's params compare by their
    text, so reordering the keys of a scene reruns nothing."""
    return rockdec_config.canonical(config["scenes"][name])


# The part of a scene each of the rules reads. A job receives only its own settings as params, so
# editing another setting (or a description) reruns nothing of it.
def physics(name):
    """The settings `calibrate` reads -- the model, the system and the excitation."""
    return {key: scene(name)[key] for key in ("model", "system", "excitation")}


def records(name):
    """The scene's records: seeds, sizes and chunks."""
    return scene(name)["records"]


def signature_settings(name):
    """What the signature pass reads: its settings, the readings it serves and the fits
    of their window curves."""
    est = scene(name)["estimates"]
    return {"signatures": scene(name)["signatures"], "readings": layout.compared_readings(est), "fit_points": est["fit_points"]}


def estimate_options(name):
    """The settings `estimates` reads -- the fits and the extrapolation weights."""
    return {key: scene(name)["estimates"][key] for key in ("fit_points", "weights")}


def signature_memory_mb(name, part=None):
    """Memory a signature job asks of a cluster (resources: mem_mb), from the scene's sizes."""
    return int(rockdec_config.signature_memory_bytes(scene(name), part) / 1e6)


def figure_names(name):
    """The figures scene ``name`` can draw: fig. 2 needs at least one stored series."""
    figures = list(layout.FIGURES)
    if layout.simulation_seeds(records(name)).size < 1:
        figures.remove("fig2")
    return figures


def series_files(name):
    """The per-replicate series files of scene ``name`` (none unless `store_series: all`)."""
    return [str(path) for path in layout.replicate_files(f"results/{name}", records(name))]


def archive_files(name):
    """What the archive of scene ``name`` holds: the run, every NetCDF its tables and figures
    are made from, and the tables; each with the rule that writes it (under results/{name}/)."""
    files = {"run.json": "calibrate", "stored_series.nc": "stored_series"}
    files.update({str(path): "series" for path in layout.replicate_files("", records(name))})
    files.update({"signatures.nc": "signatures", "readings.nc": "signatures"})
    files.update({"estimates.nc": "estimates", "table.csv": "estimates", "table.md": "estimates"})
    if "fig2" in figure_names(name):
        files["stored_signature.nc"] = "stored_signature"
    if scene(name)["estimates"]["compare_readings"]:
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


FIGURES_CODE = find_spec("rockdec.report.figures").origin


def code_fingerprint(name, sources):
    """The one code input of the rules that run ``sources`` (a file of their SHA-256s,
    :func:`rockdec.sources.fingerprint_file`), where listing the files themselves would print
    dozens of paths on each job's lines of the console: a module edited reruns them."""
    return fingerprint_file(f".snakemake/rockdec-code/{name}.sha256", sources)


# The stored series and the tables run inside the Snakemake process (`run:` with
# rockdec.pipeline.in_snakemake.step, in threads: profiles/default), so their libraries load once
# a run; their code input is what that module reaches (rockdec.pipeline.steps and the modules it runs).
# The figures are `run:` rules too, each waiting in a thread for one of the two figure workers
# (rockdec.pipeline.in_snakemake.draw).
STEPS_CODE = code_fingerprint("steps", package_sources("rockdec.pipeline.in_snakemake"))

# Those light steps (the stored series and their signature, the tables, the figures) ask for
# no core of --cores when Snakemake runs the jobs itself: a second or less each, one at a time in
# a thread of Snakemake's own process (rockdec.pipeline.in_snakemake.step), or two at a time in
# the figure workers. So the stored series start with the signature pass instead of after it,
# fig. 1b with `calibrate`, and the tables and figures all start as soon as the pass ends.
# (Snakemake starts no job, not even one of no core, while every core is taken: the stored
# series' signature and fig. 2 wait for the pass's end.) A job sent elsewhere (a cluster) asks
# for one.
IN_PROCESS_THREADS = 0 if workflow.local_exec else 1

# The figure workers (rockdec.pipeline.figure_workers): two, one under --cores 1, so that two
# figures drawing at once stay within the cores given.
try:
    figure_workers.PROCESSES = max(1, min(figure_workers.PROCESSES, int(workflow.cores)))
except Exception:  # no --cores (a cluster run with --jobs): Snakemake's WorkflowError; keep two
    pass

# `calibrate` runs there too, but reaches only the run contract's modules: editing a table or a
# figure never recalibrates (and so never reruns the signature pass).
CALIBRATE_CODE = code_fingerprint("calibrate", [find_spec("rockdec.pipeline.in_snakemake").origin, *package_sources("rockdec.physics.run")])


# The signature pass runs there too (rockdec.pipeline.in_snakemake.signatures), on its rule's
# threads; its code input is what the pass reaches, so editing a table or a figure never reruns it.
SIGNATURES_CODE = code_fingerprint(
    "signatures", [find_spec("rockdec.pipeline.in_snakemake").origin, *package_sources("rockdec.pipeline.replicates", "rockdec.console")]
)


def step_code(script):
    """The fingerprint (:func:`code_fingerprint`) of every rockdec module workflow script
    ``script`` runs (:func:`rockdec.sources.package_sources`): a compute rule's code input, so
    an edit to any of them reruns it."""
    return code_fingerprint(script.removesuffix(".py"), package_sources(f"{workflow.basedir}/workflow/scripts/{script}"))


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


def part_files(name, kind):
    """The signature jobs' files of scene ``name`` (none when its pass runs as one job)."""
    return [f"results/{name}/parts/{kind}_{part}.nc" for part in layout.signature_parts(records(name))]


def part_series(name, part):
    """The per-replicate series files one signature job reads (`store_series: all`)."""
    rec, first = layout.part_records(records(name), int(part))
    return series_files(name)[first : first + rec["replicates"]]


def coverage_records(case):
    """Records of a cell: `coverage.records` for the kernel's cells, `coverage.reference_records`
    for the reference simulator's."""
    simulator = layout.COVERAGE_CASES[case][0]
    return config["coverage"]["records" if simulator == "kernel" else "reference_records"]


def coverage_inputs(wildcards):
    """A cell's code: the modules its script runs, and the reference simulator for its cells."""
    code = {"code": step_code("coverage_case.py")}
    if layout.COVERAGE_CASES[wildcards.case][0] == "reference":
        code["reference"] = "tests/rocking_vectorised.py"
    return code


def coverage_fresh_inputs(wildcards):
    """A cell's fresh records: the cell, the modules the script runs, the reference simulator for its cells."""
    inputs = {"cell": f"results/studies/coverage/cells/{wildcards.case}.nc", "code": step_code("coverage_fresh.py")}
    if layout.COVERAGE_CASES[wildcards.case][0] == "reference":
        inputs["reference"] = "tests/rocking_vectorised.py"
    return inputs


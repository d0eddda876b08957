"""The ``rockdec`` command: ``estimate``, ``simulate``, ``signatures``, ``estimates``, ``verify``, ``workflow``.

Errors a user can cause (bad options, unknown scene, unwritable output, a request larger
than the memory) end with one sentence on stderr naming the problem and the fix, and exit
code 2; no file is left behind. An unexpected internal error says so in one line (exit
code 1); ``rockdec --debug ...`` shows its traceback. ``verify`` exits 1 when a file of the
archive changed or is missing.

The numerical modules (numpy, xarray, numba kernels, scipy, Dask) are imported by the
command that runs them, so ``--version``, ``--help`` and a refused option answer at once.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import sys
import traceback
from pathlib import Path

from rockdec import console
from rockdec.cache import VARIABLE
from rockdec.report.glossary import GLOSSARY
from rockdec._version import __version__
from rockdec import engine
from rockdec.rdd import fits
from rockdec import validate as checks

__all__ = ["FLAGS", "MAX_SECONDS", "build_parser", "main"]

log = logging.getLogger(__name__)

#: Scene fields set by ``simulate`` options: option -> path of the field in the scene.
SIMULATE_OPTIONS = {
    "--model": ("model",),
    "--e": ("system", "e"),
    "--nu": ("system", "nu"),
    "--theta-cr": ("system", "theta_cr"),
    "--sigma-p": ("excitation", "sigma_p"),
    "--points-per-cycle": ("excitation", "points_per_cycle"),
    "--dt": ("excitation", "dt"),
    "--burn-in": ("excitation", "burn_in"),
    "--n-points": ("records", "n_points"),
    "--chunk-seeds": ("records", "chunk_seeds"),
}


#: Scene fields set by ``signatures`` options: option -> (section, key).
SIGNATURE_OPTIONS = {
    "--level": ("signatures", "level"),
    "--windows": ("signatures", "windows"),
    "--n-periods": ("signatures", "n_periods"),
    "--both-signs": ("signatures", "both_signs"),
    "--v-level": ("signatures", "v_level"),
}

#: Threads a ``simulate`` run computes on at once (Dask's default scheduler, one per core).
SIMULATE_THREADS = 2

#: Seconds one simulation step and one series (its seed, impulses and chunk) take on one
#: core, and bytes a stored sample takes at most (float32 angle and velocity, before compression).
SIMULATE_STEP_SECONDS, SIMULATE_SERIES_SECONDS, SIMULATE_SAMPLE_BYTES = 7e-8, 2e-5, 8.0

#: A run estimated to take longer than this (s) is refused unless ``--yes`` is given.
MAX_SECONDS = 600.0

#: Formats ``--plot`` draws (by the file's suffix).
PLOT_FORMATS = (".png", ".pdf")

#: The command-line flag of each Python parameter that the library's messages name (in
#: backquotes, :func:`in_flags`).
FLAGS = {
    "dt": "--dt", "fs": "--fs", "g": "--g", "load": "--load", "sensor_noise": "--sensor-noise", "sensor_filter": "--sensor-filter", "model": "--model",
    "theta_cr": "--theta-cr", "cache": "--cache", "column": "--column", "variable": "--variable", "out": "--out",
    "overwrite": "--overwrite", "burn_in": "--burn-in", "theta0": "--theta0", "points_per_cycle": "--points-per-cycle",
    "e": "--e", "nu": "--nu", "sigma_p": "--sigma-p", "n_points": "--n-points", "theta": "the record",
    "group_size": "--group-size", "n_periods": "--n-periods", "fit_points": "--fit-points", "weights": "--weights",
    "repair": "--no-repair", "block": "--block", "base": "--base", "base_units": "--base-units", "g_block": "--g",
    "start": "--tail-start", "share_lengths": "--share-lengths",
}


def in_flags(message: str) -> str:
    """A library message with each parameter it names in backquotes (```dt```) replaced by its
    flag (:data:`FLAGS`; a name without a flag loses its quotes)."""
    import re

    return re.sub(r"`([A-Za-z_][A-Za-z0-9_]*)`", lambda m: FLAGS.get(m.group(1), m.group(1)), message)


class UsageError(checks.InputError):
    """Bad command-line input; the message names the option."""


class _Parser(argparse.ArgumentParser):
    """argparse with its errors on one line (no usage block), exit code 2."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message}; see '{self.prog} --help'.\n")


def seed_ranges(text: str) -> list[tuple[int, int]]:
    """Half-open ranges ``(first, stop)`` of the seeds ``"0-99"``, ``"3,7"`` or ``"0-4,10"`` name (inclusive)."""
    ranges: list[tuple[int, int]] = []
    try:
        for part in text.split(","):
            lo, _, hi = part.strip().partition("-")
            first, last = int(lo), int(hi) if hi else int(lo)
            if first < 0 or last < first or last >= 2**63:
                raise ValueError
            ranges.append((first, last + 1))
    except ValueError:
        raise UsageError(f"--seeds '{text}' is not a list of non-negative seeds; write it like 0-99 or 3,7.") from None
    return ranges


def parse_seeds(text: str) -> np.ndarray:
    """Seeds from ``"0-99"``, ``"3,7"`` or a mix like ``"0-4,10"``; inclusive ranges."""
    import numpy as np

    ranges = seed_ranges(text)
    # the seeds (int64) and the sorted copy that finds repeats
    checks.memory(16.0 * sum(stop - start for start, stop in ranges), f"--seeds '{text}'", "give fewer seeds per run")
    seeds = np.concatenate([np.arange(start, stop, dtype=np.int64) for start, stop in ranges])
    if np.unique(seeds).size != seeds.size:
        raise UsageError(f"--seeds '{text}' names a seed twice; give each seed once.")
    return seeds


def _simulate_scene(args) -> dict:
    """The scene a ``simulate`` call describes: ``--scene`` (or the defaults), then options."""
    from rockdec.pipeline import config as config_mod
    from rockdec.physics.models import restoring_acceleration

    if args.scene:
        scene = json.loads(json.dumps(config_mod.scene(config_mod.load(args.config or _default_config()), args.scene)))
    else:
        scene = config_mod.validate_scene({})
    scene = _validated(_with_options(scene, args, SIMULATE_OPTIONS), SIMULATE_OPTIONS)
    system = scene["system"]
    checks.positive(
        restoring_acceleration(system["nu"], system["theta_cr"]),
        f"--nu {checks.show(system['nu'])} with --theta-cr {checks.show(system['theta_cr'])} give g = nu^2 theta_cr =",
        "choose them so that g is a finite number > 0 (rad/s^2)",
    )
    return scene


def _with_options(scene: dict, args, options: dict) -> dict:
    """``scene`` (changed in place) with every option given on the command line set;
    ``options`` maps an option to the path of its field in the scene."""
    for option, (*sections, key) in options.items():
        value = getattr(args, option[2:].replace("-", "_"))
        if value is not None:
            _field(scene, sections)[key] = value
    return scene


def _validated(scene: dict, options: dict) -> dict:
    """``config.validate_scene``, with an error in a field set by an option named by that option."""
    from rockdec.pipeline import config as config_mod

    try:
        return config_mod.validate_scene(scene)
    except config_mod.ConfigError as exc:
        for option, (*sections, key) in options.items():
            field = ".".join(("scenes.cli", *sections, key))
            if exc.field is not None and (exc.field == field or exc.field.startswith(field + ".")):
                value = _field(scene, sections)[key]
                shown = " ".join(map(checks.show, value)) if isinstance(value, list) else checks.show(value)
                raise UsageError(f"{option} {shown}: {exc.problem.replace(' (or null)', '')}.") from None
        raise


def _check_simulation_size(scene: dict, n_seeds: int, out: Path, yes: bool, burn_in: int | None = None, seeds_text: str | None = None) -> None:
    """Refuse, before any work, a run whose series or burn-in would not fit in memory, whose
    file would not fit on the disk, or that would take longer than :data:`MAX_SECONDS`
    without ``--yes``.

    Each of :data:`SIMULATE_THREADS` threads holds one chunk of series (float64 angle and
    velocity, stacked: 4 arrays of ``n_points``) and the impulses of one series
    (``burn_in + n_points`` float64). ``burn_in``: the run's, once known (else the scene's, or 0).
    """
    import shutil

    rec = scene["records"]
    burn_in = burn_in if burn_in is not None else scene["excitation"]["burn_in"] or 0
    rows = min(rec["chunk_seeds"], n_seeds)
    need = SIMULATE_THREADS * 8.0 * (burn_in + rec["n_points"] + 4.0 * rows * rec["n_points"])
    what = f"--n-points {rec['n_points']} with --burn-in {burn_in} and --chunk-seeds {rec['chunk_seeds']}"
    checks.memory(need, what, "lower --n-points, --burn-in or --chunk-seeds")
    samples = float(n_seeds) * rec["n_points"]
    series = f"--seeds '{seeds_text}' ({n_seeds} series)" if seeds_text is not None else f"{n_seeds} series"
    disk = samples * SIMULATE_SAMPLE_BYTES
    free = shutil.disk_usage(out.parent if str(out.parent) else ".").free
    if disk > free:
        raise UsageError(
            f"{series} x --n-points {rec['n_points']} need up to {disk / 2**30:.3g} GiB on disk, more than the "
            f"{free / 2**30:.3g} GiB free beside '{out}'; give fewer seeds or points."
        )
    steps = float(n_seeds) * (burn_in + rec["n_points"])
    seconds = (steps * SIMULATE_STEP_SECONDS + n_seeds * SIMULATE_SERIES_SECONDS) / SIMULATE_THREADS
    if seconds > MAX_SECONDS and not yes:
        raise UsageError(
            f"{series} of {burn_in} burn-in and {rec['n_points']} recorded steps need about {steps:.2g} simulation "
            f"steps, ~{console.duration(seconds)} on {SIMULATE_THREADS} cores; pass --yes to go on, or give fewer seeds."
        )


def _field(scene: dict, sections) -> dict:
    """The part of ``scene`` that the path ``sections`` leads to (the scene itself for ``()``),
    made when missing."""
    for section in sections:
        scene = scene.setdefault(section, {})
    return scene


def cmd_simulate(args) -> None:
    scene = _simulate_scene(args)  # settings first: a bad value is refused before the numerical modules load
    checks.finite(args.theta0, "--theta0", "give the initial angle in rad")
    checks.finite(args.theta_dot0, "--theta-dot0", "give the initial angular velocity in rad/s")

    import numpy as np

    from rockdec import io
    from rockdec.pipeline import layout
    from rockdec.physics import run

    out = io.check_output(args.out, args.overwrite)
    n_seeds = sum(stop - start for start, stop in seed_ranges(args.seeds)) if args.seeds is not None else None
    _check_simulation_size(scene, n_seeds or layout.scene_seeds(scene["records"]).size, out, args.yes, seeds_text=args.seeds)
    seeds = parse_seeds(args.seeds) if args.seeds is not None else layout.scene_seeds(scene["records"]).ravel()
    contract = run.from_scene(scene, amplitude=abs(args.theta0), theta0=args.theta0, theta_dot0=args.theta_dot0)
    if contract.model == "housner" and abs(args.theta0) >= contract.theta_cr:
        raise UsageError(
            f"--theta0 {checks.show(args.theta0)} is beyond the critical angle {checks.show(contract.theta_cr)} rad, where the "
            "block of the Housner model (eq. 2) overturns at once (every sample NaN); start inside it, or use --model simplified."
        )
    n_points = scene["records"]["n_points"]
    if not (contract.dt >= np.finfo(np.float64).tiny and np.spacing((n_points - 1) * contract.dt) <= 0.5 * contract.dt):
        raise UsageError(
            f"a time step of {contract.dt:g} s is too small to tell {n_points} time stamps apart in floating point; "
            "give a larger --dt (the time in larger units)."
        )
    _check_simulation_size(scene, seeds.size, out, args.yes, burn_in=contract.burn_in, seeds_text=args.seeds)
    ds = contract.dataset(seeds, scene["records"]["n_points"], chunk_seeds=scene["records"]["chunk_seeds"])
    ds.attrs.update(io.provenance("simulate", scene))
    log.info(
        f"simulating {seeds.size} series x {scene['records']['n_points']} points "
        f"(dt = {contract.dt:.6g} s, burn-in {contract.burn_in} steps) -> {out}"
    )
    with console.progress("simulating"):
        io.write_netcdf(ds, out, float32=("theta", "theta_dot"), overwrite=args.overwrite)
    with io.open_dataset(out, chunks={}) as written:  # read back by its stored chunks
        for line in run.simulation_report(written["theta"], contract, step_given=scene["excitation"]["dt"] is not None):
            log.warning(f"warning: {line}")


def cmd_signatures(args) -> None:
    from rockdec import io
    from rockdec.pipeline import signature_files

    _not_an_input(args.out, "--out", [args.input])
    out = io.check_output(args.out, args.overwrite)
    scene = _validated(_with_options({}, args, SIGNATURE_OPTIONS), SIGNATURE_OPTIONS)
    counts = signature_files.signature_file(args.input, out, scene["signatures"], variable=args.variable, g=args.g,
                                            group_size=args.group_size, overwrite=args.overwrite)
    log.info(f"triggers per window: D_a {counts['a']}, D_v {counts['v']}")


def cmd_estimates(args) -> None:
    from rockdec import io
    from rockdec.pipeline import signature_files

    _not_an_input(args.out, "--out", [args.input])
    out = io.check_output(args.out, args.overwrite)
    est = signature_files.estimate_file(args.input, out, fit_points=args.fit_points, weights=args.weights, overwrite=args.overwrite)
    for name in est["estimator"].values:
        value = est["e_hat0"].sel(estimator=name).values
        err = est["e_hat0_stderr"].sel(estimator=name).values
        print(f"{name:>4}: " + ", ".join(f"{v:.4f} +- {s:.4f}" for v, s in zip(value, err)))


def _not_an_input(path: str, flag: str, inputs, what: str = "the input", output: str = "output") -> Path:
    """Refuse an output ``path`` (of option ``flag``, naming the ``output``) that is one of the
    files ``inputs``: the same name, or the same file by another spelling, through a symlink
    (at ``path`` or in its folders) or a hard link. Returns ``path`` made absolute (a symlink
    at ``path`` itself, not what it points at: the output replaces it, never writes through it)."""
    target = Path(os.path.abspath(checks.path_name(path, flag)))
    for source in inputs:
        if target == Path(os.path.abspath(source)) or (target.exists() and _same_file(target, source)):
            raise UsageError(f"{flag} '{path}' is {what} {source}; give the {output} a file name of its own.")
    return target


def _same_file(path: Path, other) -> bool:
    """Whether ``path`` and ``other`` are one file; ``False`` when ``other`` cannot be looked at
    (missing, a name too long): its reader says so."""
    try:
        return path.samefile(other)
    except OSError:
        return False


def _plot_path(args) -> str:
    """``--plot``, checked before any work: a format rockdec draws, and not one of the records."""
    plot = args.plot
    target = _not_an_input(plot, "--plot", args.records, "the record", "plot")
    suffix = target.suffix.lower()
    if suffix not in PLOT_FORMATS:
        raise UsageError(
            f"--plot '{plot}': {'no format suffix' if not suffix else f'{suffix} is not a format rockdec draws'}; "
            f"name the file {' or '.join(PLOT_FORMATS)}."
        )
    return plot


def _check_estimate_size(args) -> float:
    """Refuse, before reading the records, a run beyond the memory, or longer than
    :data:`MAX_SECONDS` without ``--yes`` (:func:`rockdec.estimation.cost`, from the files'
    headers or sizes); returns the estimated seconds."""
    from rockdec import estimation
    from rockdec.calibrate import calibration
    from rockdec.record import records

    samples = sum(records.record_size(path, args.variable) for path in args.records)
    csv = any(Path(path).suffix.lower() in (".csv", ".txt") for path in args.records)
    seconds, nbytes = estimation.cost(samples, csv, args.g is not None, records=len(args.records), length_grid=args.share_lengths)
    what = f"records of about {samples:.3g} samples"
    checks.memory(nbytes, what, "give shorter records")
    if seconds > MAX_SECONDS and not args.yes:
        raise UsageError(
            f"{what} need about {console.duration(seconds)} on 2 cores to read, analyse and calibrate (the calibration simulates "
            f"{estimation.calibration_sets(samples)} records of {sum(calibration.simulated_lengths([samples], args.share_lengths)):.3g} "
            "samples); pass --yes to go on, or give a shorter record."
        )
    return seconds


def cmd_estimate(args) -> None:
    import contextlib

    import rockdec
    from rockdec import api, io
    from rockdec.record import records

    for path in args.records:
        checks.path_name(path, "record")
    free, shake = args.test == "free", args.test == "shake"
    if free or shake:
        unused = [flag for flag, given in (("--g", args.g is not None and free), ("--load", args.load != "auto"),
                                           ("--sensor-noise", args.sensor_noise != "auto"),
                                           ("--sensor-filter", args.sensor_filter != "auto")) if given]
        if unused:
            from rockdec.free import no_record_model

            raise UsageError(f"{', '.join(unused)}: {no_record_model(args.test)}; leave them out.")
    shake_flags = [flag for flag, given in (("--base", bool(args.base)), ("--base-units", args.base_units is not None),
                                            ("--tail-start", args.tail_start is not None)) if given]
    if shake_flags and not shake:
        raise UsageError(f"{', '.join(shake_flags)}: only the shake-table test reads them; add --test shake, or leave them out.")
    if shake and len(args.base or []) != len(args.records):
        raise UsageError(f"--test shake reads one --base file per record file: {len(args.records)} record file(s), "
                         f"{len(args.base or [])} --base file(s); give the base acceleration of each record.")
    for path in args.base or []:
        checks.path_name(path, "base record")
    _, theta_cr = api.block_angle(args.block, args.model, args.theta_cr)  # refused before any record is read
    if not (free or shake):  # the random test's record model and cache; the others read neither
        api.estimate_options(g=args.g, load=args.load, sensor_noise=args.sensor_noise, sensor_filter=args.sensor_filter, model=args.model,
                             theta_cr=theta_cr, cache=args.cache)
    with contextlib.ExitStack() as stack:
        plot = stack.enter_context(io.claimed(_plot_path(args), args.overwrite)) if args.plot else None
        seconds = 0.0 if free or shake else _check_estimate_size(args)
        theta = [record for path in args.records
                 for record in records.read_records(path, column=args.column, variable=args.variable, dt=args.dt, fs=args.fs, checked=False)]
        if free:
            res = rockdec.free_rocking(theta, model=args.model, theta_cr=args.theta_cr, block=args.block)
        elif shake:
            res = _shake_table(args, theta)
        else:
            log.info(f"estimate: {len(args.records)} file(s) (up to {console.about(seconds)} when their calibration must be built)")
            with console.progress("calibrating"):  # a bar only while a calibration missing from the cache is built
                res = rockdec.estimate(theta, g=args.g, load=args.load, sensor_noise=args.sensor_noise, sensor_filter=args.sensor_filter,
                                       model=args.model, theta_cr=args.theta_cr, cache=args.cache, repair=args.repair, block=args.block,
                                       share_lengths=args.share_lengths)
        if plot is not None:
            from rockdec.report import figures

            fig = res.plot()
            written = io.write_claimed(plot, lambda tmp: figures.save(fig, tmp), args.overwrite, keep_suffix=True)
            log.warning(f"plot written to {written}")
    if args.json:
        print(json.dumps(res.to_dict(), indent=2))
    else:
        print(res.summary(verbose=args.verbose > 0))
        print("(more: rockdec -v estimate ...; what each word means: rockdec estimate --help)")


def _shake_table(args, theta: list):
    """``rockdec estimate --test shake``: the records ``theta`` with the ``--base`` files."""
    import rockdec
    from rockdec.free import shake
    from rockdec.record import records

    bases, stated = [], set()
    for path in args.base:
        read, units = records.read_base(path, column=args.base_column, variable=args.base_variable, dt=args.dt, fs=args.fs)
        bases += read
        if units is not None:
            stated.add(shake.base_units_named(units))
    if len(bases) != len(theta):
        raise UsageError(f"the --base files hold {len(bases)} record(s) for {len(theta)} record(s) of the angle; give one base per record.")
    if args.base_units is None and len(stated) != 1:
        raise UsageError("--base-units is not given and the base files state " + (f"several ({', '.join(sorted(stated))})" if stated else
                         "none") + "; give --base-units m/s2, g or rad/s2.")
    units = args.base_units or stated.pop()
    if stated - {units}:
        raise UsageError(f"--base-units {units} disagrees with the base files' units attribute ({', '.join(sorted(stated))}); give one.")
    return rockdec.shake_table(theta, bases if len(bases) > 1 else bases[0], base_units=units,
                               block=args.block, theta_cr=args.theta_cr, g_block=args.g, model=args.model, start=args.tail_start)


def cmd_verify(args) -> None:
    from rockdec.pipeline import archive

    out = archive.check_rebuild_target(args.folder, args.rebuild) if args.rebuild else None
    problems = archive.verify(args.folder)
    for line in problems:
        print(line)
    if problems:
        raise SystemExit(1)
    manifest = archive.read_manifest(args.folder)
    print(
        f"OK: {len(manifest['files'])} products and {len(manifest['workflow'])} workflow files in {args.folder} match its "
        f"{archive.MANIFEST}, and {archive.CRATE} agrees with it and meets the Workflow Run Crate's required points"
    )
    if out is not None:
        same = archive.rebuild(args.folder, out)
        for name, equal in same.items():
            print(f"rebuilt {out / name}: {'same as' if equal else 'DIFFERS from'} the archived {name}")
        print(f"checked: the {len(same)} files above, recomputed from the archived signatures (tables byte for byte, NetCDF "
              "values bit for bit); not rerun: the simulation, whose series are bit-identical across machines under a white "
              "or low-pass load and reproduced in distribution only under a spectrum load (the reproducibility page of the docs)")
        if not all(same.values()):
            raise SystemExit(1)


def _default_config() -> str:
    """The config ``--scene`` reads by default: ``config/config.yaml`` in this folder if there
    is one, else the workflow's own (:func:`workflow_root`)."""
    from rockdec.pipeline.config import DEFAULT_PATH

    root = workflow_root()
    return DEFAULT_PATH if Path(DEFAULT_PATH).is_file() or root is None else str(root / DEFAULT_PATH)


#: What the workflow needs besides the package: the extra that installs it.
WORKFLOW_EXTRA = "rockdec[workflow]"


def workflow_root() -> Path | None:
    """The folder holding the workflow's Snakefile: the copy the wheel carries
    (``rockdec/_workflow``), else the source checkout this package runs from; ``None`` if neither."""
    package = Path(__file__).resolve().parent
    for root in (package / "_workflow", package.parents[1]):
        if (root / "Snakefile").is_file() and (root / "config" / "config.yaml").is_file():
            return root
    return None


def cmd_workflow(args) -> None:
    import importlib.util
    import subprocess

    root = workflow_root()
    if root is None:
        raise UsageError("this installation of rockdec carries no workflow (no Snakefile); reinstall it from a wheel or a checkout.")
    if importlib.util.find_spec("snakemake") is None:
        raise UsageError(f"the workflow needs Snakemake, which is not installed; install it with pip install '{WORKFLOW_EXTRA}'.")
    if Path("results").exists() and not Path("results").is_dir():
        raise UsageError("./results is a file, and the workflow writes its products into the folder results/ here; move the file, or run from another folder.")
    extra = [a for a in args.snakemake_args if a != "--"]
    command = [sys.executable, "-m", "snakemake", "--snakefile", str(root / "Snakefile")]
    if not any(a == "--configfile" or a.startswith("--configfile=") for a in extra):
        command += ["--configfile", str(root / "config" / "config.yaml")]
    if args.scene:
        command += ["--config", f"default_scene={args.scene}"]
    command += extra
    log.info(f"running the workflow of {root} in {Path.cwd()}: results/ goes here")
    log.debug(" ".join(command))
    code = subprocess.run(command).returncode
    if code:
        raise SystemExit(code)


#: The first lines of ``rockdec --help``.
DESCRIPTION = (
    "rockdec: the coefficient of restitution e of a rocking rigid block, estimated from its random "
    "response by the Random Decrement technique."
)

#: Examples at the end of ``rockdec --help``.
EXAMPLES = """examples:
  rockdec estimate my_record.csv           e of your record, with a 95 % interval
  rockdec simulate --scene tiny --out sim.nc
  rockdec signatures sim.nc --out sig.nc && rockdec estimates sig.nc --out est.nc
  rockdec workflow --scene tiny            the paper's workflow (tiny scene) into ./results/
  rockdec verify results/paper/archive

'rockdec COMMAND --help' describes each command."""


def build_parser() -> argparse.ArgumentParser:
    """The parser of every command. Building it imports nothing numerical (help strings
    escape a literal percent sign as ``%%``: argparse formats them)."""
    raw = argparse.RawDescriptionHelpFormatter
    parser = _Parser(prog="rockdec", description=DESCRIPTION, epilog=EXAMPLES, formatter_class=raw)
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    loud = parser.add_mutually_exclusive_group()
    loud.add_argument("-q", "--quiet", action="count", default=0, help="print only warnings and errors (no progress)")
    loud.add_argument("-v", "--verbose", action="count", default=0, help="print details too")
    parser.add_argument("--debug", action="store_true", help="show the traceback of an unexpected error")
    parser.add_argument(
        "--dask-scheduler", metavar="ENGINE",
        help="where Dask computes: threads (default), processes:N (N local worker processes) or tcp://host:port "
        f"(a running scheduler); default ${engine.VARIABLE}",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    def command(name: str, summary: str, example: str, epilog: str = "", **kwargs):
        """A subcommand: ``summary`` in the list of commands and atop its help, ``example`` below it."""
        text = f"example:\n  {example}" + (f"\n\n{epilog}" if epilog else "")
        return sub.add_parser(
            name, help=summary, description=summary.replace("%%", "%"), epilog=text, formatter_class=raw, **kwargs
        )

    est1 = command(
        "estimate", "e of a measured record, bias-corrected, with a 95 %% interval (calibrated by simulation)",
        "rockdec estimate my_record.csv --plot e.png", GLOSSARY,
    )
    est1.add_argument("records", nargs="+", help="record file(s) of one block, pooled: .csv (time,theta), .nc or .npy; angles in rad")
    rate = est1.add_mutually_exclusive_group()
    rate.add_argument("--dt", type=float, help="sampling step in s (for files without a time axis)")
    rate.add_argument("--fs", type=float, help="sampling rate in Hz (for files without a time axis)")
    est1.add_argument("--column", default="theta", help="CSV column of the angle (default: %(default)s)")
    est1.add_argument("--variable", default="theta", help="NetCDF variable of the angle (default: %(default)s)")
    est1.add_argument("--g", type=float, help="restoring acceleration nu^2 theta_cr in rad/s^2, if known (default: read off the record)")
    est1.add_argument(
        "--load", default="auto", metavar="LOAD",
        help="the load the calibration simulates: auto (measured off the record: white, or a low-pass load when its colour "
        "is detected), white, lowpass:CORNER (corner in rocking frequencies 1/T(sigma_Y), eq. 5), spectrum:FILE (CSV "
        "frequency_rocking,psd or frequency_hz,psd) or base:FILE (a base-acceleration record, CSV time,acceleration or "
        "NetCDF; its spectrum) (default: %(default)s)",
    )
    est1.add_argument(
        "--sensor-noise", default="auto", metavar="NOISE",
        help="the sensor noise the calibration adds: auto (measured off the record, when detected), 0, a standard deviation "
        "in rad, or N%% of sigma_Y (default: %(default)s)",
    )
    est1.add_argument(
        "--sensor-filter", default="auto", metavar="FILTER",
        help="a low-pass filter between the block and the record (a logger's anti-alias filter, a sensor's bandwidth, a "
        "smoothing), which the calibration applies to its simulated records: auto (the record is checked for one, and e "
        "declined when it shows one), none, butterworth:ORDER:CORNER:PHASE or rc:CORNER:PHASE (CORNER in rocking "
        "frequencies 1/T(sigma_Y), eq. 5, or Hz as 12hz; PHASE zero-phase or causal); declare --load and --sensor-noise "
        "with it (default: %(default)s)",
    )
    est1.add_argument(
        "--model", default="simplified", choices=("simplified", "housner"),
        help="rocking model of the calibration: simplified (eq. 4) or housner (eq. 2, needs --theta-cr) (default: %(default)s)",
    )
    est1.add_argument("--theta-cr", type=float, help="critical angle in rad, for --model housner (nu^2 = g/theta_cr; default with "
                      "--block: atan(B/H))")
    est1.add_argument("--block", metavar="H,B", help="the block's height and width, one unit: the report sets Housner's e = 1 - 1.5 "
                      "sin^2(atan(B/H)) beside the measured e")
    est1.add_argument(
        "--test", choices=("random", "free", "shake"), default="random",
        help="random: the block's random response (Random Decrement, calibrated); free: a free-rocking test, the block "
        "released from a tilt (impacts and fitted flights); shake: a shake-table test, the free-decay tails after the "
        "shaking (needs --base) (default: %(default)s)",
    )
    est1.add_argument("--base", nargs="+", metavar="FILE", help="--test shake: the base acceleration, one file per record file, "
                      "in the record's formats and sampling (.csv column --base-column, .nc variable --base-variable)")
    est1.add_argument("--base-column", default="base", help="CSV column of the base acceleration (default: %(default)s)")
    est1.add_argument("--base-variable", default="base", help="NetCDF variable of the base acceleration (default: %(default)s)")
    est1.add_argument("--base-units", choices=("m/s2", "g", "rad/s2"), help="units of the base acceleration (default: the NetCDF "
                      "units attribute); m/s2 and g need --block or --theta-cr, rad/s2 (the simplified rocking equation's load) --g")
    est1.add_argument("--tail-start", type=float, metavar="SECONDS", help="--test shake: the free-decay tail starts here (s from "
                      "each record's start), cut by hand instead of found")
    est1.add_argument(
        "--no-repair", dest="repair", action="store_false",
        help="estimate the record as given: no spikes replaced, no high-pass of a drifting zero (by default both are "
        "repaired when found, the calibration's records repaired alike, and the report names the repair)",
    )
    est1.add_argument("--share-lengths", action="store_true", help="calibrate on the length grid (two lengths a decade): records "
                      "of nearby lengths share one calibration, its spread scaled to the record's length")
    est1.add_argument("--json", action="store_true", help="print one JSON object instead of the table")
    est1.add_argument("--plot", help="draw the signature and the calibration curve to this PNG or PDF")
    est1.add_argument("--cache", help=f"folder of stored calibrations (default: ${VARIABLE}, else ~/.cache/rockdec/calibration on Linux)")
    est1.add_argument("--overwrite", action="store_true", help="replace --plot if it exists")
    est1.add_argument("--yes", action="store_true", help="go on with records that need more than 10 min")
    est1.set_defaults(func=cmd_estimate)

    sim = command(
        "simulate", "simulate rocking series (exact, eqs. 21-24) to NetCDF",
        "rockdec simulate --e 0.85 --seeds 0-9 --n-points 20000 --out sim.nc",
    )
    sim.add_argument("--out", required=True, help="NetCDF file to write")
    sim.add_argument("--scene", help="take every setting from this scene of the config")
    sim.add_argument("--config", help="config file of --scene (default: config/config.yaml here, else the workflow's own)")
    sim.add_argument("--seeds", help="seeds, e.g. 0-99 or 3,7 (default: the scene's)")
    sim.add_argument("--model", help="simplified (eq. 4), housner (eq. 2) or auto (by amplitude; default: the scene's)")
    sim.add_argument("--e", type=float, help="coefficient of restitution, 0..1")
    sim.add_argument("--nu", type=float, help="rocking frequency parameter, rad/s")
    sim.add_argument("--theta-cr", type=float, help="critical angle, rad")
    sim.add_argument("--sigma-p", type=float, help="std of the velocity impulses, rad/s (0: free response)")
    step = sim.add_mutually_exclusive_group()
    step.add_argument("--points-per-cycle", type=float, help="samples per cycle at amplitude sigma_Y (sets dt)")
    step.add_argument("--dt", type=float, help="time step, s")
    sim.add_argument("--n-points", type=int, help="samples per series")
    sim.add_argument("--burn-in", type=int, help="steps discarded before recording (0 for a free response)")
    sim.add_argument("--theta0", type=float, default=0.0, help="initial angle, rad (default 0)")
    sim.add_argument("--theta-dot0", type=float, default=0.0, help="initial angular velocity, rad/s (default 0)")
    sim.add_argument("--chunk-seeds", type=int, help="seeds per Dask chunk")
    sim.add_argument("--overwrite", action="store_true", help="replace --out if it exists")
    sim.add_argument("--yes", action="store_true", help="go on with a run that needs more than 10 min")
    sim.set_defaults(func=cmd_simulate)

    sig = command(
        "signatures", "RDD signatures D_a and D_v (eq. 19) of a record or a simulation file",
        "rockdec signatures sim.nc --out sig.nc",
    )
    sig.add_argument("input", help="NetCDF file with theta(seed, time) or theta(time), in rad")
    sig.add_argument("--out", required=True, help="NetCDF file to write")
    sig.add_argument("--variable", default="theta", help="name of the record (default: %(default)s)")
    sig.add_argument("--level", type=float, help="trigger level a in units of sigma_Y (default 2)")
    sig.add_argument("--windows", type=float, nargs="+", help="relative window sizes da/da_max, ascending")
    sig.add_argument("--n-periods", type=float, help="lag range in rocking periods at amplitude a (default 2.5)")
    sig.add_argument("--v-level", type=float, help="D_v trigger velocity in units of sigma_Ydot (default 1)")
    sig.add_argument("--both-signs", action=argparse.BooleanOptionalAction, default=None, help="use mirrored triggers too")
    sig.add_argument("--g", type=float, help="restoring acceleration nu^2 theta_cr, rad/s^2 (if the file does not say)")
    sig.add_argument("--group-size", type=int, help="series pooled per signature (default: all)")
    sig.add_argument("--overwrite", action="store_true", help="replace --out if it exists")
    sig.set_defaults(func=cmd_signatures)

    est = command(
        "estimates", "estimate e (eqs. 25-27, e_v) and extrapolate to zero window",
        "rockdec estimates sig.nc --out est.nc",
    )
    est.add_argument("input", help="signature file from 'rockdec signatures'")
    est.add_argument("--out", required=True, help="NetCDF file to write")
    est.add_argument("--fit-points", type=int, default=fits.DEFAULT_FIT_POINTS, help="points per side of the e_v slope fits (default %(default)s)")
    est.add_argument("--weights", choices=["window", "count"], default="window", help="extrapolation weights")
    est.add_argument("--overwrite", action="store_true", help="replace --out if it exists")
    est.set_defaults(func=cmd_estimates)

    ver = command(
        "verify", "re-check every file of an archive (snakemake archive) and its Workflow Run Crate against its manifest",
        "rockdec verify results/paper/archive --rebuild rebuilt/",
    )
    ver.add_argument("folder", help="archive folder holding manifest.json and ro-crate-metadata.json, e.g. results/paper/archive")
    ver.add_argument("--rebuild", metavar="OUT", help="then remake the tables and figures from the archive alone into the new folder OUT")
    ver.set_defaults(func=cmd_verify)

    flow = command(
        "workflow", "run the paper's Snakemake workflow here, writing results/ in this folder",
        "rockdec workflow --scene tiny --cores 2",
        "Every other option goes to Snakemake (e.g. -n for a dry run, --cores N, a target file).\n"
        f"Needs the workflow extra: pip install '{WORKFLOW_EXTRA}'.",
        allow_abbrev=False,
    )
    flow.add_argument("--scene", help="scene of the config to build (default: paper; tiny takes about a minute)")
    flow.set_defaults(func=cmd_workflow, snakemake_args=[])
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run one command; returns the exit code: 0, 2 (input the user can fix), 1 (internal error)."""
    parser = build_parser()
    try:
        args, unknown = parser.parse_known_args(argv)
        if unknown and args.command != "workflow":  # only the workflow passes options on (to Snakemake)
            parser.error(f"unrecognized arguments: {' '.join(unknown)}")
    except SystemExit as exc:  # --help (0) or a usage error (2), printed already
        return exc.code if isinstance(exc.code, int) else 2
    if args.command is None:  # no command: the whole help, not a one-line pointer to it
        parser.print_help()
        return 2
    args.snakemake_args = unknown
    try:
        with console.configured(args.verbose - args.quiet), engine.session(scheduler=args.dask_scheduler):
            args.func(args)
    except KeyboardInterrupt:
        print(f"rockdec {args.command}: interrupted.", file=sys.stderr)
        return 130
    except BrokenPipeError:  # the reader stopped early (`| head`): what it read is all it wanted
        try:  # no second error as Python flushes stdout at exit
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        except (OSError, ValueError):  # a stdout without a file descriptor (captured)
            pass
        return 141
    except checks.InputError as exc:
        if args.debug:
            raise
        message = in_flags(" ".join(str(exc).split()))
        print(f"rockdec {args.command}: error: {message}{'' if message.endswith('.') else '.'}", file=sys.stderr)
        return 2
    except Exception as exc:  # a bug, not the user's input: one line, the traceback on request
        if args.debug:
            traceback.print_exc()
            return 1
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
        print(
            f"rockdec {args.command}: internal error ({type(exc).__name__}: {first}); this is a bug in rockdec, "
            f"not in your input: rerun as 'rockdec --debug {args.command} ...' for the traceback and report it.",
            file=sys.stderr,
        )
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())

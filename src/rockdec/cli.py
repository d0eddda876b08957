"""The ``rockdec`` command: ``estimate``, ``simulate``, ``signatures``, ``estimates``, ``verify``.

Errors a user can cause (bad options, unknown scene, unwritable output, a request larger
than the memory) end with one sentence on stderr naming the problem and the fix, and exit
code 2; no file is left behind. An unexpected internal error says so in one line (exit
code 1); ``rockdec --debug ...`` shows its traceback. ``verify`` exits 1 when a file of the
archive changed or is missing.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import traceback
import warnings
from pathlib import Path

import numpy as np

from rockdec import config as config_mod
from rockdec import __version__, archive, engine, estimators, io, layout, records, replicates, run, signatures, simulate
from rockdec import validate as checks
from rockdec.models import restoring_acceleration

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

#: Fewest lags on each side of a signature for the fits of the estimators.
MIN_LAGS = 8


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
    ranges = seed_ranges(text)
    # the seeds (int64) and the sorted copy that finds repeats
    checks.memory(16.0 * sum(stop - start for start, stop in ranges), f"--seeds '{text}'", "give fewer seeds per run")
    seeds = np.concatenate([np.arange(start, stop, dtype=np.int64) for start, stop in ranges])
    if np.unique(seeds).size != seeds.size:
        raise UsageError(f"--seeds '{text}' names a seed twice; give each seed once.")
    return seeds


def _simulate_scene(args) -> dict:
    """The scene a ``simulate`` call describes: ``--scene`` (or the defaults), then options."""
    if args.scene:
        scene = json.loads(json.dumps(config_mod.scene(config_mod.load(args.config), args.scene)))
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
            f"steps, ~{_duration(seconds)} on {SIMULATE_THREADS} cores; pass --yes to go on, or give fewer seeds."
        )


def _duration(seconds: float) -> str:
    """``seconds`` as a rounded duration: ``"40 s"``, ``"15 min"``, ``"3.2 h"``, ``"12 days"``."""
    if seconds < 120:
        return f"{seconds:.0f} s"
    if seconds < 7200:
        return f"{seconds / 60:.0f} min"
    if seconds < 2 * 86400:
        return f"{seconds / 3600:.2g} h"
    return f"{seconds / 86400:.2g} days"


def _field(scene: dict, sections) -> dict:
    """The part of ``scene`` that the path ``sections`` leads to (the scene itself for ``()``),
    made when missing."""
    for section in sections:
        scene = scene.setdefault(section, {})
    return scene


def cmd_simulate(args) -> None:
    out = io.check_output(args.out, args.overwrite)
    scene = _simulate_scene(args)
    checks.finite(args.theta0, "--theta0", "give the initial angle in rad")
    checks.finite(args.theta_dot0, "--theta-dot0", "give the initial angular velocity in rad/s")
    n_seeds = sum(stop - start for start, stop in seed_ranges(args.seeds)) if args.seeds is not None else None
    _check_simulation_size(scene, n_seeds or layout.scene_seeds(scene["records"]).size, out, args.yes, seeds_text=args.seeds)
    seeds = parse_seeds(args.seeds) if args.seeds is not None else layout.scene_seeds(scene["records"]).ravel()
    contract = run.calibrate(scene, amplitude=abs(args.theta0), theta0=args.theta0, theta_dot0=args.theta_dot0)
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
    print(
        f"simulating {seeds.size} series x {scene['records']['n_points']} points "
        f"(dt = {contract.dt:.6g} s, burn-in {contract.burn_in} steps) -> {out}",
        file=sys.stderr,
    )
    with _progress():
        io.write_netcdf(ds, out, float32=("theta", "theta_dot"), overwrite=args.overwrite)


def cmd_signatures(args) -> None:
    out = io.check_output(args.out, args.overwrite)
    with io.open_dataset(args.input) as src:
        if args.variable not in src:
            raise UsageError(f"{args.input} has no variable '{args.variable}'; name it with --variable.")
        theta = src[args.variable].load()
        attrs = dict(src.attrs)
    if theta.ndim == 1:
        theta = theta.expand_dims(seed=[0])
    if set(theta.dims) != {"seed", "time"}:
        raise UsageError(f"'{args.variable}' must have dimensions (seed, time) or (time); it has {theta.dims}.")
    theta = theta.transpose("seed", "time").astype(float)
    theta = theta.copy(data=theta.values * records.angle_factor(theta.attrs.get("units"), args.input, args.variable))
    if "dt" in attrs:
        try:
            (step,) = np.asarray(attrs["dt"], dtype=np.float64).ravel()
        except (TypeError, ValueError):
            raise UsageError(f"{args.input}: its attribute dt {attrs['dt']!r} is not a number of seconds; fix it.") from None
        theta.attrs["dt"] = checks.positive(step, f"the attribute dt of {args.input}", "fix it (the sampling step in s)")
    elif "time" in theta.coords:
        theta.attrs["dt"] = records.sampling_step(theta["time"].values, f"{args.input}: '{args.variable}'") * records.time_factor(
            theta["time"].attrs.get("units"), args.input, "time"
        )
    else:
        raise UsageError(f"{args.input}: '{args.variable}' has no time coordinate and the file no 'dt' attribute; add either.")
    if np.isinf(theta.values).any():
        raise UsageError(f"{args.input}: '{args.variable}' holds infinite values; remove them or mark them as gaps (NaN).")
    with np.errstate(invalid="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # an all-NaN series is refused just below
        still = ~(np.nanmax(theta.values, axis=1) > np.nanmin(theta.values, axis=1))
    if still.any():
        k = int(np.flatnonzero(still)[0])
        raise UsageError(f"{args.input}: series {k} of '{args.variable}' is constant (or all NaN), so it has no trigger; a rocking record must move.")
    scales = {name: attrs.get(name) for name in ("sigma_y", "sigma_ydot")}
    missing = [name for name, value in scales.items() if value is None or not np.isfinite(value)]
    if missing:  # the file's stationary statistics, else measured (one pass over the record)
        measured = simulate.pilot_statistics(theta.values, theta.attrs["dt"])
        scales.update({name: measured[name] for name in missing})
    stats = {
        **{name: float(value) for name, value in scales.items()},
        "g": args.g if args.g is not None else attrs.get("g"),
    }
    if stats["g"] is None:
        raise UsageError(f"{args.input} does not say g (rad/s^2): give --g to size the lag range in rocking periods.")
    g_name = "--g" if args.g is not None else f"the attribute g of {args.input}"
    stats["g"] = checks.positive(stats["g"], g_name, "give --g, the restoring acceleration nu^2 theta_cr in rad/s^2")
    scene = _validated(_with_options({}, args, SIGNATURE_OPTIONS), SIGNATURE_OPTIONS)
    if args.group_size is not None:
        checks.integer(args.group_size, "--group-size", 1, "give at least 1 series per signature (or leave it out: all)")
        if args.group_size > theta.sizes["seed"]:
            raise UsageError(
                f"--group-size {args.group_size}: more than the {theta.sizes['seed']} series in {args.input}; "
                f"give at most {theta.sizes['seed']} (or leave it out: all)."
            )
    size = args.group_size or theta.sizes["seed"]
    sig = scene["signatures"]
    n_lag = signatures.lag_samples(sig["n_periods"], sig["level"] * stats["sigma_y"], stats["g"], theta.attrs["dt"])
    if n_lag < MIN_LAGS:
        raise UsageError(
            f"{g_name} {checks.show(stats['g'])} with --n-periods {checks.show(sig['n_periods'])} gives a lag range of {n_lag} "
            f"samples, fewer than the {MIN_LAGS} the fits need; give the right g, or --n-periods near 2.5 (the default)."
        )
    signatures.check_lag_range(
        n_lag, theta.sizes["time"], theta.sizes["seed"], len(sig["windows"]),
        f"{g_name} {checks.show(stats['g'])} with --n-periods {checks.show(sig['n_periods'])}",
        "raise --g or lower --n-periods (or pool fewer series with --group-size)",
    )
    if size == 1:  # one signature per series: the cube keeps the seed dimension
        cube = replicates.scene_signatures(theta, sig, **stats, group=None, replicate_of_group=np.zeros(theta.sizes["seed"], dtype=int))
    else:
        group = np.arange(theta.sizes["seed"]) // size
        cube = replicates.scene_signatures(theta, sig, **stats, group=group, replicate_of_group=np.arange(group.max() + 1))
    cube.attrs.update(io.provenance("signatures", scene["signatures"], inputs=[args.input]))
    io.write_netcdf(cube, out, overwrite=args.overwrite)
    counts = cube["count"].sum(replicates.series_dim(cube))
    print(f"triggers per window: D_a {counts.sel(trigger='a').values}, D_v {counts.sel(trigger='v').values}", file=sys.stderr)


def cmd_estimates(args) -> None:
    out = io.check_output(args.out, args.overwrite)
    checks.integer(args.fit_points, "--fit-points", 3, "give at least 3 points per side (a parabola needs 3)")
    with io.open_dataset(args.input) as src:
        if "free_response" not in src or not {"group", "seed"} & set(src.dims) or "count" not in src or "dt" not in src.attrs:
            raise UsageError(f"{args.input} is not a signature file; make one with 'rockdec signatures'.")
        cube = src.load()
    lags = (cube.sizes[cube["free_response"].dims[-1]] - 1)
    if args.fit_points > lags:
        raise UsageError(f"--fit-points {args.fit_points}: more than the {lags} lags of the signatures in {args.input}; give at most {lags}.")
    if "replicate" not in cube.coords:
        dim = replicates.series_dim(cube)
        cube = cube.assign_coords(replicate=(dim, np.zeros(cube.sizes[dim], dtype=int)))
    est = replicates.replicate_estimates(cube, fit_points=args.fit_points, weights=args.weights)
    est.attrs.update(io.provenance("estimates", {"fit_points": args.fit_points, "weights": args.weights}, inputs=[args.input]))
    io.write_netcdf(est, out, overwrite=args.overwrite)
    for name in est["estimator"].values:
        value = est["e_hat0"].sel(estimator=name).values
        err = est["e_hat0_stderr"].sel(estimator=name).values
        print(f"{name:>4}: " + ", ".join(f"{v:.4f} +- {s:.4f}" for v, s in zip(value, err)))


def _plot_path(args) -> str:
    """``--plot``, checked before any work: a format rockdec draws, and not one of the records."""
    plot = str(checks.path_name(args.plot, "--plot"))
    target = Path(os.path.abspath(plot))  # a symlink itself, not what it points at: it is replaced, never written through
    for record in args.records:
        if target == Path(os.path.abspath(record)) or (target.exists() and not target.is_symlink() and target.samefile(record)):
            raise UsageError(f"--plot '{plot}' is the record {record}; give the plot a file name of its own.")
    suffix = target.suffix.lower()
    if suffix not in PLOT_FORMATS:
        raise UsageError(
            f"--plot '{plot}': {'no format suffix' if not suffix else f'{suffix} is not a format rockdec draws'}; "
            f"name the file {' or '.join(PLOT_FORMATS)}."
        )
    return plot


def _check_estimate_size(args) -> float:
    """Refuse, before reading the records, a run beyond the memory, or longer than
    :data:`MAX_SECONDS` without ``--yes`` (:func:`rockdec.inference.cost`, from the files'
    headers or sizes); returns the estimated seconds."""
    from rockdec import inference

    samples = sum(records.record_size(path, args.variable) for path in args.records)
    csv = any(Path(path).suffix.lower() in (".csv", ".txt") for path in args.records)
    seconds, nbytes = inference.cost(samples, csv, args.g is not None)
    what = f"records of about {samples:.3g} samples"
    checks.memory(nbytes, what, "give shorter records")
    if seconds > MAX_SECONDS and not args.yes:
        raise UsageError(
            f"{what} need about {_duration(seconds)} on 2 cores to read, analyse and calibrate (the calibration simulates "
            f"{len(inference.calibration.E_GRID) * inference.calibration.SETS_PER_E} records as long); pass --yes to go on, "
            "or give a shorter record."
        )
    return seconds


def cmd_estimate(args) -> None:
    import contextlib

    from rockdec import inference

    for path in args.records:
        checks.path_name(path, "record")
    if args.g is not None:
        checks.positive(args.g, "--g", "give the restoring acceleration nu^2 theta_cr in rad/s^2, or leave --g out")
    if Path(args.cache).exists() and not Path(args.cache).is_dir():
        raise UsageError(f"--cache '{args.cache}' is a file, not a folder; give a folder for the stored calibrations.")
    with contextlib.ExitStack() as stack:
        plot = stack.enter_context(io.claimed(_plot_path(args), args.overwrite)) if args.plot else None
        seconds = _check_estimate_size(args)
        recs = [
            rec
            for path in args.records
            for rec in records.read_records(path, column=args.column, variable=args.variable, dt=args.dt, fs=args.fs)
        ]
        if not args.json:
            print(
                f"rockdec estimate: {len(recs)} record(s), {sum(r.theta.size for r in recs)} samples; analysing and calibrating "
                f"(up to about {_duration(seconds)} when the calibration is not stored yet) ...",
                file=sys.stderr,
            )
        with _progress():  # a calibration not in the cache is built first (about 10 s for 200,000 samples)
            result = inference.estimate(recs, cache_dir=args.cache, g=args.g)
        if plot is not None:
            from rockdec import figures

            fig = figures.fig_record(result)
            io.write_claimed(plot, lambda tmp: figures.save(fig, tmp), args.overwrite, keep_suffix=True)
    public = {k: v for k, v in result.items() if not k.startswith("_")}
    if args.json:
        print(json.dumps(public, indent=2))
    else:
        print(_estimate_text(public))


def _estimate_text(res: dict) -> str:
    """The human-readable report of ``rockdec estimate``."""
    fmt = lambda x: "   nan" if x is None else f"{x:.4f}"  # noqa: E731
    g_how = "given (--g)" if res["g_given"] else f"from the first zero crossing of the free response, g = 2 c1/t1^2, raw {res['g_raw']:.4g}, bias-corrected"
    cal = res["calibration"]
    lines = [
        f"records: {', '.join(res['records'])}: {res['samples']} samples at dt = {res['dt']:.6g} s, {res['nan_samples']} NaN skipped",
        f"sigma_Y = {res['sigma_y']:.4g} rad, {res['points_per_cycle']:.1f} samples per cycle at sigma_Y (eq. 5)",
        f"g = {res['g']:.5g} rad/s^2 ({g_how})" if res["g"] is not None else "g: not determined",
        f"calibration: {cal['file']} ({'from the cache' if cal['cached'] else 'built in %.1f s' % cal['seconds']})",
        "",
        f"{'estimator':<10} {'raw':>7} {'corrected':>10}   {'95 % interval':<19} {'coverage':>8} {'triggers':>8}",
    ]
    pct = lambda x: "   -" if x is None else f"{x:.0%}"  # noqa: E731
    for name, est in res["estimators"].items():
        mark = " *" if name == res["estimator"] else "  "
        interval = f"[{fmt(est['interval'][0])}, {fmt(est['interval'][1])}]"
        lines.append(f"{name + mark:<10} {fmt(est['raw']):>7} {fmt(est['e']):>10}   {interval:<19} {pct(est['coverage']):>8} {est['triggers']:>8}")
        lines += [f"{'':>12}note: {note}" for note in est["notes"]]
    lines += [
        "",
        f"e = {fmt(res['e'])}, 95 % interval [{fmt(res['interval'][0])}, {fmt(res['interval'][1])}] ({res['estimator']}, marked *);",
        f"coverage: the interval held the true e on {pct(res['coverage'])} of the calibration's simulated records "
        "(in-sample; the README's coverage study checks it on independent records)",
    ]
    if res.get("reason"):
        lines.append(f"no e: {res['reason']}")
    lines += [f"warning: {w}" for w in res["warnings"]]
    return "\n".join(lines)


def cmd_verify(args) -> None:
    out = Path(args.rebuild) if args.rebuild else None
    if out is not None and out.exists():
        raise UsageError(f"--rebuild '{out}' exists already; remove it or choose another folder.")
    if out is not None and not out.parent.is_dir():
        raise UsageError(f"--rebuild '{out}': its folder '{out.parent}' does not exist; create it first.")
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
        if not all(same.values()):
            raise SystemExit(1)


def _progress():
    from dask.diagnostics import ProgressBar

    return ProgressBar(out=sys.stderr, minimum=2.0)


def _default_cache() -> str:
    """Where calibrations are stored: ``$ROCKDEC_CACHE``, else the user's cache folder."""
    import os

    import platformdirs

    return os.environ.get("ROCKDEC_CACHE") or str(Path(platformdirs.user_cache_dir("rockdec")) / "calibration")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="rockdec", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    parser.add_argument("--debug", action="store_true", help="show the traceback of an unexpected error")
    parser.add_argument(
        "--dask-scheduler", metavar="ENGINE",
        help=f"where Dask computes: threads (default), processes:N (N local worker processes) or tcp://host:port "
        f"(a running scheduler); default ${engine.VARIABLE}",
    )
    sub = parser.add_subparsers(dest="command", required=True)

    est1 = sub.add_parser("estimate", help="e of a measured record, bias-corrected, with a 95 % interval (calibrated by simulation)")
    est1.add_argument("records", nargs="+", help="record file(s) of one block, pooled: .csv (time,theta), .nc or .npy; angles in rad")
    rate = est1.add_mutually_exclusive_group()
    rate.add_argument("--dt", type=float, help="sampling step in s (for files without a time axis)")
    rate.add_argument("--fs", type=float, help="sampling rate in Hz (for files without a time axis)")
    est1.add_argument("--column", default="theta", help="CSV column of the angle (default: %(default)s)")
    est1.add_argument("--variable", default="theta", help="NetCDF variable of the angle (default: %(default)s)")
    est1.add_argument("--g", type=float, help="restoring acceleration nu^2 theta_cr in rad/s^2, if known (default: read off the record)")
    est1.add_argument("--json", action="store_true", help="print one JSON object instead of the table")
    est1.add_argument("--plot", help="draw the signature and the calibration curve to this PNG or PDF")
    est1.add_argument("--cache", default=_default_cache(), help="folder of stored calibrations (default: %(default)s)")
    est1.add_argument("--overwrite", action="store_true", help="replace --plot if it exists")
    est1.add_argument("--yes", action="store_true", help="go on with records that need more than 10 min")
    est1.set_defaults(func=cmd_estimate)

    sim = sub.add_parser("simulate", help="simulate rocking series (exact, eqs. 21-24) to NetCDF")
    sim.add_argument("--out", required=True, help="NetCDF file to write")
    sim.add_argument("--scene", help="take every setting from this scene of the config")
    sim.add_argument("--config", default="config/config.yaml", help="config file (default: %(default)s)")
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

    sig = sub.add_parser("signatures", help="RDD signatures D_a and D_v (eq. 19) of a record or a simulation file")
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

    est = sub.add_parser("estimates", help="estimate e (eqs. 25-27, e_v) and extrapolate to zero window")
    est.add_argument("input", help="signature file from 'rockdec signatures'")
    est.add_argument("--out", required=True, help="NetCDF file to write")
    est.add_argument("--fit-points", type=int, default=estimators.DEFAULT_FIT_POINTS, help="points per side of the e_v slope fits")
    est.add_argument("--weights", choices=["window", "count"], default="window", help="extrapolation weights")
    est.add_argument("--overwrite", action="store_true", help="replace --out if it exists")
    est.set_defaults(func=cmd_estimates)

    ver = sub.add_parser(
        "verify", help="re-check every file of an archive (snakemake archive) and its Workflow Run Crate against its manifest"
    )
    ver.add_argument("folder", help="archive folder holding manifest.json and ro-crate-metadata.json, e.g. results/paper/archive")
    ver.add_argument("--rebuild", metavar="OUT", help="then remake the tables and figures from the archive alone into the new folder OUT")
    ver.set_defaults(func=cmd_verify)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run one command; returns the exit code: 0, 2 (input the user can fix), 1 (internal error)."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help (0) or a usage error (2), printed already
        return exc.code if isinstance(exc.code, int) else 2
    try:
        with engine.session(scheduler=args.dask_scheduler):
            args.func(args)
    except checks.InputError as exc:
        if args.debug:
            raise
        message = " ".join(str(exc).split())
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

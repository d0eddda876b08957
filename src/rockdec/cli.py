"""The ``rockdec`` command: ``simulate``, ``signatures``, ``estimates``.

Errors a user can cause (bad options, unknown scene, unwritable output) end with one
sentence on stderr naming the problem and the fix, and exit code 2; no file is left
behind.
"""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np

from rockdec import config as config_mod
from rockdec import __version__, io, replicates, simulate

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


class UsageError(ValueError):
    """Bad command-line input; the message names the option."""


def parse_seeds(text: str) -> np.ndarray:
    """Seeds from ``"0-99"``, ``"3,7"`` or a mix like ``"0-4,10"``; inclusive ranges."""
    seeds: list[int] = []
    try:
        for part in text.split(","):
            lo, _, hi = part.strip().partition("-")
            first, last = int(lo), int(hi) if hi else int(lo)
            if first < 0 or last < first:
                raise ValueError
            seeds.extend(range(first, last + 1))
    except ValueError:
        raise UsageError(f"--seeds '{text}' is not a list of non-negative seeds; write it like 0-99 or 3,7.") from None
    if len(set(seeds)) != len(seeds):
        raise UsageError(f"--seeds '{text}' names a seed twice; give each seed once.")
    return np.asarray(seeds, dtype=np.int64)


def _simulate_scene(args) -> dict:
    """The scene a ``simulate`` call describes: ``--scene`` (or the defaults), then options."""
    if args.scene:
        scene = json.loads(json.dumps(config_mod.scene(config_mod.load(args.config), args.scene)))
    else:
        scene = config_mod.validate_scene({})
    for option, (*sections, key) in SIMULATE_OPTIONS.items():
        value = getattr(args, option[2:].replace("-", "_"))
        if value is not None:
            _field(scene, sections)[key] = value
    try:
        config_mod.validate_scene(scene)
    except config_mod.ConfigError as exc:
        for option, (*sections, key) in SIMULATE_OPTIONS.items():
            if f"'scenes.cli.{'.'.join((*sections, key))}'" in str(exc):
                value = _field(scene, sections)[key]
                raise UsageError(f"{option} {value}: {str(exc).split(': ', 1)[1].split('. Fix')[0]}.") from None
        raise
    return scene


def _field(scene: dict, sections) -> dict:
    """The part of ``scene`` that the path ``sections`` leads to (the scene itself for ``()``)."""
    for section in sections:
        scene = scene[section]
    return scene


def cmd_simulate(args) -> None:
    out = io.check_output(args.out, args.overwrite)
    scene = _simulate_scene(args)
    seeds = parse_seeds(args.seeds) if args.seeds else simulate.scene_seeds(scene).ravel()
    params = simulate.scene_parameters(scene, amplitude=abs(args.theta0))
    ds = simulate.scene_dataset(scene, params, seeds, theta0=args.theta0, theta_dot0=args.theta_dot0)
    print(
        f"simulating {seeds.size} series x {scene['records']['n_points']} points "
        f"(dt = {params['dt']:.6g} s, burn-in {params['burn_in']} steps) -> {out}",
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
    theta.attrs.setdefault("dt", attrs.get("dt", float(theta.time[1] - theta.time[0])))
    stats = {
        "sigma_y": _finite(attrs.get("sigma_y"), lambda: float(np.sqrt(np.nanmean(theta.values**2)))),
        "sigma_ydot": _finite(
            attrs.get("sigma_ydot"), lambda: float(np.sqrt(np.nanmean((np.diff(theta.values) / theta.attrs["dt"]) ** 2)))
        ),
        "g": args.g if args.g is not None else attrs.get("g"),
    }
    if stats["g"] is None:
        raise UsageError(f"{args.input} does not say g (rad/s^2): give --g to size the lag range in rocking periods.")
    scene = config_mod.validate_scene(
        {
            "signatures": {
                k: v
                for k, v in {
                    "level": args.level,
                    "windows": args.windows,
                    "n_periods": args.n_periods,
                    "both_signs": args.both_signs,
                    "v_level": args.v_level,
                }.items()
                if v is not None
            }
        }
    )
    size = args.group_size or theta.sizes["seed"]
    if size == 1:  # one signature per series: the cube keeps the seed dimension
        cube = replicates.scene_signatures(theta, scene, stats, None, np.zeros(theta.sizes["seed"], dtype=int))
    else:
        group = np.arange(theta.sizes["seed"]) // size
        cube = replicates.scene_signatures(theta, scene, stats, group, np.arange(group.max() + 1))
    cube.attrs.update(io.provenance("signatures", scene["signatures"], inputs=[args.input]))
    io.write_netcdf(cube, out, overwrite=args.overwrite)
    counts = cube["count"].sum(replicates.series_dim(cube))
    print(f"triggers per window: D_a {counts.sel(trigger='a').values}, D_v {counts.sel(trigger='v').values}", file=sys.stderr)


def _finite(value, fallback):
    return float(value) if value is not None and np.isfinite(value) else fallback()


def cmd_estimates(args) -> None:
    out = io.check_output(args.out, args.overwrite)
    with io.open_dataset(args.input) as src:
        if "free_response" not in src or not {"group", "seed"} & set(src.dims):
            raise UsageError(f"{args.input} is not a signature file; make one with 'rockdec signatures'.")
        cube = src.load()
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


def _progress():
    from dask.diagnostics import ProgressBar

    return ProgressBar(out=sys.stderr, minimum=2.0)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="rockdec", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)

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
    est.add_argument("--fit-points", type=int, default=5, help="points per side of the e_v slope fits")
    est.add_argument("--weights", choices=["window", "count"], default="window", help="extrapolation weights")
    est.add_argument("--overwrite", action="store_true", help="replace --out if it exists")
    est.set_defaults(func=cmd_estimates)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        args.func(args)
    except (UsageError, config_mod.ConfigError, io.OutputError, ValueError) as exc:
        print(f"rockdec {args.command}: error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())

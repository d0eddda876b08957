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
from rockdec import io, simulate

#: Scene fields set by ``simulate`` options: option -> (section, key).
SIMULATE_OPTIONS = {
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
    for option, (section, key) in SIMULATE_OPTIONS.items():
        value = getattr(args, option[2:].replace("-", "_"))
        if value is not None:
            scene[section][key] = value
    try:
        config_mod.validate_scene(scene)
    except config_mod.ConfigError as exc:
        for option, (section, key) in SIMULATE_OPTIONS.items():
            if f"'scenes.cli.{section}.{key}'" in str(exc):
                raise UsageError(f"{option} {scene[section][key]}: {str(exc).split(': ', 1)[1].split('. Fix')[0]}.") from None
        raise
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


def _progress():
    from dask.diagnostics import ProgressBar

    return ProgressBar(out=sys.stderr, minimum=2.0)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="rockdec", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)

    sim = sub.add_parser("simulate", help="simulate rocking series (exact, eqs. 21-24) to NetCDF")
    sim.add_argument("--out", required=True, help="NetCDF file to write")
    sim.add_argument("--scene", help="take every setting from this scene of the config")
    sim.add_argument("--config", default="config/config.yaml", help="config file (default: %(default)s)")
    sim.add_argument("--seeds", help="seeds, e.g. 0-99 or 3,7 (default: the scene's)")
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

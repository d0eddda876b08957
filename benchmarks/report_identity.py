"""Whether two versions of rockdec give the same JSON report, byte for byte, on one machine.

A plain script (not a test): it prints, per case, whether ``rockdec estimate --json`` of the
two source trees agrees, and never asserts.

    git worktree add /tmp/old <commit>
    python benchmarks/report_identity.py --old /tmp/old/src --new src [--work DIR]

The records (20,000 samples at e = 0.85, and a free-rocking test at e = 0.9) are simulated
once and given to both trees: clean, with 2 % sensor noise, drifting, with spikes, low-pass
filtered, doubled in amplitude halfway (declined after the calibration), pooled with a second
record of the block or with one of e = 0.6, estimated without repair, with a given ``g``,
under a declared model, and the free test clean and noisy. Both trees read one calibration
store with the calibration's code fingerprint fixed (:func:`rockdec.calibrate.calibration.pipeline_fingerprint`),
so that trees whose simulators agree but whose files differ (a docstring) read the same
calibrations. Each tree runs every case twice, and the second run is compared (the first
may build the calibration); the time a calibration took to read (``"seconds"``) is left out.
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

#: The command line with the calibrations' code fingerprint fixed.
FIXED = (
    "import sys; import rockdec.calibrate.calibration as c; c.pipeline_fingerprint = lambda: 'report-identity'; "
    "from rockdec.cli import main; sys.exit(main(sys.argv[1:]))"
)


def make_records(folder: Path) -> dict[str, tuple[list[str], list[str]]]:
    """Write the records; returns ``{case: (files, options)}``."""
    import numpy as np

    import rockdec

    def save(name, y, dt):
        path = folder / f"{name}.csv"
        np.savetxt(path, y, header="theta", comments="", fmt="%.9e")
        return str(path), ["--dt", repr(dt)]

    a = rockdec.simulate(0.85, 20_000, seed=1)
    dt, y = float(a.time[1] - a.time[0]), a.values
    sd, rng, t = y.std(), np.random.default_rng(5), np.arange(y.size)
    spiked = y.copy()
    spiked[[3000, 9000, 15000]] += 40 * sd
    half = y.copy()
    half[y.size // 2:] *= 2.0
    other = rockdec.simulate(0.6, 20_000, seed=3).values
    free = rockdec.simulate(0.9, 3_000, seed=0, sigma_p=0.0, theta0=0.01)
    fdt = float(free.time[1] - free.time[0])
    clean, step = save("clean", y, dt)
    second, _ = save("second", rockdec.simulate(0.85, 20_000, seed=2).values, dt)
    low_e, _ = save("other_e", other * sd / other.std(), dt)
    cases = {name: ([path], step) for name, path in [
        ("clean", clean), ("noisy", save("noisy", y + 0.02 * sd * rng.standard_normal(y.size), dt)[0]),
        ("drift", save("drift", y + 3 * sd * np.sin(2 * np.pi * t / y.size), dt)[0]), ("spikes", save("spikes", spiked, dt)[0]),
        ("filtered", save("filtered", np.convolve(y, np.ones(4) / 4, mode="same"), dt)[0]),
        ("nonstationary", save("nonstationary", half, dt)[0]),
    ]}
    cases.update({
        "pooled": ([clean, second], step), "disagree": ([clean, low_e], step), "no repair": ([clean], [*step, "--no-repair"]),
        "given g": ([clean], [*step, "--g", "1.0"]), "declared": ([clean], [*step, "--load", "white", "--sensor-noise", "0"]),
    })
    for name, noise in (("free", 0.0), ("free noisy", 2e-5)):
        path, fstep = save(name.replace(" ", "_"), free.values + noise * rng.standard_normal(free.size), fdt)
        cases[name] = ([path], [*fstep, "--test", "free"])
    return cases


def report(src: str, files: list[str], options: list[str], cache: Path) -> str:
    """The JSON text tree ``src`` prints, the calibration's read time left out."""
    env = {**os.environ, "PYTHONPATH": str(Path(src).resolve())}
    out = subprocess.run([sys.executable, "-c", FIXED, "estimate", *files, *options, "--json", "--cache", str(cache)],
                         capture_output=True, text=True, env=env)
    text = out.stdout if out.returncode == 0 else f"exit {out.returncode}: {out.stderr.strip().splitlines()[-1:]}"
    return re.sub(r'"seconds": [0-9.]+', '"seconds": -', text)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--old", required=True, help="the src folder of the first tree")
    parser.add_argument("--new", required=True, help="the src folder of the second tree")
    parser.add_argument("--work", help="folder for the records and the calibrations (default: a new temporary one)")
    args = parser.parse_args()
    work = Path(args.work or tempfile.mkdtemp(prefix="report-identity-"))
    (work / "records").mkdir(parents=True, exist_ok=True)
    cases = make_records(work / "records")
    same = 0
    print("| case | same bytes | e |")
    print("| --- | --- | --- |")
    for name, (files, options) in cases.items():
        texts = []
        for src in (args.old, args.new):
            report(src, files, options, work / "cache")  # builds the calibration if missing
            texts.append(report(src, files, options, work / "cache"))
        match = re.search(r'^\s*"e": (.*),$', texts[1], re.M)
        same += texts[0] == texts[1]
        print(f"| {name} | {'yes' if texts[0] == texts[1] else 'NO'} | {match.group(1) if match else texts[1][:60]} |")
    print(f"\n{same} of {len(cases)} cases give the same bytes")


if __name__ == "__main__":
    main()

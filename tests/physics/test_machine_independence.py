"""What is bit-identical across machines (docs/explanation/reproducibility.md): the series of
a white or low-pass load, of every model, its step search and its sensor noise come out bit
for bit the same when NumPy is held to its baseline instruction set and glibc's libm to its
variants without FMA, AVX2 or AVX-512 (the switches by which two x86-64 machines differ).
A spectrum load's impulses go through NumPy's vectorised logarithm and are reproduced in
distribution only; the suite asserts nothing of one chaotic trajectory under it."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

#: The environment of another instruction set (docs/explanation/reproducibility.md).
OTHER_MACHINE = {
    "NPY_DISABLE_CPU_FEATURES": "X86_V3 X86_V4 AVX512_ICL AVX512_SPR",
    "GLIBC_TUNABLES": "glibc.cpu.hwcaps=-AVX2,-FMA,-AVX512F,-AVX",
}

#: Prints the SHA-1 of each output the docs call bit-identical across machines.
PROBE = r"""
import hashlib, json
import numpy as np
from rockdec.physics import simulate
from rockdec.physics.loading import add_sensor_noise, series_rng

def sha(a):
    return hashlib.sha1(np.ascontiguousarray(a, dtype=np.float64).tobytes()).hexdigest()

kw = dict(dt=0.0034, g=1.0, e=0.85, sigma_p=0.003, burn_in=3000)
out = {"normals": sha(series_rng(5).standard_normal(10_000))}
for pole in (0.0, 0.97):
    out[f"simplified {pole}"] = sha(simulate.simulate_block([0, 1], 6000, pole=pole, **kw)[0])
    for model in ("fixed_step", "housner"):
        out[f"{model} {pole}"] = sha(simulate.simulate_model(model, [0, 1], 6000, theta_cr=0.2, pole=pole, **kw))
out["noise"] = sha(add_sensor_noise(np.zeros((2, 5000)), [0, 1], 0.01))
step = simulate.calibrate_dt(e=0.85, g=1.0, sigma_p=0.003, pilot_seeds=4, pilot_points=20_000)
out["step"] = repr(step["dt"])
print(json.dumps(out))
"""


def probe(extra: dict) -> dict:
    env = {**os.environ, **extra}
    done = subprocess.run([sys.executable, "-c", PROBE], env=env, capture_output=True, text=True, check=True)
    return json.loads(done.stdout.splitlines()[-1])


@pytest.mark.slow
def test_white_and_low_pass_series_are_bit_identical_under_another_instruction_set():
    here, there = probe({}), probe(OTHER_MACHINE)
    assert here.keys() == there.keys()
    assert {name: here[name] == there[name] for name in here} == {name: True for name in here}

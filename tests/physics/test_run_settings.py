"""The library's simulator stands on the physics layer: :func:`rockdec.physics.run.search`
takes plain settings with the defaults the scenes' schema gives, and ``rockdec.simulate``
reaches it without the workflow's scene validation."""

import subprocess
import sys

import pytest

from rockdec.physics import run
from rockdec.physics.record_model import Load, SensorNoise
from rockdec.pipeline import config


def test_the_run_defaults_are_the_scene_schemas():
    scene = config.validate_scene({})  # every default of the schema filled in
    assert run.DEFAULTS == {"model": scene["model"], "nu": scene["system"]["nu"], "theta_cr": scene["system"]["theta_cr"],
                            "sigma_p": scene["excitation"]["sigma_p"], "points_per_cycle": scene["excitation"]["points_per_cycle"]}


def test_a_scene_and_its_plain_settings_give_one_run():
    scene = config.validate_scene({"model": "simplified", "system": {"e": 0.8}, "excitation": {"dt": 0.004, "burn_in": 100}})
    pilot = {"pilot_seeds": 4, "pilot_points": 4000}
    plain = run.search(e=0.8, model="simplified", dt=0.004, burn_in=100, load=Load(), sensor=SensorNoise(), pilot=pilot)
    assert run.from_scene(scene, pilot=pilot) == plain


@pytest.mark.slow
def test_rockdec_simulate_imports_nothing_from_the_workflow_layer():
    code = ("import sys, rockdec; rockdec.simulate(0.85, 200, seed=0, dt=0.01, burn_in=0); "
            "print(sorted(m for m in sys.modules if m.startswith('rockdec.pipeline')))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]", done.stdout

# Config validation and the helpers that turn a scene into file names.
from rockdec import config as rockdec_config

rockdec_config.validate(config)

SCENES = sorted(config["scenes"])


wildcard_constraints:
    scene="|".join(SCENES),


def scene(name):
    """The completed settings of scene ``name``."""
    return config["scenes"][name]


def default_products():
    """Every product of the default scene."""
    name = config["default_scene"]
    tables = ["table.csv", "table.md"]
    if scene(name)["estimates"]["compare_readings"]:
        tables += ["table_readings.csv", "table_readings.md"]
    return [f"results/{name}/{table}" for table in tables]

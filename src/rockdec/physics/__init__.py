"""The rocking block and what drives it: the models (paper eqs. 1-6), the load and sensor
(the record model), the simulators (eqs. 21-24) and the run contract that fixes a series.

The package re-exports the ``__all__`` of its modules (``rockdec.physics.simulate_block`` is
``rockdec.physics.simulate.simulate_block``), each imported on first use: the simulators'
numba kernels compile on import, so ``import rockdec.physics.geometry`` stays light.

Explanation: docs/explanation/method/models.md, docs/explanation/method/simulation.md.
"""

from rockdec.lazy import lazy_names

#: The names each module of the package exports (its ``__all__``), by the module that defines them.
_MODULES = {
    "base_motion": ("envelope", "ground_gain", "ground_motion", "shake_test"),
    "fixed_step": ("KIND", "step"),
    "geometry": ("Block", "parse_block"),
    "housner": ("choose_model", "housner_flight", "integrate_housner", "simulate_block_housner"),
    "loading": (
        "ImpulseSpectrum", "SENSOR_STREAM", "WRAP_TOLERANCE", "add_sensor_noise", "check_load",
        "check_seeds", "draw_impulses", "draw_series", "embedding_size", "low_pass", "sensor_rng",
        "series_rng", "spectral_gain", "stream_words",
    ),
    "models": (
        "MODELS", "MODEL_PEAK_SIGMAS", "MODEL_TOLERANCE", "SCALE_CONSTANT_GUESS", "amplitude_limit",
        "auto_switch_ratio", "check_finite_series", "check_run", "noise_for_amplitude",
        "period_from_g", "period_housner", "period_mismatch", "period_simplified",
        "restoring_acceleration", "scale_constant", "step_for_density",
    ),
    "record_model": (
        "Load", "NO_NOISE", "PAPER", "POLE_RATE_RANGE", "RecordModel", "SensorFilter",
        "SensorNoise", "WHITE", "carried_attrs", "check_filter_declared_with_model",
        "declared_load", "load_attrs", "load_from_attrs", "parse_load", "parse_sensor_filter",
        "parse_sensor_noise", "read_base_record", "sensor_attrs", "sensor_from_attrs",
    ),
    "run": (
        "DEFAULTS", "PILOT", "PPC_TOLERANCE", "Run", "from_scene", "model_for", "overturned",
        "points_per_cycle_shortfall", "search", "simulation_report", "with_model",
    ),
    "simulate": (
        "PILOT_POINTS", "PILOT_SEED_OFFSET", "PILOT_SERIES", "STATISTICS_PILOT_SERIES",
        "STEP_ITERATIONS", "calibrate_dt", "default_burn_in", "flight", "integrate",
        "pilot_statistics", "secant_step", "simulate_block", "simulate_model", "simulation_dataset",
    ),
}

#: Where each exported name lives (imported on first use: the simulators' numba kernels compile on import).
_HOMES = {name: f"{__name__}.{module}" for module, names in _MODULES.items() for name in names}

__all__ = sorted(_HOMES)

__getattr__, __dir__ = lazy_names(__name__, _HOMES)

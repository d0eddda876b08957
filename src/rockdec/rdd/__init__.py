"""The Random Decrement analysis: signatures (paper eqs. 8, 18-20), the estimator registry,
the estimators of ``e`` (eqs. 25-27, ``e_v``) and the one path from records to windows ×
estimators.

The package re-exports the ``__all__`` of its modules (``rockdec.rdd.estimate_all`` is
``rockdec.rdd.estimators.estimate_all``), each imported on first use: the signatures' numba
kernels compile on import, so ``import rockdec.rdd.registry`` stays light.

Explanation: docs/explanation/method/signatures.md, docs/explanation/method/estimators.md.
"""

from rockdec.lazy import lazy_names

#: The names each module of the package exports (its ``__all__``), by the module that defines them.
_MODULES = {
    "estimators": (
        "COLUMNS", "Estimate", "FLAT_ULPS", "G_NAME", "HalfCycle", "LOCAL_ESTIMATORS",
        "estimate_all", "estimate_cube", "extrapolate", "extrapolate_to_zero",
        "extrapolation_weights", "half_cycle", "window_cube", "window_estimates", "zero_window",
    ),
    "fits": ("DEFAULT_FIT_POINTS", "MIN_FIT_POINTS", "min_points_per_cycle"),
    "measured": ("Analysis", "DEFAULT_SETTINGS", "analyse", "rocking_shape"),
    "registry": ("BY_RANK", "CANDIDATES", "DEFAULT_ESTIMATOR", "ESTIMATORS", "REGISTRY", "spec", "trigger"),
    "signatures": (
        "DEFAULT_WINDOWS", "NoTriggerWarning", "SUM_VARS", "SignatureSums", "TRIGGERS",
        "check_lag_range", "crossing_sums", "extremum_sums", "free_response", "lag_samples",
        "mean_signature", "pool", "signature_cube", "trigger_levels", "trigger_sums",
    ),
}

#: Where each exported name lives (imported on first use: the signatures' numba kernels compile on import).
_HOMES = {name: f"{__name__}.{module}" for module, names in _MODULES.items() for name in names}

__all__ = sorted(_HOMES)

__getattr__, __dir__ = lazy_names(__name__, _HOMES)

"""A calibration grid point without simulation, for tests that need a calibration fast.

Every estimator reads the true ``e`` with a spread of 0.01, ``g`` its true value (ratio 1)
with the same spread, and no check has a statistic (NaN: no warning). The settings of the
last call are kept as ``grid_point.settings``. Stands in for ``rockdec.calibrate.calibration._grid_point``.
"""

import numpy as np


def grid_point(j, e, cal_settings, seed_base):
    from rockdec.calibrate import calibration
    from rockdec.record import diagnostics

    grid_point.settings = cal_settings
    rng = np.random.default_rng(j)
    out = e + 0.01 * rng.standard_normal((cal_settings["sets_per_e"], len(calibration.NAMES)))
    out[:, calibration.NAMES.index("g")] = 1.0 + 0.01 * rng.standard_normal(cal_settings["sets_per_e"])
    return out, np.full((cal_settings["sets_per_e"], len(diagnostics.CHECKS)), np.nan)

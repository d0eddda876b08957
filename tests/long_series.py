"""One long series in time chunks, in memory ``O(chunk)``: the simulator's kernels driven block
by block, for the test that checks it equals the whole series and for
``benchmarks/long_record.py``.
"""

from __future__ import annotations

import numpy as np

from rockdec.physics.loading import draw_impulses, series_rng
from rockdec.physics.simulate import integrate


def long_series(seed: int, n_points: int, chunk: int, *, dt, g, e, sigma_p, theta0=0.0, theta_dot0=0.0, burn_in=0):
    """One long series in time chunks: yields ``(theta, theta_dot)`` blocks of ``chunk`` samples.

    Memory stays ``O(chunk)`` whatever ``n_points``; the concatenated blocks equal
    :func:`rockdec.physics.simulate.simulate_block` of the same seed bit for bit (the state and the random stream
    carry over from block to block).
    """
    rng = series_rng(seed)
    impulses = draw_impulses(rng, np.empty(burn_in), sigma_p)
    state_theta, state_omega = np.empty(1), np.empty(1)
    integrate(impulses, dt, g, e, theta0, theta_dot0, burn_in, state_theta, state_omega)
    theta, omega = state_theta[0], state_omega[0]
    done = 0
    while done < n_points:
        size = min(chunk, n_points - done)
        first = done == 0  # the first block starts with the state after the burn-in
        steps = size - 1 if first else size
        impulses = draw_impulses(rng, np.empty(steps), sigma_p)
        out_theta, out_omega = np.empty(steps + 1), np.empty(steps + 1)
        integrate(impulses, dt, g, e, theta, omega, 0, out_theta, out_omega)
        theta, omega = out_theta[-1], out_omega[-1]
        yield (out_theta, out_omega) if first else (out_theta[1:], out_omega[1:])
        done += size

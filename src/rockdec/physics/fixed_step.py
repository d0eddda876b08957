"""Fixed-step simulation of the simplified rocking model with impacts detected on the grid.

The scheme of most public rocking codes, kept as the cheap, biased alternative to the exact
simulator of :mod:`rockdec.physics.simulate`: same model (eq. 4, impact rule eq. 6), same
load, random stream and sampling, so the two differ only in how a step is taken. One step
(:func:`step`) flies the parabola of the side ``sign(theta)`` at its start over the whole
step and, when ``theta`` ends it on the other side, applies ``omega *= e`` at the sample.
The impact is up to one step late, so the effective restitution at ``N`` samples per cycle
is ``e_eff^2 = e^2 + 4 (1 + e^2)/N`` to first order and the free response settles on a
limit cycle of ``N* = 4 (1 + e^2)/(1 - e^2)`` samples per cycle (checked in
``tests/physics/test_fixed_step.py``). The step loop, the load and the Dask wrapper are the
exact simulator's: ``simulate_block(..., grid_impacts=True)`` and
``simulation_dataset(..., model="fixed_step")`` take :func:`step` instead of the exact flight.

Explanation: docs/explanation/method/simulation.md (the fixed-step integrator, §3.3).
"""

from __future__ import annotations

import math

import numba

__all__ = ["KIND", "step"]

#: Name of this simulator in tables (``"exact"`` is :mod:`rockdec.physics.simulate`).
KIND = "fixed_step"


@numba.njit(nogil=True, cache=True)
def step(theta, omega, dt, g, e):
    """One fixed step without load: explicit-side parabola, impact on the grid.

    ``theta`` in rad, ``omega`` in rad/s, ``dt`` in s, ``g`` in rad/s^2. Returns the new
    ``(theta, omega)``; see the module docstring for the scheme. A NaN state stays NaN.
    """
    if theta > 0.0:
        side = 1.0
    elif theta < 0.0:
        side = -1.0
    elif omega > 0.0:
        side = 1.0
    elif omega < 0.0:
        side = -1.0
    elif theta == 0.0 and omega == 0.0:
        return 0.0, 0.0
    else:  # a NaN state stays NaN (it must not come to rest)
        return math.nan, math.nan
    new_theta = theta + dt * (omega - 0.5 * side * g * dt)
    new_omega = omega - side * g * dt
    if side * new_theta < 0.0 or (new_theta == 0.0 and theta != 0.0):
        new_omega *= e
    return new_theta, new_omega

"""Fixed-step simulation of the simplified rocking model with impacts detected on the grid.

This is the scheme of most public rocking codes, kept here as the cheap, biased
alternative to the exact event-driven simulator of :mod:`rockdec.physics.simulate`. Same model
(eq. 4, ``theta'' = -g sign(theta) + F(t)``, impact rule eq. 6), same load (a velocity
impulse ``p_n ~ N(0, sigma_p^2)`` at the end of every step, white, low-pass or of a spectrum), same random stream and the
same sampling convention, so the two simulators differ only in how a step is taken.

One step of length ``dt`` (:func:`step`):

1. *Side.* The side is ``sign(theta)`` at the start of the step (``sign(omega)`` when
   ``theta = 0``; at rest, ``theta = omega = 0``, nothing moves).
2. *Flight.* The parabola of eq. 4 is advanced over the whole step with that side's
   gravity: ``theta += dt (omega - s g dt/2)``, ``omega -= s g dt``. The kinematics are
   exact for constant acceleration, but the sign of gravity is explicit (taken at the
   start of the step): after an unseen crossing the body keeps being pulled the wrong way
   until the step ends.
3. *Impact on the grid.* When ``theta`` ends the step on the other side (or exactly at
   zero, coming from a side), ``omega *= e`` at the sample. No sub-step root is sought:
   the impact is applied up to one step late, at a state that has overshot zero.

Consequences (checked in ``tests/physics/test_fixed_step.py``):

* the global error is of first order in ``dt`` (the impact time is off by up to ``dt``);
* the energy is conserved exactly between impacts (step 2 is exact for one side) and
  changes only at the impact steps, by a factor that is not ``e^2``. A crossing ``tau``
  before the end of its step is followed by ``tau`` of gravity of the wrong sign, which
  adds energy; averaged over where the crossing falls, the *effective* restitution of a
  motion with ``N`` samples per cycle is ``e_eff^2 = e^2 + 4 (1 + e^2)/N`` to first order.
  At ``e = 0.95`` and the paper's 75 points per cycle that is ``e_eff = 1.00``: the grid
  impact dissipates nothing on average;
* hence the free response never decays to rest: it settles on a limit cycle where
  ``e_eff = 1``, of ``N* = 4 (1 + e^2)/(1 - e^2)`` samples per cycle (78 at ``e = 0.95``),
  whatever the step. Under noise the stationary response is larger than the exact
  model's (3.7 times ``sigma_Y`` at 75 points per cycle, ``e = 0.95``), and estimates of
  ``e`` from it are biased upwards;
* several crossings inside one step are seen as at most one impact, and there is no rest
  state: the limit cycle has the amplitude ``g (N* dt)^2 / 32`` (eq. 5), about
  ``190 g dt^2`` at ``e = 0.95``; with ``e = 0`` the block chatters within a few ``g dt^2``
  of zero. (The exact simulator resolves multiple impacts and the rest, docs/method.md §3.3.)

The step loop, the load and the Dask wrapper are the exact simulator's:
``rockdec.physics.simulate.simulate_block(..., grid_impacts=True)`` and
``rockdec.physics.simulate.simulation_dataset(..., model="fixed_step")`` take :func:`step` instead of
the exact flight.
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

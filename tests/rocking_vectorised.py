"""A second simulator of the randomly loaded simplified model (eqs. 4, 6, 21-24), written apart.

Independent of :mod:`rockdec.physics.simulate` (the compiled kernel that the calibration runs): plain
NumPy, one time step for all records at once, the impacts inside a step handled by masks
exactly as :func:`rocking_reference.flight_reference` handles them one at a time (no
closed-form count of bounces: each impact is stepped, and the chatter stops when the
remaining bounces' geometric series, eq. 6, fits in the time left). Its random numbers come
from its own generators (Philox, keyed by each record's seed), so it shares no draw with the kernel's
streams (:mod:`rockdec.physics.loading`), and it low-pass filters the impulses and adds the sensor
noise with its own code.

The coverage study (``workflow/rules/coverage.smk``) imports it from the checkout to check
its cells on records the calibration's simulator did not make; ``tests/studies/test_coverage.py``
checks it against :func:`rocking_reference.flight_reference` flight by flight.
"""

import math

import numpy as np

#: Time steps of impulses drawn at once (memory: this many times the records, float64).
DRAW_STEPS = 8192


def flight(theta, omega, duration, g, e):
    """Free rocking of every record for ``duration`` seconds: ``(theta, omega)`` arrays in,
    new arrays out; each impact stepped, rest when the bounces' series fits (eq. 6)."""
    theta = np.array(theta, dtype=float)
    omega = np.array(omega, dtype=float)
    remaining = np.full(theta.shape, float(duration))
    idx = np.nonzero(~((theta == 0.0) & (omega == 0.0)))[0]
    while idx.size:
        th, om, rem = theta[idx], omega[idx], remaining[idx]
        side = np.where((th > 0.0) | ((th == 0.0) & (om > 0.0)), 1.0, -1.0)
        h, u = side * th, side * om
        t_cross = (u + np.sqrt(u * u + 2.0 * g * h)) / g
        flies = t_cross > rem  # a landing exactly at the end is an impact (as the reference)
        t = rem[flies]
        done = idx[flies]
        theta[done] = side[flies] * (h[flies] + u[flies] * t - 0.5 * g * t * t)
        omega[done] = side[flies] * (u[flies] - g * t)
        lands = ~flies
        hit = idx[lands]
        left = rem[lands] - t_cross[lands]
        rebound = e * (g * t_cross[lands] - u[lands])
        rest = rebound == 0.0
        if e < 1.0:
            rest |= 2.0 * rebound / g / (1.0 - e) <= left
        theta[hit] = 0.0
        omega[hit] = np.where(rest, 0.0, -side[lands] * rebound)
        remaining[hit] = left
        idx = hit[~rest]
    return theta, omega


def generators(seeds) -> list[np.random.Generator]:
    """One random generator per record: Philox keyed by its seed (and a tag of its own), so
    a record depends on its seed only, whatever records run beside it."""
    return [np.random.Generator(np.random.Philox(np.random.SeedSequence([int(s), 17]))) for s in np.atleast_1d(seeds)]


def simulate_records(seeds, n_points, *, dt, g, e, sigma_p, burn_in, pole=0.0, noise=0.0):
    """Records ``theta(record, time)`` of the randomly loaded simplified model, one per seed.

    Each record starts at rest, runs ``burn_in`` steps, then ``n_points`` samples are kept
    (the first the state after the burn-in). Each step: free rocking for ``dt``
    (:func:`flight`), then the velocity impulse ``p_n`` of that instant (eq. 21). The
    impulses are ``N(0, sigma_p^2)``, through ``p_n = pole p_{n-1} + sqrt(1 - pole^2) w_n``
    when ``pole > 0`` (started stationary). ``noise``: white sensor noise added to each
    record, its standard deviation that fraction of the record's rms.
    """
    seeds = np.atleast_1d(np.asarray(seeds, dtype=np.int64))
    rngs = generators(seeds)
    n_rec = seeds.size
    theta = np.zeros(n_rec)
    omega = np.zeros(n_rec)
    out = np.empty((n_rec, n_points))
    gain = math.sqrt(1.0 - pole * pole)
    previous = None
    total = burn_in + n_points - 1
    block = np.empty((0, n_rec))
    for step in range(-burn_in, n_points):
        if step >= 0:
            out[:, step] = theta
        if step == n_points - 1:
            break
        theta, omega = flight(theta, omega, dt, g, e)
        k = (step + burn_in) % DRAW_STEPS
        if k == 0:
            count = min(DRAW_STEPS, total - (step + burn_in))
            block = np.stack([rng.standard_normal(count) for rng in rngs], axis=1)
        w = block[k]
        previous = w if previous is None or pole == 0.0 else pole * previous + gain * w
        omega = omega + sigma_p * previous
    if noise > 0.0:
        rms = np.sqrt(np.mean(out**2, axis=1, keepdims=True))
        out += noise * rms * np.stack([rng.standard_normal(n_points) for rng in rngs])
    return out

"""How well :func:`rockdec.record.record_measure.measure` reads a record's model: records of known model.

For each ``e`` and condition (:data:`CONDITIONS`: white load, white sensor noise of a
share of ``sigma_Y``, a first-order low-pass load with its corner a multiple of the
rocking frequency ``1/T(sigma_Y)`` (eq. 5), or both) records are simulated with
:func:`rockdec.physics.simulate.simulate_block` at about :data:`POINTS_PER_CYCLE` samples per cycle
(``g = 1``, ``sigma_p = 1``: the model is scale-free), noise is added to the sampled angle,
and each record is measured. Noise and drift conditions reuse the clean records with noise
or a trend added, so their rows differ from the clean ones by that only.

The truth of each record: the noise share is the one added (of the clean record's own
``sigma_Y``); the corner is ``-ln(c) / (2 pi dt)`` times ``T(sigma_Y)`` of the clean record
at the true ``g``. :func:`summarise` reduces the rows to one line per ``(e, condition)``:
the share classified as the true kind, the bias and spread of ``sigma_n / sigma_Y`` and of
the corner, of ``g``, and the rate at which noise, colour and drift are flagged (drift conditions add a linear
trend to the clean records).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from rockdec.physics import loading, simulate
from rockdec.record import record_measure
from rockdec.physics.models import period_from_g
from rockdec.physics.record_model import Load
from rockdec.validate import InputError

__all__ = ["run"]

#: ``name: (noise share of sigma_Y, corner in rocking frequencies or None for white,
#: linear drift from start to end of the record in sigma_Y)``.
CONDITIONS = {
    "clean": (0.0, None, 0.0),
    "noise 1%": (0.01, None, 0.0),
    "noise 3%": (0.03, None, 0.0),
    "noise 5%": (0.05, None, 0.0),
    "corner 0.5x": (0.0, 0.5, 0.0),
    "corner 1x": (0.0, 1.0, 0.0),
    "corner 3x": (0.0, 3.0, 0.0),
    "corner 1x + noise 2%": (0.02, 1.0, 0.0),
    "drift 0.1": (0.0, None, 0.1),
    "drift 0.3": (0.0, None, 0.3),
}

#: Samples per cycle at ``sigma_Y`` of the study's records (the paper's sampling).
POINTS_PER_CYCLE = 75.0

#: Seeds of the study's records start here (apart from scenes, pilots and calibrations).
STUDY_SEED_OFFSET = 3 * 2**60


def truth_kind(noise: float, corner) -> str:
    """The kind :attr:`rockdec.record.record_measure.MeasuredModel.kind` should report."""
    return {(False, False): "white", (True, False): "noisy", (False, True): "coloured", (True, True): "both"}[
        (noise > 0.0, corner is not None)
    ]


def records(e: float, corner, n_records: int, n_points: int, *, pilot_seeds: int = 32, seed_offset: int = STUDY_SEED_OFFSET):
    """Clean records ``theta(record, time)`` at ``e`` under a white load (``corner`` None) or a
    low-pass load of that corner, seeds from ``seed_offset``; returns ``(theta, dt, pole)``."""
    pole = (Load() if corner is None else Load("lowpass", corner)).pole(POINTS_PER_CYCLE)
    cal = simulate.calibrate_dt(e=e, g=1.0, sigma_p=1.0, points_per_cycle=POINTS_PER_CYCLE, pilot_seeds=pilot_seeds, iterations=8, pole=pole)
    seeds = seed_offset + np.arange(n_records)
    theta, _ = simulate.simulate_block(seeds, n_points, dt=cal["dt"], g=1.0, e=e, sigma_p=1.0, burn_in=cal["burn_in"], pole=pole)
    return theta, cal["dt"], pole


def run(
    e_values=(0.6, 0.8, 0.9, 0.95, 0.98),
    conditions=CONDITIONS,
    n_records: int = 50,
    n_points: int = 200_000,
    seed_offset: int = STUDY_SEED_OFFSET,
) -> pd.DataFrame:
    """One row per measured record: the condition, the truth and what was measured
    (records and noise from seeds at ``seed_offset``)."""
    rows = []
    for e in e_values:
        by_corner = {}
        for name, (noise, corner, drift) in conditions.items():
            if corner not in by_corner:
                by_corner[corner] = records(e, corner, n_records, n_points, seed_offset=seed_offset)
            theta, dt, pole = by_corner[corner]
            for i, clean in enumerate(theta):
                sigma_y = float(np.std(clean))
                rng = loading.series_rng(seed_offset + 10_000 * (1 + list(conditions).index(name)) + i)
                y = clean + noise * sigma_y * rng.standard_normal(clean.size) if noise > 0.0 else clean
                if drift > 0.0:
                    y = y + drift * sigma_y * np.linspace(-0.5, 0.5, y.size)
                true_hz = math.nan if corner is None else -math.log(pole) / (2.0 * math.pi * dt)
                row = {
                    "e": e,
                    "condition": name,
                    "kind_true": truth_kind(noise, corner),
                    "noise_true": noise,
                    "drift_true": drift,
                    "corner_hz_true": true_hz,
                    "corner_true": true_hz * float(period_from_g(sigma_y, 1.0)),
                }
                try:
                    row.update(_measured(record_measure.measure(y, dt)))
                except InputError:  # too few triples beyond the margin: a refusal, counted
                    row["kind"] = "refused"
                rows.append(row)
    return pd.DataFrame(rows)


def _measured(m: record_measure.MeasuredModel) -> dict:
    """The columns of one measured record."""
    return {
        "kind": m.kind,
        "noise_ratio": m.noise_ratio.value,
        "noise_ratio_se": m.noise_ratio.se,
        "corner_hz": m.corner_hz.value,
        "corner_ratio": m.corner_ratio.value,
        "corner_ratio_se": m.corner_ratio.se,
        "g": m.g.value,
        "g_se": m.g.se,
        "noisy": m.noisy,
        "coloured": m.coloured,
        "drifting": m.drifting,
        "drift_z": m.drift_z,
        "noise_z": m.noise_var.z,
        "colour_z": m.pole.z,
    }


def summarise(rows: pd.DataFrame) -> pd.DataFrame:
    """One line per ``(e, condition)``: ``correct`` (share of records of the true kind),
    ``noise_bias``/``noise_sd`` of ``sigma_n/sigma_Y`` (relative to the truth where noise was
    added, absolute otherwise), ``corner_true`` (median true corner in rocking frequencies:
    the records' own ``sigma_Y`` sets it), ``corner_bias``/``corner_sd`` (relative to the
    true corner) and ``hz_bias``/``hz_sd`` (of the corner in Hz),
    ``g_bias`` (relative), and the flag rates ``noisy``, ``coloured``, ``drifting``;
    ``refused`` counts records with too few usable triples (they count as misclassified,
    and are left out of the other columns)."""
    out = []
    for (e, cond), grp in rows.groupby(["e", "condition"], sort=False):
        noise_err = (grp.noise_ratio / grp.noise_true - 1.0) if grp.noise_true.iloc[0] > 0 else grp.noise_ratio
        corner_err = grp.corner_ratio / grp.corner_true - 1.0
        hz_err = grp.corner_hz / grp.corner_hz_true - 1.0
        coloured = grp.corner_true.notna().all()
        out.append(
            {
                "e": e,
                "condition": cond,
                "records": len(grp),
                "refused": int(np.sum(grp.kind == "refused")),
                "correct": float(np.mean(grp.kind == grp.kind_true)),
                "noise_bias": float(noise_err.mean()),
                "noise_sd": float(noise_err.std()),
                "corner_true": float(grp.corner_true.median()) if coloured else math.nan,
                "corner_bias": float(corner_err.mean()) if coloured else math.nan,
                "corner_sd": float(corner_err.std()) if coloured else math.nan,
                "hz_bias": float(hz_err.mean()) if coloured else math.nan,
                "hz_sd": float(hz_err.std()) if coloured else math.nan,
                "g_bias": float((grp.g - 1.0).mean()),
                "noisy": float(grp.noisy.astype(float).mean()),
                "coloured": float(grp.coloured.astype(float).mean()),
                "drifting": float(grp.drifting.astype(float).mean()),
            }
        )
    return pd.DataFrame(out)

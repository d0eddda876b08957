"""Flight arcs of a free-rocking record, fitted with the model's closed-form free flight.

Between two impacts the block flies freely on one side, so its angle follows the model's
closed form, symmetric about the apex halfway between the impacts:

* simplified model (eq. 4, ``theta'' = -g sign(theta)``): a parabola,
  ``|theta| = (g/2) (H^2 - u^2)``, with ``H`` half the flight time and ``u`` the time from
  the apex; the speed at either impact is ``g H``;
* linearised Housner model (eq. 2, ``theta'' = nu^2 (theta - theta_cr sign(theta))``):
  ``|theta| = theta_cr (1 - cosh(nu u)/cosh(nu H))``; the speed at either impact is
  ``theta_cr nu tanh(nu H)``.

The fall from the release is half an arc, its apex at the release; before it the block is
held at the apex angle. One release and its impacts are fitted together
(:func:`fit_sequence`): the parameters are the release time, the impact times and the
model's one constant (``g``, or ``nu`` given ``theta_cr``), so the angle is zero at every
impact by construction and each impact time is pinned by the samples on both sides. The
speeds just before and after an impact are those of the arcs either side of it (eq. 6), and
their covariance follows from the fit's (:func:`log_speeds`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import optimize

from rockdec.physics.models import MODELS

__all__ = ["FIT_TOLERANCE", "SequenceFit", "fit_sequence", "log_speeds", "shape"]

#: Tolerances of the least-squares fit (relative changes of the cost, the parameters and the
#: gradient): tight, so that a noise-free record gives its impact times to rounding.
FIT_TOLERANCE = 1e-14


def shape(u, H, q, model: str, theta_cr: float | None):
    """The height above zero of a free-flight arc and its derivatives (eqs. 2, 4).

    Parameters
    ----------
    u : numpy.ndarray
        Time from the apex (s).
    H : numpy.ndarray
        Half the flight time of the arc (s).
    q : float
        ``g`` (rad/s^2) for ``model="simplified"``, ``nu`` (rad/s) for ``"housner"``.
    model : str
        ``"simplified"`` or ``"housner"``.
    theta_cr : float or None
        The critical angle (rad), for ``"housner"``.

    Returns
    -------
    tuple of numpy.ndarray
        ``(f, df/du, df/dH, df/dq)``: the height (rad) and its partial derivatives.

    Examples
    --------
    >>> f, f_u, f_H, f_q = shape(np.array([0.0, 1.0]), np.array([1.0, 1.0]), 2.0, "simplified", None)
    >>> f.tolist(), f_u.tolist()
    ([1.0, 0.0], [-0.0, -2.0])
    """
    u = np.asarray(u, dtype=float)
    H = np.asarray(H, dtype=float)
    if model == "simplified":
        return 0.5 * q * (H * H - u * u), -q * u, q * H + 0.0 * u, 0.5 * (H * H - u * u)
    ch, cu, su, th = np.cosh(q * H), np.cosh(q * u), np.sinh(q * u), np.tanh(q * H)
    f = theta_cr * (1.0 - cu / ch)
    return f, -theta_cr * q * su / ch, theta_cr * q * cu * th / ch, theta_cr * (H * cu * th - u * su) / ch


def speed(H, q, model: str, theta_cr: float | None):
    """Angular speed at either end of an arc of half-duration ``H`` (rad/s): ``g H`` (eq. 4)
    or ``theta_cr nu tanh(nu H)`` (eq. 2).

    Parameters
    ----------
    H : float or numpy.ndarray
        Half the flight time (s).
    q : float
        ``g`` (rad/s^2) or ``nu`` (rad/s), as in :func:`shape`.
    model : str
        ``"simplified"`` or ``"housner"``.
    theta_cr : float or None
        The critical angle (rad), for ``"housner"``.

    Returns
    -------
    numpy.ndarray
        The speed (rad/s).

    Examples
    --------
    >>> float(speed(0.5, 2.0, "simplified", None))
    1.0
    """
    H = np.asarray(H, dtype=float)
    return q * H if model == "simplified" else theta_cr * q * np.tanh(q * H)


def _log_speed_gradient(H, q, model: str):
    """``d log S/dH`` and ``d log S/dq`` of :func:`speed`."""
    if model == "simplified":
        return 1.0 / H, 1.0 / q + 0.0 * H
    x = 2.0 * q * H
    return 2.0 * q / np.sinh(x), 1.0 / q + 2.0 * H / np.sinh(x)


@dataclass(frozen=True)
class SequenceFit:
    """The fit of one release and its impacts.

    ``times``: the release time then the impact times (s); ``q``: ``g`` or ``nu``;
    ``covariance``: of ``(*times, q)``; ``residual_std``: of the samples about the fit (rad);
    ``n_samples``: samples fitted; ``side``: sign of the release angle; ``model``,
    ``theta_cr``: as fitted.
    """

    times: np.ndarray
    q: float
    covariance: np.ndarray
    residual_std: float
    n_samples: int
    side: int
    model: str
    theta_cr: float | None

    @property
    def half_durations(self) -> np.ndarray:
        """``H`` of each arc (s): the fall (release to first impact), then half of each flight."""
        t = self.times
        return np.concatenate([[t[1] - t[0]], 0.5 * np.diff(t[1:])])

    def curve(self, t) -> np.ndarray:
        """The fitted angle (rad) at times ``t`` (s) from the start of the fit to the last impact."""
        return _model(np.asarray(t, dtype=float), self.times, self.q, self.side, self.model, self.theta_cr)[0]


def _model(t, times, q, side, model, theta_cr):
    """The angle of a release sequence at ``t`` and its Jacobian columns (index, value pairs)."""
    n = times.size - 1  # impacts
    j = np.minimum(np.searchsorted(times, t, side="right"), n)  # 0: held, 1: fall, k >= 2: flight k - 1
    arc = np.maximum(j - 1, 0)
    sign = side * np.where(arc % 2 == 0, 1.0, -1.0)
    falling = j <= 1
    lo = np.where(falling, 0, j - 1)  # parameter index of the arc's first bound
    hi = np.where(falling, 1, j)
    centre = np.where(falling, times[0], 0.5 * (times[lo] + times[hi]))
    H = np.where(falling, times[1] - times[0], 0.5 * (times[hi] - times[lo]))
    u = np.where(j == 0, 0.0, t - centre)
    f, f_u, f_H, f_q = shape(u, H, q, model, theta_cr)
    d_lo = np.where(falling, -f_u - f_H, 0.5 * (-f_u - f_H))
    d_hi = np.where(falling, f_H, 0.5 * (-f_u + f_H))
    return sign * f, lo, sign * d_lo, hi, sign * d_hi, sign * f_q


def fit_sequence(t, y, *, side: int, times0, q0: float, model: str, theta_cr: float | None, floor: float = 0.0) -> SequenceFit:
    """Least-squares fit of one release sequence (eqs. 2, 4) to the samples ``y`` at ``t``.

    Parameters
    ----------
    t, y : numpy.ndarray
        Sample times (s) and angles (rad), from the held block before the release to the
        last impact.
    side : int
        Sign of the release angle.
    times0 : numpy.ndarray
        First guesses of the release time and the impact times (s).
    q0 : float
        First guess of ``g`` or ``nu``.
    model : str
        ``"simplified"`` or ``"housner"``.
    theta_cr : float or None
        The critical angle (rad), for ``"housner"``.
    floor : float
        Smallest standard deviation (rad) the samples' scatter is taken to have: the
        precision of the record's numbers, so that a noise-free record's covariance
        reflects its rounding rather than a residual that happens to be smaller.

    Returns
    -------
    SequenceFit
        The fitted times and constant, their covariance (the samples' scatter about the fit,
        at least ``floor``, times the inverse of the Gauss-Newton matrix) and the residual
        standard deviation.

    Raises
    ------
    ValueError
        For an unknown ``model``, or fewer samples than parameters.

    Examples
    --------
    >>> g, H = 2.0, 0.5
    >>> t = np.linspace(0.0, 1.5, 31)
    >>> y = np.where(t < H, 0.5 * g * (H**2 - t**2), -0.5 * g * (t - H) * (3 * H - t))
    >>> fit = fit_sequence(t, y, side=1, times0=[0.01, 0.49, 1.52], q0=1.8, model="simplified", theta_cr=None)
    >>> (np.round(fit.times, 9) + 0.0).tolist(), round(fit.q, 9)
    ([0.0, 0.5, 1.5], 2.0)
    """
    if model not in MODELS:
        raise ValueError(f"unknown model '{model}'; use {' or '.join(MODELS)}")
    t, y = np.asarray(t, dtype=float), np.asarray(y, dtype=float)
    p = len(times0) + 1
    if t.size <= p:
        raise ValueError(f"{t.size} samples for {p} parameters")
    # Fitted in units of the sampling step and the largest angle, from the first sample, so
    # that the same record at any angle and time scale takes the same steps to the same point.
    t_ref, t_unit, y_unit = t[0], t[1] - t[0], float(np.max(np.abs(y)))
    q_unit = y_unit / t_unit**2 if model == "simplified" else 1.0 / t_unit
    cr = None if theta_cr is None else theta_cr / y_unit
    ts, ys = (t - t_ref) / t_unit, y / y_unit
    x0 = np.concatenate([(np.asarray(times0, dtype=float) - t_ref) / t_unit, [float(q0) / q_unit]])
    rows = np.arange(t.size)

    def residual(x):
        return _model(ts, x[:-1], x[-1], side, model, cr)[0] - ys

    def jacobian(x):
        _, lo, d_lo, hi, d_hi, d_q = _model(ts, x[:-1], x[-1], side, model, cr)
        jac = np.zeros((t.size, p))
        jac[rows, lo] += d_lo
        jac[rows, hi] += d_hi
        jac[:, -1] = d_q
        return jac

    result = optimize.least_squares(residual, x0, jac=jacobian, method="lm", x_scale="jac", ftol=FIT_TOLERANCE,
                                    xtol=FIT_TOLERANCE, gtol=FIT_TOLERANCE, max_nfev=200 * p)
    jac = jacobian(result.x)
    variance = float(np.sum(residual(result.x) ** 2)) / (t.size - p)
    units = np.concatenate([np.full(p - 1, t_unit), [q_unit]])
    # Columns scaled to unit norm before the inversion: a late, low arc's impact times have
    # small columns, whose directions a plain pseudo-inverse would drop as rounding.
    norms = np.linalg.norm(jac, axis=0)
    norms[norms == 0.0] = 1.0
    scaled = jac / norms
    inverse = np.linalg.pinv(scaled.T @ scaled, hermitian=True) / np.outer(norms, norms)
    covariance = max(variance, (floor / y_unit) ** 2) * inverse * np.outer(units, units)
    x = np.concatenate([t_ref + t_unit * result.x[:-1], [q_unit * result.x[-1]]])
    variance *= y_unit**2
    return SequenceFit(x[:-1], float(x[-1]), covariance, float(np.sqrt(variance)), int(t.size), int(side), model, theta_cr)


def log_speeds(fit: SequenceFit) -> tuple[np.ndarray, np.ndarray]:
    """Log of each arc's impact speed (eq. 6 compares neighbours) and their covariance.

    Arc 0 is the fall (its speed is the one just before the first impact); arc ``k`` the
    flight after impact ``k``, whose speed is the one just after impact ``k`` and just before
    impact ``k + 1``. The covariance is the fit's, carried through by the first-order (delta)
    method.

    Parameters
    ----------
    fit : SequenceFit
        A fitted sequence.

    Returns
    -------
    tuple of numpy.ndarray
        ``log S`` (one per arc) and its covariance matrix.

    Examples
    --------
    >>> cov = np.zeros((4, 4))
    >>> fit = SequenceFit(np.array([0.0, 1.0, 2.6]), 2.0, cov, 0.0, 10, 1, "simplified", None)
    >>> np.round(np.exp(log_speeds(fit)[0]), 9).tolist()
    [2.0, 1.6]
    """
    H = fit.half_durations
    logs = np.log(speed(H, fit.q, fit.model, fit.theta_cr))
    d_H, d_q = _log_speed_gradient(H, fit.q, fit.model)
    n = fit.times.size
    grad = np.zeros((H.size, n + 1))
    grad[0, 0], grad[0, 1] = -d_H[0], d_H[0]
    for k in range(1, H.size):
        grad[k, k], grad[k, k + 1] = -0.5 * d_H[k], 0.5 * d_H[k]
    grad[:, -1] = d_q
    return logs, grad @ fit.covariance @ grad.T

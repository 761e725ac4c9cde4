"""The accelerometer's bias from standstills at several headings on the wall.

On a vertical wall, a crawler standing still at heading θ reads the specific
force of gravity alone, turned into its body frame, plus the bias:

    f(θ) = g·(sin θ, cos θ) + (b_x, b_y)                                     (1)

so the readings of standstills at different headings lie on a circle of
radius g about the bias (the multi-position static test of accelerometer
calibration, reduced to the wall's plane). The circle's centre is the bias;
the headings themselves need not be known, so the turns between the stops
may slip as they like. Kåsa's algebraic circle fit makes this linear: with
c = g² − |b|², each stop's mean reading m_k gives

    2 m_k · b + c = |m_k|²                                                  (2)

solved for (b_x, b_y, c) by least squares over the stops. A common scale
error of both axes changes only the radius, not the centre.

Its standard error comes from each stop's own: a stop's mean moves by its
standard error s_k, and |m_k|² by about 2 g s_k, so (2) has noise 2 g s_k and
the bias's covariance is (2 g s)² (AᵀA)⁻¹ over its first two rows and columns.

The wall EKF (:mod:`.wall_ekf`) starts from a prior of 0 ± 5 mg and learns the
bias from the turns between lanes; a residual of 0.2 mg leans every lane by
2 mm, lane after lane, until the first vertical seam. Calibrating at the start
gives it the bias to a fraction of that before the first lane.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["AccelCalibration", "MIN_SPREAD_DEG", "fit_accel_bias"]

MIN_SPREAD_DEG = 150.0  # the stops' readings must span this much of the circle


@dataclass(frozen=True)
class AccelCalibration:
    bias: tuple[float, float]  # (b_x, b_y), m/s²
    sigma: float  # standard error of each component, m/s²
    radius: float  # the fitted |g|, m/s² (a check: the local gravity)
    stops: int


def fit_accel_bias(stops: list[np.ndarray]) -> AccelCalibration | None:
    """The bias from standstill readings, one (n, 2) array of (f_x, f_y) samples
    per stop; None when the stops do not determine it (fewer than three, or
    their headings spanning less than :data:`MIN_SPREAD_DEG`)."""
    if len(stops) < 3 or any(len(s) < 2 for s in stops):
        return None
    means = np.array([np.mean(s, axis=0) for s in stops])
    ses = np.array([np.std(s, axis=0, ddof=1).max() / math.sqrt(len(s)) for s in stops])
    a = np.column_stack([2.0 * means, np.ones(len(means))])
    rhs = (means**2).sum(axis=1)
    sol, *_ = np.linalg.lstsq(a, rhs, rcond=None)  # eq. (2)
    b = sol[:2]
    radius = math.sqrt(max(sol[2] + float(b @ b), 0.0))
    ang = np.sort(np.degrees(np.arctan2(means[:, 0] - b[0], means[:, 1] - b[1])) % 360.0)
    gaps = np.diff(np.concatenate([ang, ang[:1] + 360.0]))
    if 360.0 - gaps.max() < MIN_SPREAD_DEG:  # an arc this short leaves the centre loose
        return None
    s = float(np.sqrt(np.mean(ses**2)))
    cov = (2.0 * radius * s) ** 2 * np.linalg.pinv(a.T @ a)
    sigma = float(math.sqrt(max(cov[0, 0], cov[1, 1])))
    return AccelCalibration((float(b[0]), float(b[1])), sigma, radius, len(stops))

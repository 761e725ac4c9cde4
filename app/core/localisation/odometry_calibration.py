"""Wheel odometry's systematic errors learnt from the mapper's scan matches
(used by mapping.LaserMapper: each step's odometry is corrected before the
prediction, and each accepted match teaches the calibration)."""

from __future__ import annotations

import math

import numpy as np


class OdometryCalibration:
    """Wheel odometry's systematic errors, learnt from the scan matches: a scale
    factor of the distance driven, a gain of the angle turned and a turn per
    metre driven (the errors the seed's ε_R, ε_L carry when the track is off,
    and when the two wheels' diameters differ: Borenstein & Feng's UMBmark,
    1996, error types B and A).

    Least squares with priors at (1, 1, 0): s = (Σ m·u + w₀) / (Σ u·u + w₀) over
    steps whose match is well determined along the motion (σ ≤ 2 cm there),
    where u is the odometry step and m the matched one; the turn by the model
    m_θ = g·u_θ + b·d (d the distance driven) over steps whose matched turn is
    known to 1°, by the 2×2 normal equations. Clipped to ``GAIN_RANGE`` and
    ±3°/m: a skid-steer base's effective track may be far from its geometric
    one (seed 003's slip on turns), so turn gains of ±40 % are allowed.

    ``turn_covariance``: how uncertain (g, b) still are, for the odometry
    noise model (odometry_noise.py): a Bayesian posterior with the prior
    σ ``gain_sigma``, ``per_m_sigma`` and each learnt step weighted by the
    inverse of its turn's variance (odometry's random part plus the match's),
    P = (P₀⁻¹ + Σ row rowᵀ / σ²)⁻¹, row = (u_θ, d). It is the spread of a
    weighted fit; the estimate above is an unweighted one with its own priors,
    which comes to the same once a few dozen turns are learnt.

    The scale by a median (``scale_rel_sigma`` > 0): no match on the logs
    states 2 cm along the motion (3–9 cm, the Hessian covariance scaled for
    the beams' correlation, and the edge floor), so the least squares above
    never learnt a scale there (1.0000 on every draw, where the drawn error
    was up to 9 %: bench/step_diagnosis.py). What a match knows of the scale
    is relative: σ along the motion over the distance driven. Each step
    whose match knows it to ``scale_rel_sigma`` gives one ratio r = m·u / u·u
    (the matched distance along the odometry's over the odometry's), and
    once ``scale_min_steps`` have come the scale is their median: a robust
    estimate (half the steps may be wrong fits or corridors held along the
    motion by the prediction, whose r is the scale used to predict), which
    needs no weight that a wrong fit's small covariance would win."""

    GAIN_RANGE = (0.6, 1.4)

    def __init__(self, prior_m2: float = 4.0, prior_rad2: float = 0.3,
                 prior_drift_m2: float = 10.0, gain_sigma: float = 0.06,
                 per_m_sigma: float = 0.02, scale_rel_sigma: float = 0.0,
                 scale_min_steps: int = 20) -> None:
        self._sxy, self._sxx = prior_m2, prior_m2
        self.scale_rel_sigma, self.scale_min_steps = scale_rel_sigma, scale_min_steps
        self._ratios: list[float] = []
        self._a = np.diag([prior_rad2, prior_drift_m2])  # normal equations of (g, b)
        self._r = np.array([prior_rad2, 0.0])
        self.scale = 1.0
        self.turn_gain = 1.0
        self.turn_per_m = 0.0
        self._info = np.diag([gain_sigma ** -2, per_m_sigma ** -2])  # P⁻¹ of (g, b)

    def turn_covariance(self) -> np.ndarray:
        """Posterior covariance of (turn gain, turn per metre)."""
        return np.linalg.inv(self._info)

    def correct(self, u: np.ndarray) -> np.ndarray:
        d = math.hypot(u[0], u[1])
        return np.array([u[0] * self.scale, u[1] * self.scale,
                         u[2] * self.turn_gain + self.turn_per_m * d])

    def learn(self, u: np.ndarray, matched: np.ndarray, cov: np.ndarray,
              turn_var: float | None = None) -> None:
        """One matched step: odometry ``u``, the matched step, the match's
        covariance (step frame); ``turn_var``: the variance of the matched
        turn about the model (odometry's random part plus the match's), by
        default the match's alone."""
        d = math.hypot(u[0], u[1])
        if d > 0.1:
            along = np.array([u[0], u[1]]) / d
            var = float(along @ cov[:2, :2] @ along)
            if var <= 0.02 ** 2:
                self._sxy += float(matched[0] * u[0] + matched[1] * u[1])
                self._sxx += d * d
                self.scale = float(np.clip(self._sxy / self._sxx, *self.GAIN_RANGE))
            if var <= (self.scale_rel_sigma * d) ** 2:
                self._ratios.append(float(matched[0] * u[0] + matched[1] * u[1]) / (d * d))
                if len(self._ratios) >= self.scale_min_steps:
                    self.scale = float(np.clip(np.median(self._ratios), *self.GAIN_RANGE))
        if cov[2, 2] <= math.radians(1) ** 2:
            row = np.array([u[2], d])
            self._a += np.outer(row, row)
            self._r += row * float(matched[2])
            var = cov[2, 2] if turn_var is None else turn_var
            self._info += np.outer(row, row) / max(var, 1e-10)
            g, b = np.linalg.solve(self._a, self._r)
            self.turn_gain = float(np.clip(g, *self.GAIN_RANGE))
            self.turn_per_m = float(np.clip(b, -math.radians(3), math.radians(3)))

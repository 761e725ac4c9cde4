"""Trajectory scores and raw-like odometry for benchmarks on reference logs.

- ATE: RMS position error after the best rigid 2-D alignment of the estimate
  onto the reference (Horn/Umeyama without scale).
- RPE (Kümmerle et al. 2009, "On measuring the accuracy of SLAM
  algorithms"): for each scan i, the first scan j at least D metres of
  reference path further on; the error of the relative motion
  δ_ij = (ref_i ⊖ ref_j) ⊖ (est_i ⊖ est_j), mean of |δ_xy| and |δ_θ|.
- ``drifting_odometry`` turns a reference trajectory into odometry with the
  errors real wheels have: a scale error of a few per cent, a yaw error
  proportional to turning, a slow yaw drift per metre, and noise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .se2 import compose, relative, wrap


def align_rigid(est_xy: np.ndarray, ref_xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """R, t minimising Σ‖R est + t − ref‖² (2-D, no scale)."""
    me, mr = est_xy.mean(axis=0), ref_xy.mean(axis=0)
    h = (est_xy - me).T @ (ref_xy - mr)
    u, _, vt = np.linalg.svd(h)
    d = np.sign(np.linalg.det(vt.T @ u.T))
    r = vt.T @ np.diag([1.0, d]) @ u.T
    return r, mr - r @ me


def ate_m(est: np.ndarray, ref: np.ndarray) -> float:
    r, t = align_rigid(est[:, :2], ref[:, :2])
    e = est[:, :2] @ r.T + t - ref[:, :2]
    return float(np.sqrt(np.mean(np.sum(e * e, axis=1))))


@dataclass(frozen=True)
class Rpe:
    trans_m: float
    rot_deg: float
    pairs: int


def rpe(est: np.ndarray, ref: np.ndarray, delta_m: float) -> Rpe:
    steps = np.hypot(*np.diff(ref[:, :2], axis=0).T)
    path = np.r_[0.0, np.cumsum(steps)]
    et, er = [], []
    for i in range(len(ref)):
        j = int(np.searchsorted(path, path[i] + delta_m))
        if j >= len(ref):
            break
        d = relative(relative(ref[i], ref[j]), relative(est[i], est[j]))
        et.append(math.hypot(d[0], d[1]))
        er.append(abs(float(d[2])))
    if not et:
        return Rpe(math.nan, math.nan, 0)
    return Rpe(float(np.mean(et)), math.degrees(float(np.mean(er))), len(et))


@dataclass(frozen=True)
class OdometryErrors:
    scale_sigma: float = 0.03  # per-run scale error of the travelled distance
    yaw_gain_sigma: float = 0.06  # per-run error per radian turned
    yaw_drift_sigma_rad_per_m: float = math.radians(0.6)  # per-run slow drift
    trans_noise_m: float = 0.01  # per-step noise, plus 1 % of the step
    yaw_noise_rad: float = math.radians(0.8)


def drifting_odometry(ref: np.ndarray, seed: int,
                      errors: OdometryErrors = OdometryErrors()) -> np.ndarray:
    """Odometry poses (first = ref[0]) integrated from the reference's relative
    motions with systematic and random errors drawn from ``seed``."""
    rng = np.random.default_rng(seed)
    scale = 1.0 + rng.normal(0.0, errors.scale_sigma)
    gain = 1.0 + rng.normal(0.0, errors.yaw_gain_sigma)
    drift = rng.normal(0.0, errors.yaw_drift_sigma_rad_per_m)
    out = [np.array(ref[0], float)]
    for k in range(1, len(ref)):
        u = relative(ref[k - 1], ref[k])
        d = math.hypot(u[0], u[1])
        sig = errors.trans_noise_m * min(d, 1.0) + 0.01 * d
        v = np.array([u[0] * scale + rng.normal(0, sig), u[1] * scale + rng.normal(0, sig),
                      float(wrap(u[2] * gain + drift * d + rng.normal(0, errors.yaw_noise_rad)))])
        out.append(compose(out[-1], v))
    return np.array(out)


def realised_odometry_errors(odo: np.ndarray, ref: np.ndarray) -> tuple[float, float, float]:
    """The systematic errors odometry ``odo`` really carries against ``ref``:
    (scale, turn gain, turn per metre) by least squares over every step,
    u_xy ≈ scale · t_xy and u_θ ≈ gain · t_θ + per_m · d (t the reference's
    step, d its length). For ``drifting_odometry`` these are the drawn
    parameters plus what the per-step noise holds in common: the mean of 169
    draws of σ 1° is ±0.08° a step (≈ ±0.04°/m on 2 m steps), and a draw
    3.5 standard errors out (default_rng(1)) holds −0.27°/step, which no
    calibration can tell from a drift. So this, not the drawn parameters,
    is what a calibration fed exact matches learns."""
    u = np.array([relative(a, b) for a, b in zip(odo[:-1], odo[1:], strict=True)])
    t = np.array([relative(a, b) for a, b in zip(ref[:-1], ref[1:], strict=True)])
    d = np.hypot(t[:, 0], t[:, 1])
    scale = float(np.sum(u[:, :2] * t[:, :2]) / max(float(np.sum(t[:, :2] ** 2)), 1e-12))
    turn = np.array([float(wrap(x)) for x in u[:, 2]])
    gain, per_m = np.linalg.lstsq(np.c_[t[:, 2], d], turn, rcond=None)[0]
    return scale, float(gain), float(per_m)

"""Scan matches that overlap the local map only in part (the laser mapper's
local step, mapping.py).

A match's inlier share (icp.py: the scan's points within ``inlier_dist_m`` of
a reference line) measures two things at once: whether the fit is right, and
how much of what the scan sees the local landmarks have seen at all. A scan
taken two metres on and turned into a new part of a hall sees most of its
walls for the first time, and only 20–45 % of its points can lie on the
local map; the fit of those points is as good as any. The mapper used to
take every fit under ``min_inlier_fraction`` (45 %) for a failure and dead
reckon the step. Diagnosis (bench/step_diagnosis.py, edmonton every second
scan driven backwards, odometry errors ×1.5, draws 0–5): 37–40 of 169 steps
fell under the share, the same places in every draw (the scene's, not the
odometry's); their fits were 0.4–0.5° off (median) where the dead-reckoned
turns were 1.2–2.1° rms off, and those turns summed to 17–29° on the
draws whose maps broke. The prediction was within 20 cm and 8° of the log's reference
at every such step, well inside the search window: the windows were not the
cause. With larger odometry errors a dead-reckoned step costs more, so a
mapper that dead reckons a fifth of its steps breaks first.

What this module decides instead, for a fit under the share:

1. enough of it: at least ``min_points`` inlier points (a share of the scan
   is not the measure: the fit's information is its inlier pairs');
2. the directions it holds — the degeneracy test of Zhang, Kaess & Singh
   ("On degeneracy of optimization-based state estimation problems", ICRA
   2016, §IV), as the loop closures use it (loop_closure.free_directions): the
   translation block of the inlier pairs' information Σ n nᵀ (in points) is
   split into its eigenvectors; along one that fewer than
   ``degenerate_points`` points hold the match's covariance gets σ
   ``free_sigma_m``, so the step takes odometry's there and the match's
   across it (a corridor seen through a doorway holds the heading and the
   position across the corridor, not along it);
3. its covariance grows as the share falls: R · (f₀ / f) with f₀ the full
   share (``min_inlier_fraction``) and f the fit's — fewer of the scan's
   points vouch for it, and a wrong association is likelier;
4. it is weighed against odometry as odometry really errs: Q is the
   consistent odometry noise model (odometry_noise.py's ``learnt`` model:
   the calibration's remaining uncertainty plus a random part whose level
   is learnt from the full fits' turn residuals), not the fixed model that
   every full fit is fused with, which states 3–5 times odometry's error so
   that the matches decide (bench/odometry_noise_bench.py). A partial fit
   is less sure than a full one (its heading 0.46° off median, 1.6° at the
   90th percentile on edmonton every second scan, where the full fits are
   0.31° and 0.81° off and odometry 0.6°), so against odometry that errs
   0.6° it takes about half the step, and against odometry that errs 1–2°
   (×1.5 errors) most of it: the weight adapts to the odometry's observed
   error;
5. a partial fit's heading errs with a heavier tail than its covariance
   says (the same places in every draw: a hall's wall seen end-on), so
   where its heading innovation is m > k σ of Q + R, R is scaled by
   (m / k)²: Huber's M-estimator as a weight (k = 1.345, his 95 %
   efficiency constant; the robust Kalman update of C. D. Karlgaard & H.
   Schaub, "Huber-based divided difference filtering", JGCD 30(3), 2007);
6. then the same innovation test as every match, νᵀ (Q + R)⁻¹ ν ≤
   ``match_gate_chi2``, with that Q: the window it grants is the
   propagated, learnt uncertainty, not fixed metres.

A partial fit does not teach the odometry calibration or the noise level
(those learn from full-overlap fits only, as before).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .icp import IcpConfig, IcpResult, Reference, pair_information
from .odometry_calibration import OdometryCalibration
from .odometry_noise import OdometryNoise, OdometryNoiseConfig


@dataclass(frozen=True)
class PartialOverlapConfig:
    enabled: bool = True
    learnt_noise: bool = True  # weighed against the learnt odometry noise (4.)
    huber_k: float = 1.345  # heading innovation over k σ: R × (m / k)² (Huber)
    min_points: int = 30  # inlier points a partial fit needs (1.)
    degenerate_points: float = 10.0  # a direction fewer points hold is left free (2.)
    free_sigma_m: float = 1.0
    min_fraction: float = 0.05  # below this share the fit is not looked at


class PartialOverlap:
    """The mapper's partial fits (the module docstring's 1.–6.): which fits
    count, their covariance, and the learnt odometry noise they are weighed
    against (taught by the full fits' turn residuals)."""

    def __init__(self, cfg: PartialOverlapConfig, noise_cfg: OdometryNoiseConfig,
                 full_fraction: float, icp_cfg: IcpConfig) -> None:
        self.cfg, self.full, self.icp_cfg = cfg, full_fraction, icp_cfg
        self.noise = OdometryNoise(replace(noise_cfg, learnt=True, estimate_level=True))

    def accepts(self, r: IcpResult, n_points: int) -> bool:
        """A fit under the full share worth fusing (1.): ``min_points`` inliers."""
        c = self.cfg
        return (c.enabled and c.min_fraction <= r.inlier_fraction < self.full
                and r.inlier_fraction * n_points >= c.min_points)

    def learn(self, u: np.ndarray, residual_rad: float, match_var: float,
              cal: OdometryCalibration | None) -> None:
        """A full fit's turn residual teaches the odometry noise level (4.)."""
        self.noise.learn(u, residual_rad, match_var, cal)

    def weigh(self, points: np.ndarray, ref: Reference, fit: IcpResult, r: np.ndarray,
              u: np.ndarray, q: np.ndarray,
              cal: OdometryCalibration | None) -> tuple[np.ndarray, np.ndarray]:
        """(the fit's covariance (2., 3.), the odometry covariance to weigh it
        against (4.); ``q`` when ``learnt_noise`` is off)."""
        r = partial_covariance(points, ref, fit.pose, r, fit.inlier_fraction, self.full,
                               self.icp_cfg, self.cfg)
        return r, self.noise.covariance(u, cal) if self.cfg.learnt_noise else q

    def huber(self, innov: np.ndarray, q: np.ndarray, r: np.ndarray) -> np.ndarray:
        """R scaled by (m / k)² where the heading innovation is m > k σ of
        Q + R (5.: Huber's weight, k = ``huber_k``)."""
        k = self.cfg.huber_k
        m2 = innov[2] ** 2 / (q[2, 2] + r[2, 2])
        return r * (m2 / k ** 2) if m2 > k ** 2 else r


def partial_covariance(points: np.ndarray, ref: Reference, pose: np.ndarray,
                       cov: np.ndarray, fraction: float, full_fraction: float,
                       icp_cfg: IcpConfig, cfg: PartialOverlapConfig) -> np.ndarray:
    """The partial fit's covariance (world frame): ``cov`` (the match's, as a
    full fit's would be) times f₀ / f (3.), plus σ ``free_sigma_m`` along each
    translation direction that fewer than ``degenerate_points`` inlier points
    hold (2.)."""
    out = np.array(cov, float) * (full_fraction / max(fraction, 1e-6))
    w, v = np.linalg.eigh(pair_information(points, ref, pose, icp_cfg))
    for lam, vec in zip(w, v.T, strict=True):
        if lam < cfg.degenerate_points:
            out[:2, :2] += cfg.free_sigma_m ** 2 * np.outer(vec, vec)
    return out


__all__ = ["PartialOverlap", "PartialOverlapConfig", "partial_covariance"]

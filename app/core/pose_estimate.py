"""The robot's localisation as the desk shows it, and the operator's "set pose".

No Qt: the map model and panel call these.

- :func:`quality_from_pose`: the optional quality block of a ``Pose`` message
  (covariance, match score, status) as a :class:`PoseQuality`, or None from a
  robot that sends none;
- :func:`covariance_ellipse`: the position uncertainty as a closed polyline
  around the estimate — the ellipse {d : dᵀ Σ⁻¹ d = k²} with k² the χ²
  quantile for two degrees of freedom at the chosen probability
  (k² = −2 ln(1 − p); p = 0.95 gives k ≈ 2.45);
- :func:`quality_line`: one line for the panel and whether it needs the
  operator (lost);
- :func:`pose_from_drag`: a click-and-drag on the map (press at the robot's
  position, release in the direction it faces, as RViz's 2-D pose estimate)
  as the ``set_pose`` command's arguments.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from app.core.i18n import translate

STATUS_ODOMETRY, STATUS_TRACKING, STATUS_LOST = 0, 1, 2
MIN_DRAG_M = 0.2  # a shorter drag gives no heading: refused with a hint


@dataclass(frozen=True)
class PoseQuality:
    cov: np.ndarray  # 2×2 position covariance, m²
    var_theta: float  # rad²
    match_score: float  # fraction of the last scan's points on the map
    match_rmse_m: float
    status: int

    @property
    def lost(self) -> bool:
        return self.status == STATUS_LOST

    @property
    def sigma_xy_m(self) -> float:
        """The largest position standard deviation (the ellipse's half major axis / k)."""
        return math.sqrt(max(float(np.linalg.eigvalsh(self.cov).max()), 0.0))

    @property
    def sigma_theta_rad(self) -> float:
        return math.sqrt(max(self.var_theta, 0.0))


def quality_from_pose(msg: Any) -> PoseQuality | None:
    """The quality block of a Pose message, or None when it has none or it is
    not finite (a bad block is not drawn)."""
    vals = [getattr(msg, k, None) for k in ("cov_xx", "cov_xy", "cov_yy", "var_theta",
                                            "match_score", "match_rmse_m", "status")]
    if any(v is None for v in vals):
        return None
    try:
        cxx, cxy, cyy, vth, score, rmse = (float(v) for v in vals[:6])
        status = int(vals[6])
    except (TypeError, ValueError):
        return None
    if not all(math.isfinite(v) for v in (cxx, cxy, cyy, vth, score, rmse)):
        return None
    if status not in (STATUS_ODOMETRY, STATUS_TRACKING, STATUS_LOST):
        return None
    return PoseQuality(np.array([[cxx, cxy], [cxy, cyy]]), vth, score, rmse, status)


def covariance_ellipse(cov: np.ndarray, centre: tuple[float, float], probability: float = 0.95,
                       segments: int = 48) -> np.ndarray:
    """(segments + 1, 2) closed polyline: the ``probability`` contour of a 2-D
    Gaussian with covariance ``cov`` around ``centre``. A covariance that is
    not positive semi-definite is clipped to it (eigenvalues below 0 → 0)."""
    cov = np.asarray(cov, float).reshape(2, 2)
    cov = (cov + cov.T) / 2
    w, v = np.linalg.eigh(cov)
    w = np.maximum(w, 0.0)
    k = math.sqrt(-2.0 * math.log(1.0 - probability))
    t = np.linspace(0.0, 2 * math.pi, segments + 1)
    unit = np.column_stack((np.cos(t), np.sin(t)))
    pts = (unit * (k * np.sqrt(w))) @ v.T
    return pts + np.asarray(centre, float)


def quality_line(q: PoseQuality | None) -> tuple[str, bool]:
    """('Localisation: ...', needs the operator)."""
    if q is None:
        return translate("Localisation", "Localisation: — (the robot sends no quality)"), False
    sig = f"σ {q.sigma_xy_m * 100:.0f} cm / {math.degrees(q.sigma_theta_rad):.1f}°"
    if q.lost:
        return translate("Localisation", "Localisation: LOST — drag Set pose on the map "
                         "({sig})").format(sig=sig), True
    if q.status == STATUS_ODOMETRY:
        return translate("Localisation", "Localisation: odometry only · {sig}").format(
            sig=sig), False
    return translate("Localisation", "Localisation: tracking · match {match} % "
                     "(rms {rms} cm) · {sig}").format(
        match=f"{q.match_score * 100:.0f}", rms=f"{q.match_rmse_m * 100:.1f}", sig=sig), False


def pose_from_drag(x0: float, y0: float, x1: float, y1: float,
                   min_drag_m: float = MIN_DRAG_M) -> dict[str, float] | None:
    """``set_pose`` arguments from a drag: the robot at the press point, facing
    the release point; None for a drag shorter than ``min_drag_m`` (no heading)
    or a non-finite point."""
    vals = (x0, y0, x1, y1)
    if not all(math.isfinite(float(v)) for v in vals):
        return None
    dx, dy = float(x1) - float(x0), float(y1) - float(y0)
    if math.hypot(dx, dy) < min_drag_m:
        return None
    return {"x_m": round(float(x0), 3), "y_m": round(float(y0), 3),
            "theta_rad": round(math.atan2(dy, dx), 4)}

"""The result of reading a gauge: :class:`Reading`, and the helpers every reader shares."""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field

__all__ = ["MIN_CONFIDENCE", "REASONS", "Reading", "ramp", "refuse", "elapsed_ms"]

MIN_CONFIDENCE = 0.5


@dataclass
class Reading:
    """One gauge reading with its confidence and the geometry an overlay needs.

    All ``*_xy`` points and the ellipse are in the input image's pixel coordinates.
    ``value`` is None when the reading is refused; ``error`` then says why.
    """

    value: float | None
    unit: str
    confidence: float
    error: str | None = None
    raw_value: float | None = None  # the candidate value even when refused
    angle_deg: float | None = None  # pointer angle on the upright dial (profile convention)
    dial_ellipse: tuple[float, float, float, float, float] | None = None  # cx, cy, w, h, deg
    dial_centre_xy: tuple[float, float] | None = None  # hub centre
    dial_radius_px: float | None = None
    pointer_tip_xy: tuple[float, float] | None = None
    pointer_line_xy: tuple[tuple[float, float], tuple[float, float]] | None = None
    scale_ends_xy: tuple[tuple[float, float], tuple[float, float]] | None = None
    in_normal_band: bool | None = None
    scores: dict = field(default_factory=dict)
    elapsed_ms: float = 0.0
    # "scale" (found on the dial), "profile-angles", "calibrated", "calibrated-reference",
    # "keypoints" (the learned fallback, :mod:`.keypoints`)
    method: str = "scale"
    homography: list | None = None  # 3 x 3, reference frame -> this image (calibrated)
    # "profile-angles": how far the value may be off, in % of full scale, by what was
    # verified (the needle estimates' and the end marks' disagreements, the pivot's miss)
    error_bound_fs: float | None = None

    @property
    def ok(self) -> bool:
        return self.value is not None

    def to_dict(self) -> dict:
        return asdict(self)


# the uncalibrated reader's checks (the names of its scores) as a low confidence's reason
REASONS = {
    "dial": "dial rim not clear",
    "pointer_length": "pointer not fully visible",
    "line_fit": "pointer is not a clean straight line",
    "line_through_hub": "pointer line misses the hub",
    "tip_agrees": "pointer tip and axis disagree",
    "scale_fit": "tick marks irregular",
    "scale_span": "scale arc does not match the profile",
    "ticks": "too few tick marks",
    "on_scale": "pointer outside the scale",
    "passes_agree": "affine and perspective corrections disagree",
    "ticks_seen": "most tick marks not visible",
    "hub_centred": "hub far from the dial rim's centre",
    "needle_unique": "another needle-like line (a second pointer?)",
    "tip_vs_tail": "cannot tell the needle's tip from its tail",
    "needles_agree": "the two needle finders barely agree",
    "error_bound": "the scale's ends leave the reading uncertain",
    "stop_pin": "the needle lies far below the minimum",
}


def ramp(x: float, bad: float, good: float) -> float:
    """1 at ``good``, 0 at ``bad``, linear between (either order)."""
    if good == bad:
        return 1.0 if x == good else 0.0
    return float(min(1.0, max(0.0, (x - bad) / (good - bad))))



def refuse(unit, reason, scores=None, **kw) -> Reading:
    return Reading(value=None, unit=unit, confidence=0.0, error=reason, scores=scores or {}, **kw)



def elapsed_ms(t0: float) -> float:
    return round((time.perf_counter() - t0) * 1000.0, 3)


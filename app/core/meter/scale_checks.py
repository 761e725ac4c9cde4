"""Checks on the scale the scale path found, before it is read alone
(:func:`app.core.meter.reader.read_gauge`): a scale one of these calls unverified is read
only where the profile's angles confirm it.

* **End ticks restored beyond the needle** (:func:`restored_ends`): the scale path
  restores end ticks the pointer hid; a restored end further out than a tick step from the
  needle may be the dial's end shifted by a tick or two.
* **A scale turned from the profile's arc** (:func:`turned_scale`): a turned camera or
  gauge turns the whole scale, which the scale path reads the needle against; beyond the
  camera's usual roll, a scale of the profile's span may be the dial's shifted by a few
  ticks (an end tick hidden by a needle at rest, print in the gap taken for ticks).
* **The needle not confirmed** (:func:`needle_doubt`): the ray finder, about the same
  hub, must find the scale path's needle within :data:`SCALE_NEEDLE_DEG`; a two-ended
  needle whose two ends reach alike is left to the profile's angles, which weigh the ends
  against the scale placed.
"""

from __future__ import annotations

import numpy as np

from .needle import WEIGH_REACH, find_needle
from .profile import GaugeProfile
from .scale import angle_diff

__all__ = ["END_COVER_DEG", "SCALE_NEEDLE_DEG", "SCALE_TURN_DEG", "needle_doubt",
           "restored_ends", "turned_scale"]

SCALE_NEEDLE_DEG = 3.0  # the ray finder confirms the scale path's needle within this

END_COVER_DEG = 20.0  # ends this close to the needle may have had ticks restored under it
SCALE_TURN_DEG = 15.0  # a scale turned further from the profile's arc must be confirmed


def restored_ends(theta: float, sc) -> str | None:
    """The scale path restores end ticks the pointer hid (``sc.extended``); a restored end
    is explained by the needle only if it lies under the needle, within a tick step of it.
    One further out (but near the needle, within :data:`END_COVER_DEG`) is unverified: a
    needle resting on its stop pin below the minimum gave a scale shifted by two ticks that
    still matched the profile's span.  The profile's angles must confirm it then."""
    if not sc.extended:
        return None
    for end in (sc.start_deg, sc.end_deg):
        off = abs(angle_diff(theta, end))
        if sc.step_deg < off <= END_COVER_DEG:
            return "end ticks restored beyond the needle are unverified"
    return None


def turned_scale(sc, prof: GaugeProfile) -> str | None:
    """A scale found turned from the profile's arc by more than :data:`SCALE_TURN_DEG` (its
    middle against the profile's) is unverified: beyond the camera's usual roll, the scale
    may be the dial's shifted by a few ticks (an end tick hidden by a needle at rest, print
    in the gap taken for ticks), its span still the profile's.  The profile's angles must
    confirm it then."""
    turn = angle_diff(0.5 * (sc.start_deg + sc.end_deg),
                      0.5 * (prof.min_angle_deg + prof.max_angle_deg))
    if abs(turn) > SCALE_TURN_DEG:
        return f"the scale found is turned {turn:+.0f} deg from the profile's arc"
    return None


def needle_doubt(res: dict, crop: np.ndarray, prof: GaugeProfile) -> str | None:
    """The scale path's needle checked by the ray finder (:func:`.needle.find_needle`) about
    the same hub: None when they agree, else the reason."""
    nf = find_needle(crop, res["centre"], res["r_s"], needle=prof.needle,
                     ignore_colour=prof.ignore_colour)
    if not nf.ok:
        return f"the needle is not confirmed ({nf.error})"
    d = abs(angle_diff(nf.angle_deg, res["theta"]))
    if d > SCALE_NEEDLE_DEG:
        return f"two needle finders disagree by {d:.0f} deg"
    if prof.needle == "two-ended" and nf.tail_px > nf.length_px - WEIGH_REACH * res["r_s"]:
        # two ends that reach alike far: the skeleton's heavier side and the rays' cues may
        # both take the tail; the profile's angles weigh the ends against the scale placed
        return "the needle's two ends reach alike"
    return None

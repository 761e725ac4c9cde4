"""Checks that the pivot a reading is measured about is the dial's, by a second estimate.

Two places where the uncalibrated reader measured angles about a point nothing
independent had confirmed, and read dials 2.3 and 5.3 % FS off at full confidence
(docs/meter-bench.md, "A pivot no second estimate confirms"):

* the scale path's hub where no circle fits it (:func:`scale_pivot_doubt`);
* the oblique second look, which removes the perspective about the scale ring's centre
  (:func:`second_look_allowed`).
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from .angles import DARK_FACE_GREY, HUB_RMS_PX, SAME_START_PX, median_face_grey
from .dial import FACE_RADIUS
from .pointer import CENTRE as _C
from .pointer import read_normalised
from .profile import GaugeProfile
from .ring_centre import (
    CENTRES_AGREE_PX,
    hub_is_perspective_centre,
    pass_images,
    ring_centre,
)

__all__ = ["HUB_FIRM_RMS_PX", "hub_moved", "negative_pass", "scale_pivot_doubt",
           "second_look_allowed"]

HUB_FIRM_RMS_PX = 1.5  # a hub circle fitting its boundary this closely is a firm pivot


def scale_pivot_doubt(res: dict) -> str | None:
    """The scale path measures every angle about the hub; a hub whose circle was not fitted
    (``hub_rms``: none fits the pointer region's boundary about it within
    :data:`.angles.HUB_RMS_PX`) is only the thickest point of that region near the centre,
    which for a tapered needle whose cap the threshold leaves out is the needle's base, up
    to a cap's radius from the pivot along the needle.  The ticks' angles about such a
    point can still fit an even comb (with a wrong step), so the scale's own checks do not
    see it.  Such a hub is then checked as the angles path checks its pivot: against the
    centre of the ring of scale marks (:func:`.ring_centre.ring_centre`, fitted from the
    hub and from the rim's centre, the closer circle winning), within
    :data:`.ring_centre.CENTRES_AGREE_PX`.  Where they disagree, the profile's angles
    (whose pivot is that ring's centre, checked against the needle's line) must confirm
    the reading.  A hub whose circle was fitted but lies more than that off the rim's
    centre is checked the same way: a circle of the cap's highlight, or of the cap and a
    tail's ring together, fits as closely as the cap's own, and measured about it a short
    needle reads degrees off while the ticks' comb still fits.  None when the pivot is
    verified, else the reason."""
    hub = res["centre"]
    if res.get("hub_rms", 99.0) < HUB_RMS_PX and \
            math.hypot(hub[0] - _C, hub[1] - _C) <= CENTRES_AGREE_PX:
        return None
    starts = [hub] if math.hypot(hub[0] - _C, hub[1] - _C) < SAME_START_PX else [hub, (_C, _C)]
    darkf, hidden = pass_images(res)
    fits = [f for f in (ring_centre(darkf, res["otsu_t"], s, FACE_RADIUS, hidden)
                        for s in starts) if f is not None]
    if not fits:
        return "the pivot is unverified (no circle fits the pointer's hub, no ring of " \
            "scale marks about it)"
    c = min(fits, key=lambda f: f[1])[0]
    d = math.hypot(c[0] - hub[0], c[1] - hub[1])
    if d <= CENTRES_AGREE_PX:
        return None
    return f"the pivot is unverified (no circle fits the pointer's hub, and the scale " \
        f"ring's centre lies {d:.0f} px from it)"


def negative_pass(crop: np.ndarray, prof: GaugeProfile):
    """A callable giving the first pass (:func:`.pointer.read_normalised`) on the crop's
    negative, where a dark face's light marks are dark, made on first use and kept: the
    profile's angles and the second look's check (:func:`second_look_allowed`) each read
    the same crop's negative.  Read-only use: the pass's result is not changed by either."""
    memo: list = []

    def get() -> dict:
        if not memo:
            memo.append(read_normalised(cv2.bitwise_not(crop), prof))
        return memo[0]

    return get


def second_look_allowed(res: dict, crop: np.ndarray, prof: GaugeProfile, c, r_aff: float,
                        negative=None) -> bool:
    """Whether the scale ring's centre ``c`` (crop pixels) may be the image of the dial's
    centre, so that the perspective may be removed about it for a second look.

    ``c`` came from the ring fit (of those started from the hub and from the rim's
    centre) that lay closest to a circle; the other start's ring of marks may fit about
    another centre.  Under perspective every ring of marks is centred on the line from the
    dial's centre's image to the rim's centre, by the square of its radius
    (:func:`.ring_centre.hub_is_perspective_centre`), so each ring found must allow ``c``.
    A ring that stays on the rim's centre while ``c`` lies far off it says ``c`` is the
    centre of something else (a ring inside the ticks about the needle's base): the warp about
    ``c`` would make the scale concentric with it, and the second look's pivot checks
    would then confirm it by construction.  The marks are dark in the crop read (a dark
    face's negative; ``negative``: :func:`negative_pass` of ``crop``, if made already)."""
    marks = res
    if median_face_grey(crop) < DARK_FACE_GREY:
        marks = (negative or negative_pass(crop, prof))()
    if "dark" not in marks:
        return True  # no pointer region to hide: nothing to test the point against
    return hub_is_perspective_centre(marks, r_aff, hub=c, every_ring=True)


def hub_moved(res: dict) -> bool:
    """Whether the view rectified about the hub finds its hub elsewhere: the perspective
    was removed about the point the first pass took for the hub, which the second view
    puts at the crop's centre; a hub found there again is the same pivot, a firm circle
    found off it (over CENTRES_AGREE_PX) says the first was something else (a needle's
    counterweight beside its nut), and a view rectified about a wrong point turns the
    middle of the scale against its ends (a scale's ends still match the profile's span)."""
    c = res.get("centre")
    return c is not None and res.get("hub_rms", 99.0) < HUB_FIRM_RMS_PX and \
        math.hypot(c[0] - _C, c[1] - _C) > CENTRES_AGREE_PX

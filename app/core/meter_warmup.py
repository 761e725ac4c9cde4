"""Warming the meter reader up when the desk starts (no Qt).

The desk's first meter reading, minutes into a patrol, ran code nothing had run
before: OpenCV's and the reader's compiled paths were paged in and the reading
thread's heap grew to what a reading needs (measured: resident memory +11.7 MB and
138 ms for the first reading, nothing and 17 ms for the next). A desk left running
seemed to grow for its first minutes. :func:`warm_up_reader`, run on the desk's
reading thread at start, reads a drawn dial once with each gauge type's profile
and loads the keypoint model, so that growth happens at start and the first real
reading is as quick as the rest. The readings are thrown away.
"""

from __future__ import annotations

import logging
import math

import cv2
import numpy as np

from app.core.meter_service import MeterService, read_frame

__all__ = ["synthetic_dial_frame", "warm_up_reader"]

log = logging.getLogger(__name__)

FRAME_H, FRAME_W = 480, 640  # the robot camera's frame
DIAL_R = 130  # px


def synthetic_dial_frame(value: float = 0.6) -> np.ndarray:
    """A plain dial (RGB): a white face in a dark rim, 41 ticks over 270 degrees from
    lower left clockwise, a dark needle at ``value`` (0..1) of the span."""
    img = np.full((FRAME_H, FRAME_W, 3), 120, np.uint8)
    c = (FRAME_W // 2, FRAME_H // 2)
    cv2.circle(img, c, DIAL_R + 8, (40, 40, 40), -1, cv2.LINE_AA)
    cv2.circle(img, c, DIAL_R, (245, 245, 245), -1, cv2.LINE_AA)
    start, span = 225.0, 270.0  # deg, clockwise from the top (screen coordinates)

    def at(frac: float, r: float) -> tuple[int, int]:
        a = math.radians(start + span * frac)
        return int(round(c[0] + r * math.sin(a))), int(round(c[1] - r * math.cos(a)))

    for i in range(41):
        inner = DIAL_R * (0.78 if i % 5 == 0 else 0.86)
        cv2.line(img, at(i / 40, inner), at(i / 40, DIAL_R * 0.95), (20, 20, 20),
                 3 if i % 5 == 0 else 1, cv2.LINE_AA)
    cv2.line(img, c, at(value, DIAL_R * 0.85), (25, 25, 25), 4, cv2.LINE_AA)
    cv2.circle(img, c, 9, (25, 25, 25), -1, cv2.LINE_AA)
    return img


def warm_up_reader(service: MeterService) -> int:
    """Read the drawn dial once with each gauge type's profile (run on the thread
    that reads meters); returns how many profiles were read. Never raises."""
    n = 0
    try:
        from app.core.meter.keypoints import load_model

        load_model()
        frame = synthetic_dial_frame()
        types: dict[str, str] = {}
        for gauge_id, info in service.gauges.items():
            types.setdefault(info.type, gauge_id)
        for gauge_id in types.values():
            try:
                read_frame(frame, service.profile(gauge_id))
                n += 1
            except ValueError as e:  # a bad profile file: said when it is used for real
                log.debug("meter warm-up: %s", e)
    except Exception:  # noqa: BLE001 - a warm-up must never stop the desk
        log.exception("meter warm-up failed")
    log.debug("meter reader warmed up with %d gauge profiles", n)
    return n

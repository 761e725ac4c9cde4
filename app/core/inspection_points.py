"""Calibrated inspection points: a route point's own gauge profile and reference frame.

The robot stops at the same inspection point on every patrol and sees the same gauge from
nearly the same place.  Calibrating the point (three clicks on a frozen frame: the needle's
pivot, the scale's minimum and maximum end marks) stores, beside the route file::

    routes/north.json                      the route; its point "P1" gets
                                           "profile": "north.points/P1.json"
    routes/north.points/P1.json            the calibrated profile (the gauge type's
                                           profile plus "calibration", see
                                           docs/gauge-profiles.md)
    routes/north.points/P1.png             the reference frame the points were clicked on

The profile's ``calibration.image`` is relative to the profile file (``"P1.png"``), the
route's ``profile`` relative to the route file, so the folder can be moved as a whole.
Every file is written atomically (a temporary file renamed over the target), the reference
frame first and the route last, so a route never names a profile that is not there.

Qt-free: the calibration dialog (app/ui) and the tests call the same functions.
"""

from __future__ import annotations

import json
import logging
import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from app.core.meter import GaugeProfile, load_profile, make_calibrated_profile, read_gauge
from app.core.paths import writable_route
from app.core.route import (
    RoutePoint,
    check_relative_path,
    load_route,
    save_route,
    write_atomic,
)

__all__ = ["POINTS_SUFFIX", "PointCalibration", "calibrate_point", "point_file_stem",
           "suggest_points"]

log = logging.getLogger(__name__)

POINTS_SUFFIX = ".points"  # <route stem>.points/ holds the route's point profiles
XY = tuple[float, float]


@dataclass(frozen=True)
class PointCalibration:
    """What :func:`calibrate_point` wrote."""

    point: str
    route: Path  # the route file
    profile: Path  # the calibrated profile (absolute)
    image: Path  # the reference frame (absolute)
    relative: str  # the route's "profile" value


def point_file_stem(point_name: str) -> str:
    """A file-name stem for a point name: letters, digits, ``.``, ``_`` and ``-`` kept,
    anything else (spaces, slashes) made ``_``; never empty, never hidden."""
    stem = re.sub(r"[^A-Za-z0-9._-]+", "_", point_name.strip()).strip("._") or "point"
    return stem


def _check_xy(v: Any, what: str, size: tuple[int, int]) -> XY:
    try:
        x, y = (float(c) for c in v)
    except (TypeError, ValueError):
        raise ValueError(f"{what} must be a pair of numbers, got {v!r}") from None
    w, h = size
    if not (math.isfinite(x) and math.isfinite(y)):
        raise ValueError(f"{what} must be finite, got {v!r}")
    if not (-0.5 <= x <= w - 0.5 and -0.5 <= y <= h - 0.5):
        raise ValueError(f"{what} ({x:.1f}, {y:.1f}) lies outside the {w}x{h} frame")
    return x, y


def _base_dict(base: GaugeProfile | dict) -> dict:
    """The gauge type's profile as the base of a calibrated one: name, unit, range, normal
    band and tick table; its angles are left out (the clicked points give the arc)."""
    d = base.to_dict() if isinstance(base, GaugeProfile) else dict(base)
    d.pop("calibration", None)
    if not d.get("ticks"):
        d.pop("min_angle_deg", None)
        d.pop("max_angle_deg", None)
    return d


def _profile_rel(route_dir_name: str, point: RoutePoint, others: set[str]) -> str:
    """The point's profile path relative to the route's folder; kept when the point has
    one already, else ``<route stem>.points/<point>.json``, made unique in the route."""
    if point.profile is not None:
        return point.profile
    stem = point_file_stem(point.name)
    rel, k = f"{route_dir_name}/{stem}.json", 2
    while rel in others:
        rel, k = f"{route_dir_name}/{stem}-{k}.json", k + 1
    return rel


def calibrate_point(route_path: str | Path, point_name: str, base: GaugeProfile | dict,
                    image_rgb: np.ndarray, centre: XY, min_point: XY, max_point: XY, *,
                    clockwise: bool | None = None) -> PointCalibration:
    """Calibrate ``point_name`` of the route at ``route_path`` on the frozen frame
    ``image_rgb`` (H x W x 3 uint8, RGB as the link delivers it) with the three clicked
    points, starting from the gauge type's profile ``base``.

    Writes the reference PNG, the calibrated profile (via
    :func:`app.core.meter.make_calibrated_profile`) and the route with the point's
    ``profile`` key.  ``clockwise`` defaults to the base profile's direction.  A second
    calibration of the same point replaces its files.  ValueError names what is wrong (no
    such point, a point without a gauge, a bad frame, a point off the frame, a profile the
    meter package refuses); nothing is changed in the route then."""
    route_path = writable_route(route_path)  # a shipped route: the user's copy of it
    route = load_route(route_path)
    point = next((p for p in route.points if p.name == point_name), None)
    if point is None:
        raise ValueError(f"{route_path.name}: no point named {point_name!r}")
    if point.gauge is None:
        raise ValueError(f"{route_path.name}: point {point_name!r} has no gauge to calibrate")
    if not (isinstance(image_rgb, np.ndarray) and image_rgb.dtype == np.uint8
            and image_rgb.ndim == 3 and image_rgb.shape[2] == 3 and image_rgb.size):
        raise ValueError("the frozen frame must be an H x W x 3 8-bit RGB image")
    size = (image_rgb.shape[1], image_rgb.shape[0])
    c = _check_xy(centre, "the pivot", size)
    p0 = _check_xy(min_point, "the minimum mark", size)
    p1 = _check_xy(max_point, "the maximum mark", size)
    base_d = _base_dict(base)
    if clockwise is None:
        clockwise = (base if isinstance(base, GaugeProfile) else load_profile(base)).clockwise

    others = {p.profile for p in route.points if p.profile is not None and p is not point}
    rel = check_relative_path(_profile_rel(route_path.stem + POINTS_SUFFIX, point, others),
                              f"point {point_name!r}: 'profile'")
    profile_path = (route_path.resolve().parent / rel)
    image_path = profile_path.with_suffix(".png")
    c, p0, p1 = ((round(x, 2), round(y, 2)) for x, y in (c, p0, p1))  # clicks, not microns
    d = make_calibrated_profile(base_d, c, p0, p1, image=image_path.name,
                                clockwise=bool(clockwise))
    ok, png = cv2.imencode(".png", cv2.cvtColor(image_rgb, cv2.COLOR_RGB2BGR))
    if not ok:
        raise ValueError("the frozen frame could not be encoded as PNG")

    profile_path.parent.mkdir(parents=True, exist_ok=True)
    write_atomic(image_path, png.tobytes())
    load_profile(d, base_dir=profile_path.parent)  # the reference image must load too
    write_atomic(profile_path, (json.dumps(d, indent=2) + "\n").encode("utf-8"))
    point.profile = rel
    save_route(route, route_path)
    log.info("calibrated %s of %s: %s", point_name, route_path.name, profile_path)
    return PointCalibration(point_name, route_path, profile_path, image_path, rel)


def suggest_points(image_rgb: np.ndarray, base: GaugeProfile) -> tuple[XY, XY, XY] | None:
    """The pivot and the two scale ends the uncalibrated reader finds on the frame, as a
    starting point for the operator's clicks; None when it finds no dial or no ends."""
    try:
        r = read_gauge(cv2.cvtColor(image_rgb, cv2.COLOR_RGB2BGR), base)
    except Exception as e:  # noqa: BLE001 - a suggestion is optional; never a crash
        log.warning("no point suggestion: %s", e)
        return None
    if r.dial_centre_xy is None or r.scale_ends_xy is None:
        return None
    (x0, y0), (x1, y1) = r.scale_ends_xy
    cx, cy = r.dial_centre_xy
    return (float(cx), float(cy)), (float(x0), float(y0)), (float(x1), float(y1))

"""Gauge profiles: the angle form, the tick-table form (Table 1), validation, calibration."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .geometry import fit_circle
from .interpolate import eq21_reading

__all__ = [
    "Calibration",
    "GaugeProfile",
    "calibrate_profile",
    "load_profile",
    "make_calibrated_profile",
    "save_profile",
]

_REQUIRED = ("name", "unit", "min_value", "max_value", "min_angle_deg", "max_angle_deg")
NEEDLES = ("single", "two-ended")
# hue ranges (OpenCV's 0..180 hue) of the colours a set-point pointer may have
COLOUR_HUES: dict[str, tuple[tuple[int, int], ...]] = {
    "red": ((0, 10), (165, 180)),
    "orange": ((8, 22),),
    "yellow": ((20, 36),),
    "green": ((36, 88),),
    "blue": ((88, 132),),
}


@dataclass(frozen=True)
class Calibration:
    """The operator's three clicks: the needle's pivot and the scale's two end marks.

    Pixel coordinates in the reference image ``image_path`` (absolute), or, when it is
    None, in the coordinates of the image being read.  ``image`` is the path as written in
    the profile (relative to the profile file).  ``clockwise``: values rise clockwise in
    the image; the scale arc runs from ``min_point`` to ``max_point`` in that direction.
    """

    center: tuple[float, float]
    min_point: tuple[float, float]
    max_point: tuple[float, float]
    image_path: Path | None = None
    clockwise: bool = True
    image: str | None = None

    @property
    def radius_px(self) -> float:
        """Mean distance of the end marks from the pivot (the scale ring's radius)."""
        cx, cy = self.center
        return 0.5 * (math.hypot(self.min_point[0] - cx, self.min_point[1] - cy)
                      + math.hypot(self.max_point[0] - cx, self.max_point[1] - cy))

    def image_angles(self) -> tuple[float, float, float]:
        """(min angle, max angle, span) in the image, degrees clockwise from up; the max
        angle is unwrapped so that max - min runs along the scale (negative if anticlockwise)."""
        a0 = _angle_cw(self.center, self.min_point)
        a1 = _angle_cw(self.center, self.max_point)
        span = (a1 - a0) % 360.0 if self.clockwise else (a0 - a1) % 360.0
        return a0, a0 + span if self.clockwise else a0 - span, span

    def to_dict(self) -> dict:
        d = {"center": list(self.center), "min_point": list(self.min_point),
             "max_point": list(self.max_point)}
        if self.image is not None:
            d["image"] = self.image
        d["clockwise"] = self.clockwise
        return d


def _angle_cw(c, p) -> float:
    return math.degrees(math.atan2(p[0] - c[0], -(p[1] - c[1])))


@dataclass(frozen=True)
class GaugeProfile:
    """A validated gauge profile.

    Angles are degrees clockwise from 12 o'clock on the upright dial.  ``min_angle_deg`` is
    where the minimum value lies; if ``max_angle_deg`` is smaller the scale runs
    counter-clockwise.  ``ticks`` (optional) is the paper's tick table: (value, x, y) on a
    ``dial_size`` square template, read with eq. 21.
    """

    name: str
    unit: str
    min_value: float
    max_value: float
    min_angle_deg: float
    max_angle_deg: float
    normal_min: float | None = None
    normal_max: float | None = None
    ticks: tuple[tuple[float, float, float], ...] | None = None
    dial_size: int = 300
    # derived from the tick table: scale-circle centre (m, n) and radius r (eq. 20)
    table_centre: tuple[float, float] | None = None
    table_radius: float | None = None
    calibration: Calibration | None = None
    needle: str = "single"  # "single" or "two-ended"
    ignore_colour: str | None = None  # a pointer of this colour is not the needle
    angles_given: bool = True  # False: the angles were derived (calibration or tick table)

    @property
    def span_deg(self) -> float:
        return abs(self.max_angle_deg - self.min_angle_deg)

    @property
    def clockwise(self) -> bool:
        return self.max_angle_deg > self.min_angle_deg

    @property
    def full_scale(self) -> float:
        return self.max_value - self.min_value

    def in_normal_band(self, value: float) -> bool | None:
        """Whether ``value`` lies in the normal band; None when the profile has no band."""
        if self.normal_min is None and self.normal_max is None:
            return None
        lo = self.normal_min if self.normal_min is not None else -math.inf
        hi = self.normal_max if self.normal_max is not None else math.inf
        return bool(lo <= value <= hi)

    def value_at_fraction(self, f: float) -> float:
        """Value at fraction ``f`` (0 at the minimum mark, 1 at the maximum) of the arc."""
        f = min(max(f, 0.0), 1.0)
        if self.ticks:
            ang = self.min_angle_deg + f * (self.max_angle_deg - self.min_angle_deg)
            return self.value_at_angle(ang)
        return self.min_value + f * (self.max_value - self.min_value)

    def value_at_angle(self, angle_deg: float) -> float:
        """Value for an upright-dial angle; the tick-table form uses eq. 21 on the template."""
        if self.ticks:
            m, n = self.table_centre
            r = self.table_radius
            a = math.radians(angle_deg)
            p = (m + r * math.sin(a), n - r * math.cos(a))
            xy = [(x, y) for _, x, y in self.ticks]
            vals = [v for v, _, _ in self.ticks]
            v, *_ = eq21_reading(p, xy, vals)
            return float(min(max(v, self.min_value), self.max_value))
        f = (angle_deg - self.min_angle_deg) / (self.max_angle_deg - self.min_angle_deg)
        return self.value_at_fraction(f)

    def to_dict(self) -> dict:
        d = {k: getattr(self, k) for k in _REQUIRED}
        if not self.angles_given:
            del d["min_angle_deg"], d["max_angle_deg"]
        if self.normal_min is not None:
            d["normal_min"] = self.normal_min
        if self.normal_max is not None:
            d["normal_max"] = self.normal_max
        if self.ticks:
            d["dial_size"] = self.dial_size
            d["ticks"] = [{"value": v, "x": x, "y": y} for v, x, y in self.ticks]
        if self.calibration is not None:
            d["calibration"] = self.calibration.to_dict()
        if self.needle != "single":
            d["needle"] = self.needle
        if self.ignore_colour is not None:
            d["ignore_colour"] = self.ignore_colour
        return d


def _num(d: dict, key: str, where: str) -> float:
    v = d.get(key)
    if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
        raise ValueError(f"{where}: '{key}' must be a finite number, got {v!r}")
    return float(v)


def _point(c: dict, key: str, where: str) -> tuple[float, float]:
    v = c.get(key)
    if (not isinstance(v, list | tuple) or len(v) != 2
            or any(isinstance(x, bool) or not isinstance(x, int | float) or not math.isfinite(x)
                   for x in v)):
        raise ValueError(f"{where}: calibration '{key}' must be [x, y] (two finite numbers), "
                         f"got {v!r}")
    return float(v[0]), float(v[1])


def _calibration(d: dict, where: str, base_dir, check_image: bool) -> Calibration:
    """Validate the ``calibration`` object (see docs/gauge-profiles.md)."""
    c = d["calibration"]
    if not isinstance(c, dict):
        raise ValueError(f"{where}: 'calibration' must be an object")
    unknown = set(c) - {"center", "min_point", "max_point", "image", "clockwise"}
    if unknown:
        raise ValueError(f"{where}: unknown calibration field(s) {sorted(unknown)}")
    centre = _point(c, "center", where)
    p0, p1 = _point(c, "min_point", where), _point(c, "max_point", where)
    r0 = math.hypot(p0[0] - centre[0], p0[1] - centre[1])
    r1 = math.hypot(p1[0] - centre[0], p1[1] - centre[1])
    if min(r0, r1) < 8.0:
        raise ValueError(f"{where}: calibration end marks must lie at least 8 px from the "
                         f"center (min {r0:.1f} px, max {r1:.1f} px)")
    if max(r0, r1) > 3.0 * min(r0, r1):
        raise ValueError(f"{where}: calibration end marks are at very different distances "
                         f"from the center ({r0:.1f} and {r1:.1f} px)")
    if math.hypot(p0[0] - p1[0], p0[1] - p1[1]) < 3.0:
        raise ValueError(f"{where}: calibration min_point and max_point coincide")
    cw = c.get("clockwise")
    has_angles = "min_angle_deg" in d and "max_angle_deg" in d
    if cw is not None and not isinstance(cw, bool):
        raise ValueError(f"{where}: calibration 'clockwise' must be true or false")
    if has_angles:
        a0, a1 = _num(d, "min_angle_deg", where), _num(d, "max_angle_deg", where)
        if cw is not None and cw != (a1 > a0):
            raise ValueError(f"{where}: calibration 'clockwise' ({cw}) contradicts the "
                             f"angles (min_angle_deg {a0:g}, max_angle_deg {a1:g})")
        cw = a1 > a0
    image = c.get("image")
    path = None
    if image is not None:
        if not isinstance(image, str) or not image:
            raise ValueError(f"{where}: calibration 'image' must be a non-empty path string")
        path = Path(image)
        if not path.is_absolute():
            path = Path(base_dir if base_dir is not None else Path.cwd()) / path
        path = path.resolve()
        if check_image:
            from .register import reference_image  # decoded once, cached by mtime
            try:
                reference_image(path)
            except ValueError as e:
                raise ValueError(f"{where}: {e}") from None
    cal = Calibration(centre, p0, p1, path, True if cw is None else cw, image)
    span = cal.image_angles()[2]
    if not 10.0 <= span <= 358.0:
        raise ValueError(f"{where}: the calibrated scale must span 10..358 degrees "
                         f"({'clockwise' if cal.clockwise else 'anticlockwise'} from "
                         f"min_point to max_point), got {span:.1f}")
    return cal


def load_profile(src, base_dir=None, *, check_image: bool = True) -> GaugeProfile:
    """Load and validate a profile from a path, a JSON string path, a dict or a GaugeProfile.

    A calibration's reference ``image`` is resolved relative to the profile file (for a
    path) or to ``base_dir`` (for a dict; default: the current directory); it must exist
    and decode unless ``check_image`` is False.  Raises ValueError with a message naming
    the problem (missing field, bad number, empty range, unreadable file or reference
    image, tick table out of order ...).
    """
    if isinstance(src, GaugeProfile):
        return src
    where = "profile"
    if isinstance(src, str | Path):
        where = str(src)
        if base_dir is None:
            base_dir = Path(src).resolve().parent
        try:
            d = json.loads(Path(src).read_text(encoding="utf-8"))
        except FileNotFoundError as e:
            raise ValueError(f"{where}: no such profile file") from e
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
            raise ValueError(f"{where}: not a readable JSON profile ({e})") from e
    else:
        d = src
    if not isinstance(d, dict):
        raise ValueError(f"{where}: a profile must be a JSON object")
    ticks = d.get("ticks")
    for key in ("name", "unit", "min_value", "max_value"):
        if key not in d:
            raise ValueError(f"{where}: missing field '{key}'")
    if not isinstance(d["name"], str) or not d["name"]:
        raise ValueError(f"{where}: 'name' must be a non-empty string")
    if not isinstance(d["unit"], str):
        raise ValueError(f"{where}: 'unit' must be a string")
    vmin, vmax = _num(d, "min_value", where), _num(d, "max_value", where)
    if not vmax > vmin:
        raise ValueError(f"{where}: 'max_value' ({vmax}) must exceed 'min_value' ({vmin})")
    needle = d.get("needle", "single")
    if needle not in NEEDLES:
        raise ValueError(f"{where}: 'needle' must be one of {list(NEEDLES)}, got {needle!r}")
    ignore = d.get("ignore_colour")
    if ignore is not None and ignore not in COLOUR_HUES:
        raise ValueError(f"{where}: 'ignore_colour' must be one of {sorted(COLOUR_HUES)}, "
                         f"got {ignore!r}")
    cal = None
    if d.get("calibration") is not None:
        cal = _calibration(d, where, base_dir, check_image)
    has_angles = "min_angle_deg" in d and "max_angle_deg" in d
    angles_given = has_angles
    table = None
    centre = radius = None
    size = 300
    if ticks is not None:
        if not isinstance(ticks, list) or len(ticks) < 3:
            raise ValueError(f"{where}: 'ticks' must be a list of at least 3 ticks")
        try:
            table = tuple((float(t["value"]), float(t["x"]), float(t["y"])) for t in ticks)
        except (TypeError, KeyError, ValueError) as e:
            raise ValueError(f"{where}: each tick needs numeric 'value', 'x', 'y'") from e
        vals = [t[0] for t in table]
        if any(b <= a for a, b in zip(vals, vals[1:], strict=False)):
            raise ValueError(f"{where}: tick values must increase strictly")
        if abs(vals[0] - vmin) > 1e-9 or abs(vals[-1] - vmax) > 1e-9:
            raise ValueError(f"{where}: the tick table must run from min_value to max_value")
        size = int(d.get("dial_size", 300))
        m, n, r, _ = fit_circle([(x, y) for _, x, y in table])
        centre, radius = (m, n), r
        angs = np.degrees(np.arctan2([x - m for _, x, y in table], [n - y for _, x, y in table]))
        angs = np.unwrap(np.radians(angs))
        angs = np.degrees(angs)
        if not (np.all(np.diff(angs) > 0) or np.all(np.diff(angs) < 0)):
            raise ValueError(f"{where}: tick positions must go round the dial in one direction")
        if not has_angles:
            a0 = float(angs[0])
            a0 = (a0 + 180) % 360 - 180
            d = dict(d, min_angle_deg=a0, max_angle_deg=a0 + float(angs[-1] - angs[0]))
            angles_given = cal is None  # written back as before (the table's own angles)
    elif not has_angles and cal is not None:
        a0, a1, _ = cal.image_angles()  # the calibrated arc as seen in the image
        d = dict(d, min_angle_deg=a0, max_angle_deg=a1)
    elif not has_angles:
        raise ValueError(f"{where}: missing 'min_angle_deg'/'max_angle_deg' (or a 'ticks' table"
                         " or a 'calibration')")
    a0, a1 = _num(d, "min_angle_deg", where), _num(d, "max_angle_deg", where)
    span = abs(a1 - a0)
    if not 10.0 <= span <= (358.0 if cal is not None else 355.0):
        raise ValueError(f"{where}: the scale must span 10..355 degrees, got {span:g}")
    nmin = d.get("normal_min")
    nmax = d.get("normal_max")
    if nmin is not None:
        nmin = _num(d, "normal_min", where)
    if nmax is not None:
        nmax = _num(d, "normal_max", where)
    if nmin is not None and nmax is not None and nmin > nmax:
        raise ValueError(f"{where}: 'normal_min' exceeds 'normal_max'")
    return GaugeProfile(
        name=d["name"], unit=d["unit"], min_value=vmin, max_value=vmax, min_angle_deg=a0,
        max_angle_deg=a1, normal_min=nmin, normal_max=nmax, ticks=table, dial_size=size,
        table_centre=centre, table_radius=radius, calibration=cal, needle=needle,
        ignore_colour=ignore, angles_given=angles_given or cal is None,
    )


def save_profile(profile, path) -> Path:
    """Validate and write a profile as JSON; returns the path.

    A calibration's reference image is resolved relative to the file written, so it must
    already be in place there (write the reference frame first)."""
    path = Path(path)
    p = load_profile(profile.to_dict() if isinstance(profile, GaugeProfile) else profile,
                     base_dir=path.resolve().parent)
    path.parent.mkdir(parents=True, exist_ok=True)
    d = p.to_dict()
    ticks = d.pop("ticks", None)
    text = json.dumps(d, indent=2)
    if ticks:  # one tick per line keeps Table 1 readable beside the paper
        rows = ",\n".join("    " + json.dumps(t) for t in ticks)
        text = text[:-2] + ',\n  "ticks": [\n' + rows + "\n  ]\n}"
    path.write_text(text + "\n", encoding="utf-8")
    return path


def calibrate_profile(
    centre_xy,
    min_tick_xy,
    max_tick_xy,
    min_value: float,
    max_value: float,
    name: str,
    unit: str,
    *,
    clockwise: bool = True,
    normal_min: float | None = None,
    normal_max: float | None = None,
    image_roll_deg: float = 0.0,
) -> dict:
    """An angle-form profile from one upright photo with centre, min and max tick marked.

    The angles are measured around the marked centre, clockwise from the image's up
    direction (minus ``image_roll_deg`` if the photo was rolled); the scale runs clockwise
    from the minimum tick unless ``clockwise`` is False.  Returns a validated profile dict.
    """
    cx, cy = centre_xy

    def ang(p):
        return math.degrees(math.atan2(p[0] - cx, -(p[1] - cy))) - image_roll_deg

    a0 = (ang(min_tick_xy) + 180) % 360 - 180
    a1 = ang(max_tick_xy)
    if math.hypot(min_tick_xy[0] - cx, min_tick_xy[1] - cy) < 1 or math.hypot(
            max_tick_xy[0] - cx, max_tick_xy[1] - cy) < 1:
        raise ValueError("the tick marks must lie away from the centre")
    if clockwise:
        span = (a1 - a0) % 360
        a1 = a0 + span
    else:
        span = (a0 - a1) % 360
        a1 = a0 - span
    d = {
        "name": name, "unit": unit, "min_value": float(min_value), "max_value": float(max_value),
        "min_angle_deg": round(a0, 3), "max_angle_deg": round(a1, 3),
    }
    if normal_min is not None:
        d["normal_min"] = float(normal_min)
    if normal_max is not None:
        d["normal_max"] = float(normal_max)
    load_profile(d)
    return d


def make_calibrated_profile(base: dict, center, min_point, max_point, *, image=None,
                            clockwise: bool = True) -> dict:
    """A calibrated profile dict from a base profile and the operator's three clicks.

    ``base`` holds name, unit, min_value, max_value and optionally the normal band, a tick
    table, ``needle`` and ``ignore_colour``; its angles, if any, are dropped (the clicks
    define the arc).  ``image`` is the reference frame's path relative to the profile file
    that will be written (it is not checked here).  Returns a validated dict.
    """
    if not isinstance(base, dict):
        raise ValueError("the base profile must be a dict")
    d = {k: v for k, v in base.items()
         if k not in ("min_angle_deg", "max_angle_deg", "calibration")}
    cal = {}
    for key, pt in (("center", center), ("min_point", min_point), ("max_point", max_point)):
        try:
            cal[key] = [float(v) for v in pt]
        except (TypeError, ValueError) as e:
            raise ValueError(f"calibration '{key}' must be [x, y], got {pt!r}") from e
    if image is not None:
        cal["image"] = str(image)
    cal["clockwise"] = bool(clockwise)
    d["calibration"] = cal
    load_profile(d, check_image=False)
    return d

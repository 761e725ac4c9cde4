"""Gauge profiles: the angle form, the tick-table form (Table 1), validation, calibration."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .geometry import fit_circle
from .interpolate import eq21_reading

__all__ = ["GaugeProfile", "calibrate_profile", "load_profile", "save_profile"]

_REQUIRED = ("name", "unit", "min_value", "max_value", "min_angle_deg", "max_angle_deg")


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

    @property
    def span_deg(self) -> float:
        return abs(self.max_angle_deg - self.min_angle_deg)

    @property
    def clockwise(self) -> bool:
        return self.max_angle_deg > self.min_angle_deg

    @property
    def full_scale(self) -> float:
        return self.max_value - self.min_value

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
        if self.normal_min is not None:
            d["normal_min"] = self.normal_min
        if self.normal_max is not None:
            d["normal_max"] = self.normal_max
        if self.ticks:
            d["dial_size"] = self.dial_size
            d["ticks"] = [{"value": v, "x": x, "y": y} for v, x, y in self.ticks]
        return d


def _num(d: dict, key: str, where: str) -> float:
    v = d.get(key)
    if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
        raise ValueError(f"{where}: '{key}' must be a finite number, got {v!r}")
    return float(v)


def load_profile(src) -> GaugeProfile:
    """Load and validate a profile from a path, a JSON string path, a dict or a GaugeProfile.

    Raises ValueError with a message naming the problem (missing field, bad number, empty
    range, unreadable file, tick table out of order ...).
    """
    if isinstance(src, GaugeProfile):
        return src
    where = "profile"
    if isinstance(src, str | Path):
        where = str(src)
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
    has_angles = "min_angle_deg" in d and "max_angle_deg" in d
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
    elif not has_angles:
        raise ValueError(f"{where}: missing 'min_angle_deg'/'max_angle_deg' (or a 'ticks' table)")
    a0, a1 = _num(d, "min_angle_deg", where), _num(d, "max_angle_deg", where)
    span = abs(a1 - a0)
    if not 10.0 <= span <= 355.0:
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
        table_centre=centre, table_radius=radius,
    )


def save_profile(profile, path) -> Path:
    """Validate and write a profile as JSON; returns the path."""
    p = load_profile(profile.to_dict() if isinstance(profile, GaugeProfile) else profile)
    path = Path(path)
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

"""Patrol routes: a JSON file (schema in docs/patrol.md) of named points to visit.

```json
{"name": "default",
 "points": [{"name": "CG-301", "kind": "meter", "x_m": 58.6, "y_m": 35.0,
             "gauge": "CG-301", "dwell_s": 4.0}, ...]}
```

``kind`` is meter | tank_wall | valve | waypoint; ``gauge`` names a gauge of the
station (meter points need one); ``dwell_s`` is sim time spent inspecting.
An optional ``heading_rad`` fixes the heading to inspect from; otherwise a
point with a gauge faces the gauge and a tank wall faces the nearest tank.
``profile`` (the desk's calibrated gauge profile of the point, see
app/core/inspection_points.py) is the desk's business: accepted and ignored here, so a
route file the desk calibrated stays a route the robot runs.
Every problem is a ValueError that names the point and the field.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from .config import RESOURCES

ROUTES_DIR = RESOURCES / "routes"
DEFAULT_ROUTE = ROUTES_DIR / "default.json"
KINDS = ("meter", "tank_wall", "valve", "waypoint")
MAX_POINTS = 200
MAX_DWELL_S = 600.0


@dataclass
class RoutePoint:
    name: str
    kind: str
    x_m: float
    y_m: float
    gauge: str | None = None
    dwell_s: float = 0.0
    heading_rad: float | None = None


@dataclass
class Route:
    name: str
    points: list[RoutePoint]

    def to_dict(self) -> dict[str, Any]:
        out = []
        for p in self.points:
            d = asdict(p)
            if d["heading_rad"] is None:
                del d["heading_rad"]
            out.append(d)
        return {"name": self.name, "points": out}


def _number(obj: dict, key: str, where: str, default: float | None = None) -> float:
    if key not in obj:
        if default is not None:
            return default
        raise ValueError(f"{where}: missing {key!r}")
    v = obj[key]
    if isinstance(v, bool) or not isinstance(v, int | float):
        raise ValueError(f"{where}: {key!r} must be a number, not {v!r}")
    if not math.isfinite(v):
        raise ValueError(f"{where}: {key!r} must be finite, not {v!r}")
    return float(v)


def parse_route(obj: Any, gauges: set[str] | None = None,
                size_m: tuple[float, float] | None = None) -> Route:
    """Validate a route object (as decoded from JSON). ``gauges``: the station's
    gauge ids (checked when given); ``size_m``: the map's extent (points must lie
    inside). Raises ValueError with a message that names what is wrong."""
    if not isinstance(obj, dict):
        raise ValueError(f"a route must be a JSON object, not {type(obj).__name__}")
    unknown = set(obj) - {"name", "points"}
    if unknown:
        raise ValueError(f"route: unknown field(s) {sorted(unknown)}")
    name = obj.get("name")
    if not isinstance(name, str) or not name.strip():
        raise ValueError("route: 'name' must be a non-empty string")
    pts = obj.get("points")
    if not isinstance(pts, list) or not pts:
        raise ValueError(f"route {name!r}: 'points' must be a non-empty list")
    if len(pts) > MAX_POINTS:
        raise ValueError(f"route {name!r}: {len(pts)} points, at most {MAX_POINTS}")
    out: list[RoutePoint] = []
    seen: set[str] = set()
    for i, p in enumerate(pts):
        where = f"route {name!r} point {i}"
        if not isinstance(p, dict):
            raise ValueError(f"{where}: must be an object")
        unknown = set(p) - {"name", "kind", "x_m", "y_m", "gauge", "dwell_s", "heading_rad",
                            "profile"}
        if unknown:
            raise ValueError(f"{where}: unknown field(s) {sorted(unknown)}")
        pname = p.get("name")
        if not isinstance(pname, str) or not pname.strip():
            raise ValueError(f"{where}: 'name' must be a non-empty string")
        where = f"route {name!r} point {i} ({pname})"
        if pname in seen:
            raise ValueError(f"{where}: duplicate point name")
        seen.add(pname)
        kind = p.get("kind")
        if kind not in KINDS:
            raise ValueError(f"{where}: 'kind' must be one of {', '.join(KINDS)}, not {kind!r}")
        x = _number(p, "x_m", where)
        y = _number(p, "y_m", where)
        if size_m is not None and not (0.0 <= x <= size_m[0] and 0.0 <= y <= size_m[1]):
            raise ValueError(f"{where}: ({x}, {y}) lies outside the "
                             f"{size_m[0]:g} x {size_m[1]:g} m map")
        gauge = p.get("gauge")
        if gauge is not None and not isinstance(gauge, str):
            raise ValueError(f"{where}: 'gauge' must be a gauge id string or null")
        if kind == "meter" and not gauge:
            raise ValueError(f"{where}: a meter point needs a 'gauge'")
        if gauge and gauges is not None and gauge not in gauges:
            raise ValueError(f"{where}: no gauge {gauge!r} in this station "
                             f"(known: {', '.join(sorted(gauges))})")
        dwell = _number(p, "dwell_s", where, 0.0)
        if not 0.0 <= dwell <= MAX_DWELL_S:
            raise ValueError(f"{where}: 'dwell_s' must be 0..{MAX_DWELL_S:g} s, not {dwell}")
        heading = None
        if p.get("heading_rad") is not None:
            heading = _number(p, "heading_rad", where)
        out.append(RoutePoint(pname, kind, x, y, gauge or None, dwell, heading))
    return Route(name.strip(), out)


def load_route(path: str | Path, gauges: set[str] | None = None,
               size_m: tuple[float, float] | None = None) -> Route:
    path = Path(path)
    try:
        obj = json.loads(path.read_text(encoding="utf-8"))
    except OSError as e:
        raise ValueError(f"cannot read route file {path}: {e}") from None
    except json.JSONDecodeError as e:
        raise ValueError(f"route file {path} is not JSON: {e}") from None
    return parse_route(obj, gauges, size_m)

"""Patrol route files: load, validate, save (no Qt).

The one schema and parser of route files, for both processes: the desk reads and
writes routes here, and the robot reads them through here too
(:mod:`sim_robot.route` adds only the station's checks: known gauge ids, the
map's extent). The schema and its rules — fields, limits, what happens to
unknown keys and blank gauges, how points are numbered in messages — are written
down once, in docs/patrol.md ("Route files"); :data:`ROUTE_KEYS` and
:data:`POINT_KEYS` are the keys it names. Every problem is a :class:`ValueError`
that names the point and field.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath, PureWindowsPath
from typing import Any

__all__ = ["KINDS", "MAX_DWELL_S", "MAX_POINTS", "POINT_KEYS", "ROUTE_KEYS", "Route",
           "RoutePoint", "check_relative_path", "dumps", "load_route", "loads",
           "route_from_dict", "route_to_dict", "save_route", "write_atomic"]

KINDS: tuple[str, ...] = ("meter", "tank_wall", "valve", "waypoint")
MAX_POINTS = 200
MAX_DWELL_S = 600.0
# the keys the schema names; any other key is ignored on reading and dropped on writing
ROUTE_KEYS: tuple[str, ...] = ("name", "points")
POINT_KEYS: tuple[str, ...] = ("name", "kind", "x_m", "y_m", "gauge", "dwell_s", "heading_rad",
                               "profile")


@dataclass
class RoutePoint:
    name: str
    kind: str = "waypoint"
    x_m: float = 0.0
    y_m: float = 0.0
    gauge: str | None = None
    dwell_s: float = 0.0
    heading_rad: float | None = None  # optional: the heading to inspect from
    profile: str | None = None  # optional: calibrated profile, relative to the route file

    def to_dict(self) -> dict[str, Any]:
        d: dict[str, Any] = {"name": self.name, "kind": self.kind, "x_m": float(self.x_m),
                             "y_m": float(self.y_m), "gauge": self.gauge,
                             "dwell_s": float(self.dwell_s)}
        if self.heading_rad is not None:
            d["heading_rad"] = float(self.heading_rad)
        if self.profile is not None:
            d["profile"] = self.profile
        return d


@dataclass
class Route:
    name: str = "route"
    points: list[RoutePoint] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        return route_to_dict(self)

    def names(self) -> list[str]:
        return [p.name for p in self.points]

    def unique_name(self, stem: str = "P") -> str:
        """A point name not used yet: ``P1``, ``P2``, ..."""
        used = set(self.names())
        i = len(self.points) + 1
        while f"{stem}{i}" in used:
            i += 1
        return f"{stem}{i}"

    def validate(self) -> None:
        """Raise ValueError when the route would not survive a save/load."""
        route_from_dict(route_to_dict(self))


def _number(v: Any, where: str, key: str) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise ValueError(f"{where}: {key!r} must be a number, got {type(v).__name__}")
    f = float(v)
    if not math.isfinite(f):
        raise ValueError(f"{where}: {key!r} must be finite, got {v}")
    return f


def check_relative_path(v: Any, what: str = "path") -> str:
    """``v`` as a relative POSIX path that stays below its base folder; ValueError says why
    not (not a string, empty, absolute, a drive, a backslash, or a ``..`` component)."""
    if not isinstance(v, str):
        raise ValueError(f"{what} must be a string, got {type(v).__name__}")
    if not v.strip() or v != v.strip():
        raise ValueError(f"{what} must be a non-empty path without surrounding spaces")
    if "\\" in v or "\0" in v:
        raise ValueError(f"{what} {v!r}: use '/' between folders (no backslash or NUL)")
    p = PurePosixPath(v)
    if p.is_absolute() or PureWindowsPath(v).drive:
        raise ValueError(f"{what} {v!r} must be relative to the route file's folder")
    if any(part == ".." for part in p.parts):
        raise ValueError(f"{what} {v!r} must not climb out of the route's folder ('..')")
    if not p.parts or p.name in ("", "."):
        raise ValueError(f"{what} {v!r} does not name a file")
    return v


def _point_from_dict(obj: Any, i: int) -> RoutePoint:
    where = f"point {i + 1}"
    if not isinstance(obj, dict):
        raise ValueError(f"{where}: must be an object, got {type(obj).__name__}")
    name = obj.get("name")
    if isinstance(name, str) and name.strip():
        where = f"point {i + 1} ({name!r})"
    missing = [k for k in ("name", "kind", "x_m", "y_m") if k not in obj]
    if missing:
        raise ValueError(f"{where}: missing field{'s' if len(missing) > 1 else ''} "
                         + ", ".join(repr(k) for k in missing))
    if not isinstance(name, str) or not name.strip():
        raise ValueError(f"{where}: 'name' must be a non-empty string")
    kind = obj["kind"]
    if not isinstance(kind, str) or kind not in KINDS:
        raise ValueError(f"{where}: 'kind' must be one of {', '.join(KINDS)}; got {kind!r}")
    x = _number(obj["x_m"], where, "x_m")
    y = _number(obj["y_m"], where, "y_m")
    gauge = obj.get("gauge")
    if gauge is not None and not isinstance(gauge, str):
        raise ValueError(f"{where}: 'gauge' must be a string or null, "
                         f"got {type(gauge).__name__}")
    if isinstance(gauge, str) and not gauge.strip():
        gauge = None
    dwell = _number(obj.get("dwell_s", 0.0), where, "dwell_s")
    if not 0.0 <= dwell <= MAX_DWELL_S:
        raise ValueError(f"{where}: 'dwell_s' must be 0..{MAX_DWELL_S:g} s, got {dwell}")
    if kind == "meter" and gauge is None:
        raise ValueError(f"{where}: a meter point needs a 'gauge'")
    heading = obj.get("heading_rad")
    if heading is not None:
        heading = _number(heading, where, "heading_rad")
    profile = obj.get("profile")
    if profile is not None:
        profile = check_relative_path(profile, f"{where}: 'profile'")
        if gauge is None:
            raise ValueError(f"{where}: a 'profile' needs the point's 'gauge'")
    return RoutePoint(name.strip(), kind, x, y, gauge, dwell, heading, profile)


def route_from_dict(obj: Any) -> Route:
    """Validate a parsed route object and build a :class:`Route`."""
    if not isinstance(obj, dict):
        raise ValueError(f"a route must be a JSON object, got {type(obj).__name__}")
    if "name" not in obj:
        raise ValueError("route: missing field 'name'")
    if not isinstance(obj["name"], str) or not obj["name"].strip():
        raise ValueError("route: 'name' must be a non-empty string")
    if "points" not in obj:
        raise ValueError("route: missing field 'points'")
    pts = obj["points"]
    if not isinstance(pts, list):
        raise ValueError(f"route: 'points' must be a list, got {type(pts).__name__}")
    if not pts:
        raise ValueError("route: empty route (no points)")
    if len(pts) > MAX_POINTS:
        raise ValueError(f"route: {len(pts)} points, at most {MAX_POINTS}")
    points = [_point_from_dict(p, i) for i, p in enumerate(pts)]
    seen: set[str] = set()
    for p in points:
        if p.name in seen:
            raise ValueError(f"route: duplicate point name {p.name!r}")
        seen.add(p.name)
    return Route(obj["name"].strip(), points)


def route_to_dict(route: Route) -> dict[str, Any]:
    return {"name": route.name, "points": [p.to_dict() for p in route.points]}


def loads(text: str | bytes) -> Route:
    try:
        obj = json.loads(text)
    except (json.JSONDecodeError, UnicodeDecodeError) as e:
        raise ValueError(f"not valid JSON: {e}") from None
    return route_from_dict(obj)


def dumps(route: Route) -> str:
    route.validate()
    return json.dumps(route_to_dict(route), indent=2) + "\n"


def load_route(path: str | os.PathLike) -> Route:
    """Read and validate a route file; ValueError (naming the file) on any problem."""
    p = Path(path)
    try:
        data = p.read_bytes()
    except OSError as e:
        raise ValueError(f"{p}: cannot read: {e.strerror or e}") from None
    try:
        return loads(data)
    except ValueError as e:
        raise ValueError(f"{p.name}: {e}") from None


def save_route(route: Route, path: str | os.PathLike) -> None:
    """Validate and write atomically (a temporary file renamed over the target)."""
    write_atomic(path, dumps(route).encode("utf-8"))


def write_atomic(path: str | os.PathLike, data: bytes) -> None:
    """Write ``data`` to a temporary file beside ``path``, flush it to disk and rename it
    over ``path``: a reader sees the old file or the new one, never a part."""
    p = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{p.name}.", suffix=".tmp", dir=p.parent or ".")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, p)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise

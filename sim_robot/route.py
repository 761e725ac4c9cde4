"""Patrol routes at the robot: the desk's route files, plus the station's checks.

The schema, its rules and its parser are :mod:`app.core.route`'s (documented in
docs/patrol.md, "Route files"); the desk and the robot read a file with the same
code, so they accept and refuse the same files with the same message — unknown
keys ignored, a blank gauge read as none, points numbered from 1. The robot adds
what only it knows:

- every ``gauge`` names a gauge of the station (``gauges``, when given);
- every point lies inside the map (``size_m``, when given).

(The mission executor then refuses a point the robot cannot stand on.)
Every problem is a ValueError that names the point and the field.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from app.core import route as _route
from app.core.route import KINDS, MAX_DWELL_S, MAX_POINTS, Route, RoutePoint

from .config import RESOURCES

__all__ = ["DEFAULT_ROUTE", "KINDS", "MAX_DWELL_S", "MAX_POINTS", "ROUTES_DIR", "Route",
           "RoutePoint", "check_station", "load_route", "parse_route"]

ROUTES_DIR = RESOURCES / "routes"
DEFAULT_ROUTE = ROUTES_DIR / "default.json"


def check_station(route: Route, gauges: set[str] | None = None,
                  size_m: tuple[float, float] | None = None) -> Route:
    """Refuse a point whose gauge the station lacks (``gauges``) or that lies
    outside the ``size_m`` map; return ``route`` unchanged."""
    for i, p in enumerate(route.points):
        where = f"point {i + 1} ({p.name!r})"  # numbered as app.core.route numbers them
        if size_m is not None and not (0.0 <= p.x_m <= size_m[0] and 0.0 <= p.y_m <= size_m[1]):
            raise ValueError(f"{where}: ({p.x_m:g}, {p.y_m:g}) lies outside the "
                             f"{size_m[0]:g} x {size_m[1]:g} m map")
        if p.gauge is not None and gauges is not None and p.gauge not in gauges:
            raise ValueError(f"{where}: no gauge {p.gauge!r} in this station "
                             f"(known: {', '.join(sorted(gauges))})")
    return route


def parse_route(obj: Any, gauges: set[str] | None = None,
                size_m: tuple[float, float] | None = None) -> Route:
    """A route object (as decoded from JSON) checked by the shared parser, then
    against the station: ``gauges`` its gauge ids, ``size_m`` the map's extent."""
    return check_station(_route.route_from_dict(obj), gauges, size_m)


def load_route(path: str | os.PathLike, gauges: set[str] | None = None,
               size_m: tuple[float, float] | None = None) -> Route:
    """Read a route file (the shared reader: its errors name the file), then the
    station checks; their errors name the file too."""
    route = _route.load_route(path)
    try:
        return check_station(route, gauges, size_m)
    except ValueError as e:
        raise ValueError(f"{Path(path).name}: {e}") from None

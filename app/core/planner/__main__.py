"""Plan on a map from the command line.

    python -m app.core.planner plan --map MAP START GOAL [--algo jps] [--inflate 0.35]

MAP is a Moving AI ``.map`` or a ROS map_server ``.yaml``. START and GOAL are
``ROW,COL`` cells, or ``X,Y`` in metres with ``--metres``. Prints one JSON object:
``{"found", "length_cells", "length_m", "expanded", "time_ms", "turning_points",
"any_angle_turning_points", "cells"?}``. Exit 2 with a one-line message for a
missing or unreadable map, a bad point, or a start or goal that is blocked; the
message names the point in the units it was given (metres with ``--metres``, with
the map's extent in metres; cells otherwise).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from . import astar, jps, load_movingai_map, load_ros_map
from .anyangle import shorten, turning_points


def _point(text: str) -> tuple[float, float]:
    try:
        a, b = (float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected two numbers 'A,B', got {text!r}") from None
    return a, b


def endpoint_error(grid, name: str, given: tuple[float, float], cell: tuple[int, int],
                   metres: bool, inflate_m: float) -> str | None:
    """Why ``given`` (as the user typed it) cannot be a start or goal, in its units;
    None when it can."""
    r, c = cell
    h, w = grid.shape
    if metres:
        ox, oy = grid.origin_xy
        wm, hm = grid.size_m
        where = f"x {given[0]:g} m, y {given[1]:g} m"
        extent = (f"the map spans x {ox:g}..{ox + wm:g} m, y {oy:g}..{oy + hm:g} m")
    else:
        where = f"cell row {r}, col {c}"
        extent = f"the map has {h} rows and {w} columns"
    if not grid.in_bounds(r, c):
        return f"{name} {where} lies outside the map ({extent})"
    if grid.blocked[r, c]:
        near = (f" or within the --inflate {inflate_m:g} m of one" if inflate_m > 0 else "")
        return f"{name} {where} is blocked (on an obstacle{near})"
    return None


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m app.core.planner", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    p = sub.add_parser("plan", help="plan one path and print it as JSON")
    p.add_argument("--map", required=True, help="a Moving AI .map or a ROS .yaml")
    p.add_argument("start", type=_point)
    p.add_argument("goal", type=_point)
    p.add_argument("--metres", action="store_true", help="START and GOAL are X,Y in metres")
    p.add_argument("--algo", choices=["astar", "jps"], default="jps")
    p.add_argument("--heuristic", choices=["octile", "euclidean", "manhattan", "improved"],
                   default="octile", help="A* only")
    p.add_argument("--inflate", type=float, default=0.0, metavar="RADIUS_M",
                   help="inflate obstacles by the robot's radius first")
    p.add_argument("--cells", action="store_true", help="include the cell path")
    a = ap.parse_args(argv)

    path = Path(a.map)
    try:
        grid = load_ros_map(path) if path.suffix in (".yaml", ".yml") \
            else load_movingai_map(path)
    except FileNotFoundError:
        print(f"planner: map not found: {path}", file=sys.stderr)
        return 2
    except (OSError, ValueError, KeyError) as e:
        print(f"planner: cannot read map {path}: {e}", file=sys.stderr)
        return 2
    if a.inflate > 0:
        grid = grid.inflate(a.inflate)

    def cell(pt: tuple[float, float]) -> tuple[int, int]:
        return grid.world_to_cell(*pt) if a.metres else (int(pt[0]), int(pt[1]))

    start, goal = cell(a.start), cell(a.goal)
    for name, given, at in (("start", a.start, start), ("goal", a.goal, goal)):
        why = endpoint_error(grid, name, given, at, a.metres, a.inflate)
        if why:
            print(f"planner: {why}", file=sys.stderr)
            return 2
    try:
        if a.algo == "jps":
            res = jps(grid.blocked, start, goal)
        else:
            res = astar(grid.blocked, start, goal, heuristic=a.heuristic)
    except ValueError as e:
        print(f"planner: {e}", file=sys.stderr)
        return 2
    out = {
        "found": res.length is not None,
        "start": list(start),
        "goal": list(goal),
        "length_cells": res.length,
        "length_m": None if res.length is None else res.length * grid.resolution_m,
        "expanded": res.expanded,
        "time_ms": round(res.time_ms, 3),
        "turning_points": turning_points(res.cells) if res.cells else 0,
        "any_angle_turning_points":
            turning_points(shorten(grid.blocked, res.cells)) if res.cells else 0,
    }
    if a.cells:
        out["cells"] = [list(c) for c in res.cells]
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())

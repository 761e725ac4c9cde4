"""Plan on a map from the command line.

    python -m app.core.planner plan --map MAP START GOAL [--algo jps] [--inflate 0.35]

MAP is a Moving AI ``.map`` or a ROS map_server ``.yaml``. START and GOAL are
``ROW,COL`` cells, or ``X,Y`` in metres with ``--metres``. Prints one JSON object:
``{"found", "length_cells", "length_m", "expanded", "time_ms", "turning_points",
"any_angle_turning_points", "cells"?}``. Exit 2 with a one-line message for a
missing or unreadable map, a bad point, or a start or goal that is blocked.
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

"""How far the detours to a vertical seam are from the tank's lane ends, on the map
alone (no run): for every end of a column's run of free cells (the vertical lanes'
ends), the way one way to the nearest cell a vertical seam crosses, on the end's own
row (the detours before) and on any row (sim_robot/climber/seam_detour.py), for the
point probe of the headless inspection and, with --body, for the relay executor's
route map and the body's steps (sim_robot/climber/link_ends.py body_steps).

    PYTHONPATH=$PWD python bench/climber_detour_reach.py [--box 68,95,640,710] [--body]

Prints, over the whole tank and inside the box (rows R0-R1, columns C0-C1; the
wedge between the stair band and the top edge by default), how many lane ends have
a seam's cell within SeamDetour's max_steps, and the lengths.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from app.core.planner.coverage.wall import default_wall, rasterise  # noqa: E402
from sim_robot.climber.contact import WallContact  # noqa: E402
from sim_robot.climber.kinematics import ClimberParams  # noqa: E402
from sim_robot.climber.link_ends import body_steps  # noqa: E402
from sim_robot.climber.reach import Reach  # noqa: E402
from sim_robot.climber.seam_detour import (  # noqa: E402
    SeamDetour,
    seam_cells,
    straight_path,
)


def lane_ends(blocked: np.ndarray) -> list[tuple[int, int]]:
    """Both ends of every column's run of free cells."""
    rows, cols = blocked.shape
    out = []
    for c in range(cols):
        r = 0
        while r < rows:
            if blocked[r, c]:
                r += 1
                continue
            end = r
            while end + 1 < rows and not blocked[end + 1, c]:
                end += 1
            out.extend({(r, c), (end, c)})
            r = end + 1
    return out


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--box", default="68,95,640,710", metavar="R0,R1,C0,C1")
    ap.add_argument("--body", action="store_true",
                    help="the relay executor's route map and the body's steps")
    ap.add_argument("--far", type=int, default=90,
                    help="in the box, search this far (cells, one way)")
    ap.add_argument("--whole", action="store_true",
                    help="also count the whole tank's lane ends (within max_steps only)")
    a = ap.parse_args(argv)
    spec = default_wall()
    blocked = rasterise(spec)
    step_ok = None
    if a.body:
        p = ClimberParams()
        reach = Reach(WallContact(spec, blocked, p.length_m, p.width_m), p.length_m / 2)
        blocked = reach.body_blocked()
        step_ok = body_steps(reach, spec.cell_m, blocked.shape[1])
    det = SeamDetour(blocked, spec.seams, spec.cell_m, max_lanes=1)
    r0, r1, c0, c1 = (int(v) for v in a.box.split(","))
    within = det.max_steps
    ends = lane_ends(blocked)
    boxed = [e for e in ends if r0 <= e[0] <= r1 and c0 <= e[1] <= c1]
    own, anyrow = {}, {}
    for e in ends if a.whole else boxed:
        far = a.far if e in boxed else within
        goals = seam_cells(spec.seams, e[0], spec.cell_m, blocked)
        own[e] = len(straight_path(blocked, e, goals, far, step_ok)) or (
            0 if e in goals else None)
        anyrow[e] = len(straight_path(blocked, e, det.goals, far, step_ok)) or (
            0 if e in det.goals else None)
    print(f"{'body steps on the relay executor route map' if a.body else 'point probe'}; "
          f"{len(ends)} lane ends; max_steps {within}")
    for name, sel in ((("whole tank", ends),) if a.whole else ()) + (
            (f"rows {r0}-{r1}, columns {c0}-{c1}", boxed),):
        for label, d in (("own row", own), ("any row", anyrow)):
            got = [d[e] for e in sel if d[e] is not None and d[e] <= within]
            print(f"{name}, {label}: {len(got)} of {len(sel)} lane ends within {within} "
                  f"steps (median {np.median(got) if got else float('nan'):.0f})")
    box = sorted(boxed, key=lambda e: (e[1], e[0]))
    print("in the box, lane end: own row / any row (steps one way; - beyond "
          f"{a.far}):")
    def show(n) -> str:
        return "-" if n is None else str(n)

    print("  " + ", ".join(f"{e}: {show(own[e])}/{show(anyrow[e])}" for e in box))


if __name__ == "__main__":
    main()

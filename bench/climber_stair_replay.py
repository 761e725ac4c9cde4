"""The relay's executor replayed with the body model at the tank's stair band,
headless (no link, no threads): a lane's bottom end above the band (column 641,
where a tank run wedged), the estimate the truth plus a constant offset, the
relay's contact reports (when a contact begins and every second it lasts).
Prints, per offset, the contact reports, the route cells filed and the ways
round. ``--wedge`` starts instead from the stair wedge at (64.11, 5.89, −140°)
(the poses within that log line's rounding whose footprint touches the band
without overlapping it).

    PYTHONPATH=$PWD python bench/climber_stair_replay.py [--offsets -0.03 0 0.03] [--wedge]
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from app.core.planner.coverage.wall import rasterise  # noqa: E402
from sim_robot.climber.contact import WallContact  # noqa: E402
from sim_robot.climber.executor import MOP_UPS, InspectionExecutor  # noqa: E402
from sim_robot.climber.kinematics import ClimberBody, ClimberParams, ClimberState  # noqa: E402
from sim_robot.climber.reach import Reach  # noqa: E402
from sim_robot.climber.sim import ClimberSetup  # noqa: E402

LANE_END = (58, 641)  # the lane's bottom end above the band


def wedge_poses(contact: WallContact) -> list[tuple[float, float, float]]:
    """The poses within the rounding of (64.11, 5.89, −140°) whose footprint touches
    the map without overlapping it (depth in (−1 mm, 0])."""
    x0, y0, th0 = 64.11, 5.89, math.radians(-140.0)
    out = []
    for dx in np.linspace(-0.005, 0.005, 11):
        for dy in np.linspace(-0.005, 0.005, 11):
            for dth in np.radians(np.linspace(-0.5, 0.5, 11)):
                pose = (x0 + dx, y0 + dy, th0 + dth)
                if -0.001 < contact.depth(*pose)[0] <= 1e-9:
                    out.append(pose)
    return out


def replay(ex: InspectionExecutor, route, start: int, body: ClimberBody,
           offset: tuple[float, float], t_max: float = 150.0) -> tuple[int, int, float]:
    """Drive ``route`` from index ``start``; (contact reports, cells filed, sim s)."""
    ex.start(0.0)
    ex.cells, ex.planned, ex.index = list(route), len(route), start
    ex.mop_ups = MOP_UPS  # (the route's end is the replay's: no mop-up of the whole tank)
    ex._replan = start == 0
    t, told, was, reports = 0.0, -9.0, False, 0
    while t < t_max and ex.index < len(ex.cells):
        s = body.s
        belief = (s.x_m + offset[0], s.y_m + offset[1], s.theta_rad)
        v, w = ex.step(belief, t, t, None)
        body.step(v, w, 0.05)
        t += 0.05
        s = body.s
        ex.reading((s.x_m + offset[0], s.y_m + offset[1], s.theta_rad), 10.0)
        touching = bool(body.touching)
        if touching and (not was or t - told >= 1.0):
            told, reports = t, reports + 1
            ex.touched(t, v)
        was = touching
    return reports, sum(bool(ex.covered[c]) for c in set(route)), t


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--offsets", type=float, nargs="+", default=[0.0, -0.03, -0.05, 0.03],
                    help="the estimate's x minus the truth's, m")
    ap.add_argument("--wedge", action="store_true", help="start from the stair wedge")
    a = ap.parse_args(argv)
    spec = ClimberSetup().spec
    blocked = rasterise(spec)
    p = ClimberParams()
    contact = WallContact(spec, blocked, p.length_m, p.width_m)
    reach = Reach(contact, p.length_m / 2)
    plan = InspectionExecutor(blocked, spec.cell_m, (0, 0), p, turns_in_place=True,
                              reach=reach).cells
    k = next(i for i in range(1, len(plan)) if plan[i] == LANE_END
             and plan[i - 1] == (LANE_END[0] + 1, LANE_END[1]))
    lead = p.length_m / 2
    if a.wedge:
        route, start = plan[k:k + 10], 0
        poses = wedge_poses(contact)
    else:  # from two cells up the lane, facing down
        route, start = plan[k - 2:k + 10], 1
        r, c = route[0]
        poses = [((c + 0.5) * spec.cell_m, (r + 0.5) * spec.cell_m + lead, -math.pi / 2)]
    print(f"route {route}")
    for pose in poses:
        for off in a.offsets:
            ex = InspectionExecutor(blocked, spec.cell_m, (0, 0), p, turns_in_place=True,
                                    reach=reach)
            body = ClimberBody(p, ClimberState(*pose), contact.circ_m, seed=1,
                               height_m=spec.height_m, contact=contact.depth)
            reports, filed, t = replay(ex, route, start, body, (off, 0.0))
            s = body.s
            print(f"from ({pose[0]:.3f}, {pose[1]:.3f}, {math.degrees(pose[2]):.1f}°), "
                  f"estimate x {off:+.3f} m off: {reports} contact reports, filed {filed} of "
                  f"{len(set(route))}, ways round {ex.ways_round}, {t:.0f} s; the body at "
                  f"({s.x_m:.3f}, {s.y_m:.3f}, {math.degrees(s.theta_rad):.0f}°)")


if __name__ == "__main__":
    main()

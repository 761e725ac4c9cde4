"""A simulated inspection of a whole tank wall (issue 14's last goal): plan
the coverage, drive the climber's probe over every planned cell, and check
that every reachable cell was probed and the thinnest patch found within one
cell of the truth.

    PYTHONPATH=$PWD python bench/climber_inspection_bench.py [--small]

--localise ekf steers on the estimate instead of the true pose and files
each reading under the believed cell (see sim_robot/climber/inspection.py):
the seed-003 EKF (encoders + gyro) alone, or with --gravity and
--seam-fixes the wall EKF (gravity heading, seams and shell edges, gravity
slip learnt); --lanes vertical sweeps the whole wall up and down; --wall
6x2.4 takes the link bench's test wall.

With --localise ekf --seam-fixes --lanes vertical the crawler by default
turns in place at each lane change and, after 10 lane changes without an x
fix, detours along its row to the nearest vertical seam and back (the
setting measured best on the tank, docs/climber.md); --no-turns-in-place and
--x-fix-lanes 0 switch them off, --x-fix-lanes N sets the lanes between
detours. Elsewhere both are off unless asked for. The bench prints the
probed and missed cells, the detours, the simulated time and how many
cells the thinnest reading lies from the true thinnest patch. --x-fix-trace
[R0,R1,C0,C1] also prints the longest stretches without an x fix and the cells
filed with the true probe in another cell (bench/_climber_xfix_trace.py).

    PYTHONPATH=$PWD python bench/climber_inspection_bench.py --localise ekf \
        --gravity --seam-fixes --lanes vertical --seed 0
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from app.core.planner.coverage.wall import (  # noqa: E402
    Band,
    Disc,
    WallSpec,
    default_wall,
    plate_seams,
)
from sim_robot.climber.inspection import X_FIX_LANES, inspect_wall, lane_options  # noqa: E402
from sim_robot.climber.wall_world import WallWorld  # noqa: E402


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--small", action="store_true", help="an 8 m × 4.8 m wall instead of the tank")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--localise", choices=["truth", "ekf"], default="truth")
    ap.add_argument("--seam-fixes", action="store_true", help="correct the EKF on weld seams seen")
    ap.add_argument("--gravity", action="store_true", help="the accelerometer's absolute heading")
    ap.add_argument("--lanes", choices=["planner", "vertical"], default="planner")
    ap.add_argument("--seek", action="store_true",
                    help="seek the shell's edge when an edge row is reached and the camera "
                         "has not seen it (sim_robot/climber/edge_seek.py)")
    ap.add_argument("--accel-cal", action="store_true",
                    help="with --gravity: calibrate the accelerometer's bias at the start "
                         "(four standstills a quarter turn apart)")
    ap.add_argument("--turns-in-place", action=argparse.BooleanOptionalAction, default=None,
                    help="at a lane's end turn in place, step sideways facing along the "
                         "wall's horizontal, turn in place again (default: on with "
                         "--localise ekf --seam-fixes --lanes vertical, else off)")
    ap.add_argument("--x-fix-lanes", type=int, default=None, metavar="N",
                    help="with --seam-fixes: after N lane changes without an x fix, drive to "
                         "the nearest vertical seam at the next lane's end and back; 0: never "
                         f"(default: {X_FIX_LANES} with --localise ekf --seam-fixes "
                         "--lanes vertical, else 0)")
    ap.add_argument("--sure-ends", action=argparse.BooleanOptionalAction, default=None,
                    help="judge each end of a vertical run by the estimate's height and its "
                         "covariance; seek the shell's edge when not sure (default: on where "
                         "the x fix detours are, sim_robot/climber/sure_ends.py)")
    ap.add_argument("--wall", help="circumference x height in m: the link bench's test wall")
    ap.add_argument("--slip-walk", metavar="PER_S,PER_M",
                    help="the wall EKF's slip states' random walk per √s and per √m of wheel "
                         "arc (a filter variant; default: WallNoise's)")
    ap.add_argument("--detour-any-row", action="store_true",
                    help="a detour goes to the nearest cell any vertical seam crosses, on any "
                         "row (SeamDetour.any_row, off by default)")
    ap.add_argument("--x-fix-trace", metavar="R0,R1,C0,C1", nargs="?", const="",
                    help="print the longest stretches without an x fix and the cells filed "
                         "with the true probe in another cell (bench/_climber_xfix_trace.py), "
                         "also for the box of rows R0-R1 and columns C0-C1 when given "
                         "(the tank's wedge above the stair band: 68,95,640,710)")
    a = ap.parse_args(argv)
    if a.slip_walk:  # the filter variant: every WallEkf the inspection makes gets this noise
        import functools

        import sim_robot.climber.inspection as inspection
        from app.core.localisation.wall_ekf import WallEkf, WallNoise

        per_s, per_m = (float(v) for v in a.slip_walk.split(","))
        inspection.WallEkf = functools.partial(
            WallEkf, wall=WallNoise(slip_walk=per_s, slip_walk_per_m=per_m))
    if a.wall:
        from bench.climber_link_bench import setup

        st = setup(a.wall)
        spec = st.spec
        world = WallWorld(spec, patches=st.patches, nominal_mm=st.nominal_mm, seed=a.seed)
    elif a.small:
        spec = WallSpec(
            8.0 / math.pi,
            4.8,
            0.1,
            manholes=(Disc(1.0, 1.0, 0.5),),
            nozzles=(Disc(3.0, 0.5, 0.2),),
            stairs=(Band(5.0, 0.0, 6.0, 4.8, 0.3),),
            seams=plate_seams(8.0 / math.pi, 4.8, 2.4, 4),
        )
    else:
        spec = default_wall()
    if not a.wall:
        world = WallWorld(spec, seed=a.seed)
    free = ~world.blocked
    start = tuple(int(v) for v in next(iter(zip(*free.nonzero(), strict=True))))
    if a.wall:
        from sim_robot.climber.kinematics import ClimberParams
        from sim_robot.climber.sim import first_start

        start = first_start(world.blocked, ClimberParams(), spec.cell_m)
    if a.detour_any_row:
        from sim_robot.climber.seam_detour import SeamDetour

        SeamDetour.any_row = True
    trace = None
    if a.x_fix_trace is not None:
        from bench._climber_xfix_trace import XFixTrace

        trace = XFixTrace(world)
    turns, x_fix = lane_options(a.localise, a.seam_fixes, a.lanes, a.turns_in_place,
                                a.x_fix_lanes)
    t0 = time.process_time()
    res = inspect_wall(world, start, seed=a.seed, localise=a.localise, seam_fixes=a.seam_fixes,
                       gravity=a.gravity, lanes=a.lanes, seek=a.seek,
                       accel_calibration=a.accel_cal,
                       turns_in_place=turns, x_fix_lanes=x_fix, sure_ends=a.sure_ends)
    cpu = time.process_time() - t0
    true_mm, true_cell = world.thinnest()
    dr = abs(res.thinnest_cell[0] - true_cell[0])
    dc = abs(res.thinnest_cell[1] - true_cell[1])
    dc = min(dc, world.cols - dc)
    print(
        f"wall {world.rows}×{world.cols} cells, start {start}, steering on {a.localise}"
        f"{' with seam fixes' if a.seam_fixes else ''}; turns in place {'on' if turns else 'off'}"
        f"; {f'x fix detours after {x_fix} lanes' if x_fix else 'no x fix detours'}"
    )
    print(
        f"probed {res.probed} of {res.planned} planned cells ({res.coverage:.2%}; "
        f"{res.planned - res.probed} missed); "
        f"sim time {res.sim_time_s / 3600:.2f} h; repetition {res.repetition:.2%} "
        f"(believed cell entries); CPU {cpu:.1f} s"
    )
    print(
        f"thinnest measured {res.thinnest_mm:.2f} mm at {res.thinnest_cell}; "
        f"true {true_mm:.2f} mm at {true_cell}; off by {max(dr, dc)} cell(s)"
    )
    print(f"believed − true probe position at the end: {res.final_error_m:.2f} m")
    if any(res.seeks):
        print("edge seeks: {} started, {} found the edge, {} gave up".format(*res.seeks))
    if any(res.detours):
        print("detours to a vertical seam: {} driven, {} cells on them".format(*res.detours))
    if res.sure_seeks or res.unsure:
        print(f"edge seeks for unsure lane ends: {res.sure_seeks}; ends never judged sure: "
              f"{len(res.unsure)} {list(res.unsure)[:20]}")
    if any(res.sure_fixes):
        print("routes to a girth seam or an edge row for unsure lane ends: {} driven, "
              "{} cells on them".format(*res.sure_fixes))
    missed = [(int(r), int(c)) for r, c in zip(*np.nonzero(np.isnan(res.measured)
                                                           & ~world.blocked), strict=True)]
    print(f"missed cells: {missed[:40]}{' ...' if len(missed) > 40 else ''}")
    for name, r in (("top", world.rows - 1), ("bottom", 0)):
        got = int(np.isfinite(res.measured[r]).sum())
        print(f"{name} row: {got} of {int((~world.blocked[r]).sum())} free cells probed")
    if trace is not None:
        box = tuple(int(v) for v in a.x_fix_trace.split(",")) if a.x_fix_trace else None
        for line in trace.report(res, box):
            print(line)


if __name__ == "__main__":
    main()

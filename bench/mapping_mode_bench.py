"""The station map built in mapping mode against the true map (issue 13).

    .venv/bin/python bench/mapping_mode_bench.py --laps 1

The robot maps while it drives the station's default patrol route (standing in
for the operator's keyboard: the mapper sees only the odometry and the lidar,
as in mapping mode, through ``Navigation.mapping``; the route is driven on
the robot's own localisation). The world, the MCU model and the navigation
are stepped in lock-step (sim_robot.patrol_sim). Only this bench reads the
truth: at every fused scan it casts the lidar's beams from the true pose and
keeps the true wall cells they end in ("seen" walls; people are not walls).

The map is compared in the station frame (the map is carried into the
odometry's frame, which starts at the dock's true pose; no alignment):

* coverage: share of the seen true wall cells with a mapped occupied cell
  within one cell (centres ≤ 1.5 cells apart, so the 8 neighbours count);
* spurious: share of mapped occupied cells whose centre is more than
  ``--far`` metres (default 0.25 m, beyond the neighbours' neighbours) from
  any true wall cell; also printed at 0.15 and 0.35 m.

Both the map as the desk sees it while mapping (the live landmark poses) and
the map after the mapper's ``finish()`` (final pass and long-range ties, the
map ``save_map`` writes) are scored; so is the map the landmark scans
make at their true poses (the keyframes' views alone; the map itself is
drawn from every scan the mode kept, sim_robot/mapping_mode.py), and the
mapper's pose error against the truth. Goals: coverage ≥ 97 %, spurious ≤ 2 %.
The saved map is also scored with its cells shifted by half a cell (x, y,
both): its cells lie on multiples of the resolution in the odometry frame,
which here is the station's, so on the true map's cells, the most
favourable phase; a real map's walls fall anywhere in its cells.

One lap's figure moves by several points with the simulated trajectory, so
compare seeds, not one run. Saved map, coverage / spurious (1 lap):

    seed   7c8e5ad        fa9220f       af46991        829558d       disagreement
    0      98.7 / 1.52    91.8 / 0.74   95.9 / 0.80    97.0 / 0.69   97.8 / 0.68
    1      62.6 / 17.18   -             71.0 / 11.53   87.5 / 5.09   95.8 / 3.83
    2      -              -             93.3 / 2.44    97.2 / 1.92   95.1 / 2.29
    3      94.3 / 0.72    -             69.1 / 11.94   95.5 / 0.89   96.0 / 0.88

Up to af46991 the maps that failed were bent by false loop closures, 17-54
cm off, each claiming a σ of 3-7 cm: a scan along a wall matched to an old
one whose position along the wall only a few points held (a person, a
post, the edge of a shadow; 0.1-1.4 points' worth of pairs), and weak
closures about 0.4 m off (a wall's thickness) that a partner far round a
long cycle vouched for. 829558d leaves such a direction free in the
closure's edge and tests weak closures against the graph's own estimate
(loop_closure.py): in seeds 1 and 3 no online closure is now more than
15 cm off in a direction it holds (one in seed 1 is 21 cm off along the
wall it leaves free), where 5 of 18 and 3 of 17 were before. Seed 1's map
still carries a heading error of 0.3-0.45 degrees over the middle of the
loop (nodes 120-400, from the turns on the spot near (54, 35) m and the
125 degree turn near (30, 28.5) m), which the chain's edges spread evenly
when the loop closes; the ends are right. The chain's steps are good
(heading 0.04 degrees rms against the truth, each claiming 0.6 with the
0.5 degree floor): the middle's drift came from a few steps 0.15-0.2
degrees off whose neighbour did not cancel them (nodes 176, 420-421),
where the ICP fit and the grid fit had parted by 0.15-0.3 degrees (0.0-0.07
at their neighbours) while every step claimed the same
sigma, so the solve spread the correction evenly instead of putting it
there. With the disagreement added to the match's covariance (k = 1.5) and
a 0.2 degree heading floor (column "disagreement", sim_robot/mapping_mode.py's
MAPPING_CONFIG; k 1, 1.5, 2, 3 gave seeds 1/0/3 94.6/95.7/98.8,
95.8/97.8/96.0, 94.6/94.7/97.9, 97.4/95.4/96.9; the floor alone 89.7/97.3/
93.4; seed 2 measured once, after the choice, and worse) the finished
poses' median / max error is 2.2 / 8.9, 6.9 / 12.8, 3.9 / 11.0, 1.3 / 6.5
cm for seeds 0-3 (2.5 / 7.4, 9.7 / 22.6, 4.9 / 13.3, 2.5 / 4.6 before).
The finish (final pass) closed nothing in these runs; with MappingConfig's
final_pass on, the saved maps were far worse (seeds 0/1/3: 90.1, 77.6, 68.0 % coverage at 829558d).

The spurious cells left were movers the tracker (8 m reach) never
followed, seen against open ground: the cart driving along the road 8-12 m
off (seeds 0 and 1; a 13 m streak in seed 1) and worker-2 standing at and
walking from (48, 20) (seed 3); no later beam that crossed their cells
ended anywhere, so nothing cleared them (with --no-people spurious was 0).
Saved map, coverage / spurious, after 65a6203 ("disagreement" above):

    seed   free rays      + grid cells   + 25 %         + 25 %, cells ½ off (x / y / both)
    0      94.9 / 0.10    98.7 / 0.06    99.4 / 0.08    99.1 / 97.5 / 96.0
    1      94.9 / 0.17    98.7 / 0.16    99.3 / 0.15    97.3 / 97.6 / 93.2
    2      -              98.6 / 0.00    99.5 / 0.00    99.1 / 97.5 / 94.9
    3      97.4 / 0.00    97.4 / 0.00    99.2 / 0.03    98.5 / 98.2 / 97.0

"free rays" (a4dcf5f): the beams with no return are free space
(app/core/localisation/free_space.py) and clear the movers; it cost no
wall cell at a given grid phase (seed 1 at its phase: 94.9 / 3.87 from the
returns alone), but the rays widened the grid, whose cells then lay
elsewhere: before 5218789 ("grid cells") each run's phase was arbitrary.
"+ 25 %" (a424ec1): the mapping mode's cell is a wall while hits are over
25 % of its beams (GMapping's occ_thresh; it was 40 %, which wore walls
seen at a grazing angle away, most at the half-cell phases: seeds 0/1/3
at (½, ½) 93.0, 90.3, 94.9 before it). Chosen after its effect on the
tuning seeds' replayed scans was seen (Karto's 10 % gave more there and was
not taken); seed 2 held out, its figures entered no choice. Seed 1, two
laps (--laps 2): 97.5 / 6.51 at 65a6203, 98.8 / 0.14 after (cells ½ off:
97.8 / 97.4 / 89.8).

Where the cells lay ½ off in both, the tuning seeds' replayed scans
(--record, fed to a fresh MappingMode: the same map) said why walls were
missed. Of the seen wall cells left uncovered (seeds 0/1/3: 96, 163, 71),
61, 53 and 65 had returns in one of their four nearest map cells (at that
phase the only ones within 1.5 cells), worn under 25 % by misses, 98 % of
which fell within 1 m of their ray's end: beams ending farther along a
wall seen at a grazing angle, one cell short of their end but still
within a few centimetres of the wall, crossed the near half of the face
cells, which a face lying mid-cell has (at phase 0 the face lies on the
cells' edge and the rays stay in the cell before it). The others (35,
110, 6) had no return within reach: the wall drawn over half a cell
towards the robot by the mapper's pose error (seed 1: kept scans' median
6.9 cm, max 12.9 cm), which phase 0 forgives up to a cell. "surface"
(d451b15): a return's free ray stops one cell off the surface it ended on
(the segments to its neighbouring returns, map_io.build_grid's
stop_at_surface) instead of one cell short along the ray (the same at
normal incidence). Saved map, coverage / spurious, cells as drawn and ½
off (x / y / both):

    seed   as drawn       ½ off x        ½ off y        ½ off both
    0      99.8 / 0.07    99.7 / 0.11    99.3 / 0.08    98.5 / 0.09
    1      99.7 / 0.14    98.3 / 0.19    98.7 / 0.14    95.4 / 0.24
    2      99.8 / 0.00    99.8 / 0.00    99.1 / 0.00    97.7 / 0.00
    3      99.9 / 0.02    99.9 / 0.06    99.8 / 0.03    99.7 / 0.03

(before, the "+ 25 %" column and its shifts above). At ½ off both these
equal what the returns alone allow (every cell a return fell in, movers
included: 98.5, 95.4, 99.7), and the same scans at their true poses give
99.7 % or more at every phase (98.0 with the old stop), so seed 1's 95.4
is its poses' error, not the drawing. The one-cell band was not tuned
(0.07-0.2 m gave the same to 0.1 point; 0.05 m up to 0.5 less); seed 2 was
run once, after. Drawing a lap's map: 0.73-0.75 s CPU against 0.72-0.73 s
(min of 8 on the replayed views). On the CARMEN logs (carmen_map_bench.py's
scoring, 5 draws, references drawn without it) the stop adds coverage to
the CLI's drawing (ref-both: freiburg 98.9 → 99.4, edmonton 66.7 → 68.4)
but spurious cells on freiburg (0.04 → 0.08 %; ref-old 0.17 → 0.29), so
build_grid keeps the one-cell-short stop by default and the CLI its
drawing.

Seed 1's 95.4 was its map turned 0.13 degrees about the dock (poses 1.8
cm median once turned back): each match errs ~0.04 degrees in heading
(the lidar's noise; as much against keyframes at their true poses), the
start's short chain alone held the heading to the dock, and finish() was
only a solve. The mapping mode now finishes with the final pass matched
as the online closures match (ICP, faces known, a direction few pairs
hold left free: loop_closure.final_pass, LoopConfig.final_free_directions)
and the variance components; the grid fit's pass (the logs') had broken
the maps through edges 10-30 cm off along the roads. Saved map, coverage
as drawn / 1/2 off x / y / both, spurious %, finished poses' median / max
error (cm), before -> after (docs/localisation.md, section (f)):

    seed   before                            after
    0      99.8/99.7/99.3/98.5 0.07 2.2/8.9   99.9/99.9/99.7/99.0 0.08 2.3/5.5
    1      99.7/98.3/98.7/95.4 0.14 6.9/12.8  99.9/99.8/99.8/99.4 0.14 4.4/8.5
    3      99.9/99.9/99.8/99.7 0.02 1.3/6.5   99.9/99.8/99.8/99.7 0.02 0.9/5.1
    5 (h)  99.8/99.8/99.7/99.5 0.00 2.7/7.1   99.8/99.8/99.8/97.9 0.00 1.4/6.1
    6 (h)  99.8/99.8/99.8/99.5 0.38 3.7/6.6   99.8/99.8/99.7/99.5 0.34 2.7/7.1

(h): held out, run once before and once after. Seed 5's loss at 1/2 off
both: two weak final-pass edges 0.3-0.46 degrees off (partial views in
its dead end) bent that stretch by 0.2 degrees.
"""

from __future__ import annotations

import argparse
import logging
import math
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from app.core.localisation.map_io import OccupancyGrid, build_grid  # noqa: E402
from app.core.localisation.se2 import compose  # noqa: E402
from bench.patrol_bench import add_crowd  # noqa: E402
from sim_robot import mapping_mode  # noqa: E402
from sim_robot.config import SimConfig  # noqa: E402
from sim_robot.mapping_mode import MappingMode  # noqa: E402
from sim_robot.patrol import ACTIVE  # noqa: E402
from sim_robot.patrol_sim import OfflinePatrol  # noqa: E402
from sim_robot.route import DEFAULT_ROUTE, load_route  # noqa: E402


def seen_walls(world, beams: int, range_m: float) -> set[tuple[int, int]]:
    """True wall cells (row, col) the lidar's beams end in from the true pose."""
    p = world.pose
    ang = p.theta + np.linspace(-math.pi, math.pi, beams, endpoint=False)
    r, _ = world.raycast(p.x, p.y, ang, range_m)
    ok = np.isfinite(r)
    d = r[ok] + 0.5 * world.res  # just inside the hit cell
    cols = np.floor((p.x + np.cos(ang[ok]) * d) / world.res).astype(int)
    rows = np.floor((p.y + np.sin(ang[ok]) * d) / world.res).astype(int)
    h, w = world.occupied.shape
    inside = (rows >= 0) & (rows < h) & (cols >= 0) & (cols < w)
    rows, cols = rows[inside], cols[inside]
    wall = world.occupied[rows, cols]
    return set(zip(rows[wall].tolist(), cols[wall].tolist(), strict=True))


def score(grid, world, seen: set, far_m: float) -> str:
    occ = np.argwhere(grid.occupied)
    mapped = np.column_stack((grid.origin_xy[0] + (occ[:, 1] + 0.5) * grid.resolution_m,
                              grid.origin_xy[1] + (occ[:, 0] + 0.5) * grid.resolution_m))
    seen_xy = (np.array(sorted(seen))[:, ::-1] + 0.5) * world.res
    all_xy = (np.argwhere(world.occupied)[:, ::-1] + 0.5) * world.res
    d_cov, _ = cKDTree(mapped).query(seen_xy)
    d_sp, _ = cKDTree(all_xy).query(mapped)
    cover = np.mean(d_cov <= 1.5 * grid.resolution_m) * 100
    spur = {f: np.mean(d_sp > f) * 100 for f in (0.15, far_m, 0.35)}
    return (f"coverage {cover:.1f} % of {len(seen_xy)} seen wall cells (goal >= 97 %); "
            f"spurious {spur[far_m]:.2f} % of {len(mapped)} mapped occupied cells beyond "
            f"{far_m:.2f} m (goal <= 2 %) [beyond 0.15 m {spur[0.15]:.2f} %, "
            f"0.35 m {spur[0.35]:.2f} %]")


def at_phase(view, off_m: tuple[float, float]) -> OccupancyGrid:
    """The map of ``view`` (a MapView) with its cells shifted by ``off_m``
    (the grid's corners lie on multiples of the resolution in the odometry
    frame, which here is the station's, so on the true map's cells)."""
    poses = np.array(view.poses, float)
    poses[:, :2] += off_m
    g = replace(view, poses=poses).grid()
    return OccupancyGrid(g.cells, g.resolution_m,
                         (g.origin_xy[0] - off_m[0], g.origin_xy[1] - off_m[1]))


def run(seed: int, laps: int, crowd: int, people: bool, far_m: float, max_lap_s: float,
        dump: str | None = None, record: str | None = None) -> int:
    op = OfflinePatrol(SimConfig(seed=seed, video=False))
    if not people:
        op.world.walkers, op.world.vehicles = [], []
    add_crowd(op.world, crowd, seed)
    op.nav.warm_up()
    beams, range_m = op.cfg.lidar_beams, op.cfg.lidar_range_m
    with tempfile.TemporaryDirectory() as tmp:
        mode = op.nav.mapping = MappingMode(tmp)
        mode.start()
        inputs: list[tuple[np.ndarray, np.ndarray]] = []  # every scan offered to the mode
        if record:
            add = mode.add

            def add_recorded(odom_pose, points, map_points=None, free_points=None):
                add(odom_pose, points, map_points, free_points)
                inputs.append((np.asarray(odom_pose, float), np.asarray(points, float),
                               None if map_points is None else np.asarray(map_points, float),
                               None if free_points is None else np.asarray(free_points, float)))
            mode.add = add_recorded
        ex = op.nav.executor
        route = load_route(DEFAULT_ROUTE)
        seen: set = set()
        truth: list[tuple[float, float, float]] = []  # at each mapped scan (node)
        added = 0
        for lap in range(1, laps + 1):
            ok, why = ex.start(route, op.t)
            if not ok:
                print(f"lap {lap}: not started: {why}")
                break
            end = op.t + max_lap_s
            while op.t < end and ex.state in ACTIVE:
                op.step()
                if mode.scans > added:  # a scan went to the mapper: what did it see?
                    added = mode.scans
                    seen |= seen_walls(op.world, beams, range_m)
                    p = op.world.pose
                    truth.append((p.x, p.y, p.theta))
            print(f"lap {lap}: {ex.state} at sim {op.t:.0f} s, {mode.scans} scans mapped, "
                  f"{len(mode.mapper.landmarks)} landmarks", flush=True)
        print(f"\nseed {seed}, {laps} laps, people {'on' if people else 'off'}, "
              f"crowd {crowd}, sim {op.t:.0f} s, contacts {len(op.world.collisions)}")
        t0 = time.process_time()
        live = mode.grid()
        cpu = time.process_time() - t0
        print(f"  live map (while mapping, {1000 * cpu:.0f} ms CPU to build): "
              f"{score(live, op.world, seen, far_m)}")
        t0 = time.process_time()
        snap = mode.snapshot()
        print(f"  snapshot (copy of the mapper) {1000 * (time.process_time() - t0):.0f} ms CPU")
        t0 = time.process_time()
        grid = snap.finish()
        cpu = time.process_time() - t0
        print(f"  saved map (after finish, {cpu:.1f} s CPU): {score(grid, op.world, seen, far_m)}")
        view = mapping_mode._view(snap.mapper, snap.anchor, snap.resolution_m, snap.kept)
        for off in ((0.5, 0.0), (0.0, 0.5), (0.5, 0.5)):  # in cells
            g = at_phase(view, (off[0] * mode.resolution_m, off[1] * mode.resolution_m))
            print(f"    its cells shifted by {off} cell: {score(g, op.world, seen, far_m)}")
        m = snap.mapper
        truth_a = np.array(truth)
        lms = [lm.node for lm in m.landmarks]
        ideal = build_grid(truth_a[lms], [lm.points for lm in m.landmarks], mode.resolution_m)
        print(f"  the landmark scans at their TRUE poses: {score(ideal, op.world, seen, far_m)}")
        for label, poses in (("live", mode.mapper.poses), ("finished", m.poses)):
            est = np.array([compose(snap.anchor, q) for q in poses[:len(truth_a)]])
            e = np.hypot(*(est[:, :2] - truth_a[:len(est), :2]).T) * 100
            print(f"  {label} mapper poses vs truth: median {np.median(e):.1f} cm, "
                  f"p95 {np.percentile(e, 95):.1f} cm, max {e.max():.1f} cm")
        if record:  # every scan offered to the mapping mode, to replay it offline
            np.savez_compressed(
                record, occupied=op.world.occupied, res=op.world.res,
                seen=np.array(sorted(seen)), truth=truth_a,
                odom=np.array([i[0] for i in inputs]), anchor=snap.anchor,
                scans=np.array([i[1] for i in inputs], dtype=object),
                map_scans=np.array([i[2] for i in inputs], dtype=object),
                free_scans=np.array([i[3] for i in inputs], dtype=object))
        if dump:  # the landmark scans and poses, to study the map building offline
            np.savez_compressed(
                dump, occupied=op.world.occupied, res=op.world.res,
                seen=np.array(sorted(seen)), truth=truth_a[lms],
                live=np.array([compose(snap.anchor, mode.mapper.poses[i]) for i in lms]),
                finished=np.array([compose(snap.anchor, m.poses[i]) for i in lms]),
                scans=np.array([lm.points for lm in m.landmarks], dtype=object))
        print(f"  loop closures {sum(e.loop for e in m.edges)}, final pass "
              f"{getattr(m, 'final_closures', 0)}, "
              f"long-range ties {getattr(m, 'long_range_ties', 0)}")
    return 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--laps", type=int, default=1)
    ap.add_argument("--crowd", type=int, default=0, help="extra workers crossing the road")
    ap.add_argument("--no-people", action="store_true", help="an empty station")
    ap.add_argument("--far", type=float, default=0.25, help="spurious beyond this (m)")
    ap.add_argument("--max-lap-s", type=float, default=1800.0)
    ap.add_argument("--dump", help="save the landmark scans and poses (npz) here")
    ap.add_argument("--record", help="save every scan offered to the mapping mode with its "
                    "odometry, and the true poses of the mapped ones (npz) here, to "
                    "replay it offline")
    ap.add_argument("--icp-cov-scale", type=float, default=None,
                    help="MappingConfig.icp_cov_scale of the mapping mode (default: its own)")
    a = ap.parse_args()
    if a.icp_cov_scale is not None:
        mapping_mode.MAPPING_CONFIG = replace(mapping_mode.MAPPING_CONFIG,
                                              icp_cov_scale=a.icp_cov_scale)
    logging.basicConfig(level=logging.WARNING)
    return run(a.seed, a.laps, a.crowd, not a.no_people, a.far, a.max_lap_s, a.dump, a.record)


if __name__ == "__main__":
    sys.exit(main())

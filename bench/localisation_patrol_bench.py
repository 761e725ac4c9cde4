"""Localisation on patrol: the robot's own pose estimate against the simulator's
truth over laps of the station's default route, with the crowd.

    .venv/bin/python bench/localisation_patrol_bench.py --laps 2 --crowd 6

The world, the MCU model and the navigation stack are stepped in lock-step
(sim_robot.patrol_sim). The navigation localises on its lidar scans against
the saved station map, fused with the encoder/gyro odometry (sim_robot/
localisation.py); only this bench reads the truth, to score it. Each lap
starts at the dock where the previous one ended, without resetting the
estimate. Printed per lap and over all laps: position error (median, p95,
p99, max), yaw error median and p99, while the robot moves (|v| > 0.05 m/s)
and over all steps; scans matched, times lost, contacts with the robot
moving, and CPU time per localisation update (process time).

Goals (issue 13): 10 laps with the crowd, median ≤ 3 cm, p99 ≤ 10 cm, yaw
median ≤ 0.5°, 0 lost, 0 contacts while moving.
"""

from __future__ import annotations

import argparse
import logging
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.patrol_bench import add_crowd, watch_speed  # noqa: E402
from sim_robot.config import SimConfig  # noqa: E402
from sim_robot.patrol import ACTIVE  # noqa: E402
from sim_robot.patrol_sim import OfflinePatrol  # noqa: E402
from sim_robot.route import DEFAULT_ROUTE, load_route  # noqa: E402


def timed_correct(loc, cpu_ms: list[float]) -> None:
    """Record the process time of each scan's localisation update."""
    correct = loc.correct

    def wrapped(scan, *rest):
        t0 = time.process_time()
        out = correct(scan, *rest)
        cpu_ms.append((time.process_time() - t0) * 1000.0)
        return out

    loc.correct = wrapped


def summary(err: np.ndarray) -> str:
    if len(err) == 0:
        return "no samples"
    d, yaw = err[:, 0] * 100, np.degrees(err[:, 1])
    return (f"pos cm median {np.median(d):.1f} p95 {np.percentile(d, 95):.1f} "
            f"p99 {np.percentile(d, 99):.1f} max {d.max():.1f} · yaw ° median "
            f"{np.median(yaw):.2f} p99 {np.percentile(yaw, 99):.2f}")


def moving_contacts(collisions: list[dict], speeds: list[tuple[float, float]]) -> int:
    t = np.array([s[0] for s in speeds]) if speeds else np.zeros(0)
    n = 0
    for c in collisions:
        i = int(np.searchsorted(t, c["t_s"] + 1e-6)) - 1
        v = speeds[i][1] if i >= 0 else 0.0
        n += abs(v) >= 0.01 or c["what"] == "static"
    return n


def run(seed: int, laps: int, crowd: int, max_lap_s: float, max_wall_s: float) -> int:
    wall_end = time.monotonic() + max_wall_s
    op = OfflinePatrol(SimConfig(seed=seed, video=False))
    add_crowd(op.world, crowd, seed)
    speeds = watch_speed(op.world)
    op.nav.warm_up()
    loc = op.nav.localiser
    cpu_ms: list[float] = []
    timed_correct(loc, cpu_ms)
    ex = op.nav.executor
    route = load_route(DEFAULT_ROUTE)
    all_err, all_moving = [], []
    done = 0
    for lap in range(1, laps + 1):
        ok, why = ex.start(route, op.t)
        if not ok:
            print(f"lap {lap}: not started: {why}")
            break
        err, moving = [], []
        end = op.t + max_lap_s
        while op.t < end and ex.state in ACTIVE:
            op.step()
            p = op.world.pose  # the truth, read by the bench only
            x, y, th = loc.pose
            e = (math.hypot(x - p.x, y - p.y),
                 abs((th - p.theta + math.pi) % (2 * math.pi) - math.pi))
            err.append(e)
            if abs(p.v) > 0.05:
                moving.append(e)
        reached = sum(1 for d in op.codes("point_reached"))
        print(f"lap {lap}: {ex.state} at sim {op.t:.0f} s, points reached so far {reached}, "
              f"lost so far {loc.lost_count}; moving: {summary(np.array(moving))}", flush=True)
        all_err += err
        all_moving += moving
        done = lap
        if loc.lost:
            print("  localisation lost: the robot stopped; the bench stops here")
            break
        if lap < laps and time.monotonic() > wall_end:
            print(f"  wall-time budget ({max_wall_s:.0f} s) spent after {lap} laps; "
                  "the bench stops here")
            break
    contacts = moving_contacts(op.world.collisions, speeds)
    print(f"\nseed {seed}, {done} of {laps} laps run, crowd {crowd}, sim {op.t:.0f} s")
    print(f"  while moving: {summary(np.array(all_moving))}")
    print(f"  all steps:    {summary(np.array(all_err))}")
    print(f"  scans {loc.scans}, matched {loc.fixes}, failed {loc.failures}, "
          f"lost {loc.lost_count}; contacts {len(op.world.collisions)} "
          f"({contacts} with the robot moving)")
    c = np.array(cpu_ms) if cpu_ms else np.zeros(1)
    print(f"  localisation update CPU ms: median {np.median(c):.1f} p95 "
          f"{np.percentile(c, 95):.1f} (process time, shared host)")
    return 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--laps", type=int, default=2)
    ap.add_argument("--crowd", type=int, default=6, help="extra workers crossing the road")
    ap.add_argument("--max-lap-s", type=float, default=1800.0)
    ap.add_argument("--max-wall-s", type=float, default=math.inf,
                    help="start no new lap after this much wall time (loaded hosts)")
    a = ap.parse_args()
    logging.basicConfig(level=logging.WARNING)
    return run(a.seed, a.laps, a.crowd, a.max_lap_s, a.max_wall_s)


if __name__ == "__main__":
    sys.exit(main())

"""4WS crowd patrol bench: the 4WS robot's lock-step patrol of the default
route with the crowd of six crossers, per seed, as tests/sim/test_fws_patrol.py
runs it (meter dwell 50 s, ``FwsOfflinePatrol``, ``bench/patrol_bench.py``'s
``add_crowd``).

    PYTHONPATH=$PWD .venv/bin/python bench/fws_crowd_bench.py --seeds 1 2 3 4 5 6 7
    PYTHONPATH=$PWD .venv/bin/python bench/fws_crowd_bench.py --seeds 2 --trace

Per seed: the mission's end, points inspected, contacts, contacts while moving
and struck while stopped — counted as the skid-steer robot's crowd figures are
(``bench/patrol_bench.py``'s ``report_collisions``: the robot's speed at the
last motion step before the contact; |v| < 0.01 m/s is "struck while stopped",
anything else "while moving") — and the sim time. For every contact: the
robot's speed, its board's steering mode, the navigator's mode (``blocked``:
the safety stop; ``pivot``: turning in place; ``following``/``avoiding``:
pure pursuit on the TEB band), the command and the worker's true velocity, and
with ``--trace`` the two seconds before it every 0.2 s: the distance between
the robot's body and the worker's, the robot's speed and command, what the
navigator did and the worker's track as the robot saw it. The bench reads the
simulator's ground truth (people's positions); the robot never does.
"""

from __future__ import annotations

import argparse
import logging
import math
import sys
import time
from collections import deque
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.patrol_bench import add_crowd  # noqa: E402
from sim_robot.config import SimConfig  # noqa: E402
from sim_robot.fws_robot import FwsOfflinePatrol  # noqa: E402
from sim_robot.route import DEFAULT_ROUTE, load_route  # noqa: E402

KEEP_S = 2.0
MOVING_MPS = 0.01  # as bench/patrol_bench.py: below this the robot was struck while stopped


def watch_speed(world) -> list[tuple[float, float]]:
    """(sim time, robot speed) at every motion step of the world, as
    ``bench/patrol_bench.py``'s ``watch_speed`` with the 4WS base's sideways
    speed too (the speed is signed by the forward one)."""
    log: list[tuple[float, float]] = []
    move = world.move_robot

    def move_robot(v, omega, dt, radius_m, *when, lateral_mps: float = 0.0):
        log.append((world.clock(), math.copysign(math.hypot(v, lateral_mps), v)))
        return move(v, omega, dt, radius_m, *when, lateral_mps=lateral_mps)

    world.move_robot = move_robot
    return log


class Recorder:
    """Every control step of the last ``KEEP_S``: sim time, true pose and speed,
    the navigator's command, mode and the board's steering mode, the tracked
    obstacles and every mover's true position (for the dump, not the robot)."""

    def __init__(self, op: FwsOfflinePatrol) -> None:
        self.op = op
        self.rows: deque = deque()
        self.dumps: list[tuple[dict, list]] = []
        self.cmd = (0.0, 0.0, "-")
        nav = op.fws_nav
        nstep = nav.step

        def nav_step(*a, **k):
            out = nstep(*a, **k)
            self.cmd = (float(out[0]), float(out[1]), str(out[2]))
            return out

        nav.step = nav_step
        step = op.step

        def stepped():
            step()
            self._row()

        op.step = stepped
        on = op.world.on_collision

        def hit(rec):
            self.dumps.append((rec, list(self.rows)))
            if on is not None:
                on(rec)

        op.world.on_collision = hit

    def _row(self) -> None:
        op, nav = self.op, self.op.fws_nav
        p = op.world.pose
        t = op.t
        teb = nav.last_teb
        why = nav.mode
        if teb is not None and teb.turning_in_place and why != "blocked":
            why = "pivot"
        self.rows.append((t, p.x, p.y, p.theta, p.v, self.cmd, why, op.mcu.steer_mode,
                          op.nav.executor.phase, np.array(op.nav.obstacles, float).copy(),
                          op.world.people(t).copy(), op.world.mover_ids()))
        while self.rows and self.rows[0][0] < t - KEEP_S - 0.05:
            self.rows.popleft()


def worker_velocity(rows: list, k: int) -> tuple[float, float]:
    """The true velocity of mover ``k`` over the last two rows."""
    if len(rows) < 2:
        return 0.0, 0.0
    t0, p0 = rows[-2][0], rows[-2][10]
    t1, p1 = rows[-1][0], rows[-1][10]
    dt = max(t1 - t0, 1e-9)
    return float((p1[k, 0] - p0[k, 0]) / dt), float((p1[k, 1] - p0[k, 1]) / dt)


def describe(rec: dict, rows: list, v_contact: float, radius_m: float,
             trace: bool) -> str:
    if not rows:
        return f"    contact {rec}: no steps recorded"
    ids = rows[-1][11]
    who = rec["what"]
    k = ids.index(who) if who in ids else -1
    t, x, y, th, v, cmd, why, steer, phase, obs, ppl, _ = rows[-1]
    wv = worker_velocity(rows, k) if k >= 0 else (math.nan, math.nan)
    moving = abs(v_contact) >= MOVING_MPS and who != "static"
    out = [f"    contact t {rec['t_s']:.2f} {who} at ({rec['x_m']:.2f},{rec['y_m']:.2f}): "
           f"robot v {v_contact:+.2f} m/s ({'moving' if moving else 'struck while stopped'}), "
           f"heading {math.degrees(th):+.0f}°, board {steer}, navigator {why} "
           f"(phase {phase}), command ({cmd[0]:+.2f}, {cmd[1]:+.2f}); "
           f"worker v ({wv[0]:+.2f},{wv[1]:+.2f}) m/s"]
    if trace and k >= 0:
        last = -math.inf
        for t, x, y, th, v, cmd, why, steer, _ph, obs, ppl, _ in rows:
            if t - last < 0.195:
                continue
            last = t
            gap = math.hypot(ppl[k, 0] - x, ppl[k, 1] - y) - ppl[k, 2] - radius_m
            tr = "-"
            if len(obs):
                do = np.hypot(obs[:, 0] - ppl[k, 0], obs[:, 1] - ppl[k, 1])
                j = int(np.argmin(do))
                if do[j] < 0.6:
                    o = obs[j]
                    tr = f"({o[0]:.2f},{o[1]:.2f}) v ({o[2]:+.2f},{o[3]:+.2f}) r {o[4]:.2f}"
            out.append(f"      t {t:7.2f} gap {gap:+.2f} m robot ({x:.2f},{y:.2f},"
                       f"{math.degrees(th):+4.0f}°) v {v:+.2f} cmd ({cmd[0]:+.2f},"
                       f"{cmd[1]:+.2f}) {why:9s} {steer:8s} worker ({ppl[k, 0]:.2f},"
                       f"{ppl[k, 1]:.2f}) track {tr}")
    return "\n".join(out)


def run(seed: int, crowd: int, meter_dwell: float, trace: bool) -> dict:
    route = load_route(DEFAULT_ROUTE)
    for p in route.points:
        if p.gauge:
            p.dwell_s = max(p.dwell_s, meter_dwell)
    op = FwsOfflinePatrol(SimConfig(seed=seed, video=False))
    add_crowd(op.world, crowd, seed)
    speeds = watch_speed(op.world)
    rec = Recorder(op)
    c0 = time.process_time()
    state = op.run(route, max_sim_s=1800)
    cpu = time.process_time() - c0
    pts = op.nav.executor.mission.points
    inspected = sum(p["state"] == "done" for p in pts)
    ts = np.array([s[0] for s in speeds]) if speeds else np.zeros(0)
    moving = stopped = 0
    lines = []
    for c, rows in rec.dumps:
        i = int(np.searchsorted(ts, c["t_s"] + 1e-6)) - 1
        v = speeds[i][1] if i >= 0 else 0.0
        if abs(v) >= MOVING_MPS or c["what"] == "static":
            moving += 1
        else:
            stopped += 1
        lines.append(describe(c, rows, v, op.world.robot_radius_m, trace))
    res = {"seed": seed, "state": state, "inspected": inspected, "points": len(pts),
           "contacts": len(op.world.collisions), "moving": moving, "stopped": stopped,
           "sim_s": op.t, "cpu_s": cpu, "min_clear": op.min_clearance_m,
           "stops": op.fws_nav.governor_count,
           "yield_steps": getattr(op.fws_nav, "yield_count", 0)}
    print(f"seed {seed}: {state} points {inspected}/{len(pts)} contacts {res['contacts']} "
          f"(while moving {moving}, struck while stopped {stopped})  sim {op.t:.1f} s  "
          f"safety steps {res['stops']} (backing away {res['yield_steps']})  "
          f"min clearance {op.min_clearance_m:.2f} m  "
          f"CPU {cpu:.1f} s", flush=True)
    for ln in lines:
        print(ln, flush=True)
    return res


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3, 4, 5, 6, 7])
    ap.add_argument("--crowd", type=int, default=6)
    ap.add_argument("--meter-dwell", type=float, default=50.0)
    ap.add_argument("--trace", action="store_true",
                    help="print the 2 s before each contact, every 0.2 s")
    a = ap.parse_args()
    logging.basicConfig(level=logging.WARNING)
    logging.getLogger("sim_robot").setLevel(logging.ERROR)
    out = [run(s, a.crowd, a.meter_dwell, a.trace) for s in a.seeds]
    print("total: contacts {} (while moving {}, struck while stopped {}); all points "
          "inspected on {}/{} seeds".format(
              sum(r["contacts"] for r in out), sum(r["moving"] for r in out),
              sum(r["stopped"] for r in out),
              sum(r["inspected"] == r["points"] and r["state"] == "done" for r in out),
              len(out)))
    return 0 if all(r["contacts"] == 0 and r["state"] == "done" for r in out) else 1


if __name__ == "__main__":
    sys.exit(main())

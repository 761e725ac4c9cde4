"""Patrol bench: the whole default route, headless, with walkers and the cart.

    .venv/bin/python bench/patrol_bench.py                    # relay at 20x + offline
    .venv/bin/python bench/patrol_bench.py --mode offline --seeds 1 2 3 4 5

``relay``: an in-process SimRobot (MCU model on a pty, relay threads, the
navigation loop paced in wall time) at ``--time-scale``; the patrol is started
with the desk's command. ``offline``: the world, the MCU model and the
navigation stack stepped in lock-step (sim_robot.patrol_sim), as fast as the
host allows. Prints points reached, collisions, path length, patrol duration
(sim), control step ms (median / p95), replans and avoidance episodes; each
collision with the robot's speed at contact ("struck while stopped" when a
person walked into the robot as it stood).
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

from app.comm.protocol import Command  # noqa: E402
from sim_robot.config import SimConfig  # noqa: E402
from sim_robot.patrol_sim import OfflinePatrol  # noqa: E402
from sim_robot.route import DEFAULT_ROUTE, load_route  # noqa: E402
from sim_robot.sim import SimRobot  # noqa: E402
from sim_robot.world import Walker, World  # noqa: E402

CROSSING_Y = (14.0, 18.0, 29.0, 31.5, 42.0, 50.0)


def add_crowd(world: World, n: int, seed: int) -> None:
    """``n`` extra workers walking across the north-south road (x 52.5..59.4),
    where the route runs, with short pauses: a stress test for avoidance."""
    rng = np.random.default_rng(seed + 77)
    for i, y in enumerate(CROSSING_Y[:n]):
        world.walkers.append(Walker({"id": f"crosser-{i}", "path": [[52.5, y], [59.4, y]],
                                     "speed_mps": float(rng.uniform(0.5, 1.0)),
                                     "pause_s": 5.0, "radius_m": 0.25},
                                    float(rng.uniform(0, 60))))


def watch_speed(world: World) -> list[tuple[float, float]]:
    """Record (sim time, robot speed) at every motion step of the world, so a
    contact can be told apart: the robot moving, or standing when struck."""
    log: list[tuple[float, float]] = []
    move = world.move_robot

    def move_robot(v, omega, dt, radius_m, *when):
        log.append((world.clock(), float(v)))
        return move(v, omega, dt, radius_m, *when)

    world.move_robot = move_robot
    return log


def time_planner(planner) -> dict[str, list[float]]:
    """Time each HybridPlanner.step in the calling thread's CPU time (less
    sensitive to other load than wall time), steps that replan apart."""
    out: dict[str, list[float]] = {"step": [], "replan": []}
    step = planner.step

    def timed(*args, **kwargs):
        n, c0 = planner.replan_count, time.thread_time()
        res = step(*args, **kwargs)
        out["replan" if planner.replan_count > n else "step"].append(
            (time.thread_time() - c0) * 1e3)
        return res

    planner.step = timed
    return out


def planner_line(times: dict[str, list[float]]) -> str:
    st = np.array(times["step"]) if times["step"] else np.zeros(1)
    rp = np.array(times["replan"]) if times["replan"] else np.full(1, np.nan)
    return (f"    planner step ms (CPU) med {np.median(st):.3f} p95 {np.percentile(st, 95):.3f} "
            f"max {st.max():.1f}; replanning steps {len(times['replan'])}, ms med "
            f"{np.median(rp):.2f} max {np.max(rp):.1f}")


class Tracer:
    """``--trace``: keep the last ``keep_s`` sim seconds of navigation steps
    (wall and sim time, true pose and speed, the command, the planner's mode,
    the tracked obstacles and every person's true position) and print them
    before each contact, so a contact can be explained after the run."""

    def __init__(self, world: World, nav, keep_s: float = 4.0) -> None:
        self.world, self.nav, self.keep_s = world, nav, keep_s
        self.rows: list[tuple] = []
        self.dumps: list[list[tuple]] = []
        step = nav.step

        def traced(t, dt, odom, *rest):
            out = step(t, dt, odom, *rest)
            p = world.pose
            self.rows.append((time.perf_counter(), t, p.x, p.y, p.theta, p.v, out[0], out[1],
                              nav.executor.planner.mode, nav.obstacles.copy(),
                              world.people(t).copy(), world.mover_ids()))
            while self.rows and self.rows[0][1] < t - keep_s:
                self.rows.pop(0)
            return out

        nav.step = traced
        on = world.on_collision

        def hit(rec):
            self.dumps.append((rec, list(self.rows)))
            if on is not None:
                on(rec)

        world.on_collision = hit

    def print(self) -> None:
        for rec, rows in self.dumps:
            print(f"    trace before {rec}:")
            last_wall = None
            for wall, t, x, y, th, v, cv, cw, mode, obs, ppl, ids in rows[::2]:
                gap = 0.0 if last_wall is None else (wall - last_wall) * 1e3
                last_wall = wall
                d = np.hypot(ppl[:, 0] - x, ppl[:, 1] - y) - ppl[:, 2] if len(ppl) else []
                k = int(np.argmin(d)) if len(d) else -1
                near = f"{ids[k]} surf {d[k] - 0.25:.2f} at ({ppl[k, 0]:.2f},{ppl[k, 1]:.2f})" \
                    if k >= 0 else "-"
                tr = "-"
                if len(obs):
                    do = np.hypot(obs[:, 0] - x, obs[:, 1] - y) - obs[:, 4]
                    j = int(np.argmin(do))
                    o = obs[j]
                    tr = (f"({o[0]:.2f},{o[1]:.2f}) v ({o[2]:+.2f},{o[3]:+.2f}) r {o[4]:.2f}")
                print(f"      t {t:8.2f} gap {gap:5.1f} ms  robot ({x:.2f},{y:.2f},"
                      f"{math.degrees(th):+5.0f}°) v {v:+.2f} cmd ({cv:+.2f},{cw:+.2f}) "
                      f"{mode:9s} nearest {near}  tracked {tr}")


def report_collisions(collisions: list[dict], speeds: list[tuple[float, float]]) -> int:
    """Print each contact with the robot's speed then; returns how many found
    the robot standing (|v| < 0.01 m/s: struck while stopped)."""
    t = np.array([s[0] for s in speeds]) if speeds else np.zeros(0)
    standing = 0
    for c in collisions:
        i = int(np.searchsorted(t, c["t_s"] + 1e-6)) - 1
        v = speeds[i][1] if i >= 0 else 0.0
        stood = abs(v) < 0.01 and c["what"] != "static"
        standing += stood
        print("    collision:", c, f"robot v {v:.2f} m/s",
              "— struck while stopped" if stood else "", flush=True)
    return standing


def _row(mode, seed, state, reached, n, collisions, nav, ex, t_sim, wall, min_clear):
    sm = np.array(nav.step_ms) if nav.step_ms else np.zeros(1)
    c = ex.counts()
    return (f"{mode:8s} seed {seed}: {state:7s} points {reached}/{n}  collisions {collisions}  "
            f"driven {c['driven_m']:.1f} m (plans {c['path_length_m']:.1f} m)  "
            f"sim {t_sim:.0f} s  wall {wall:.1f} s  "
            f"step ms {np.median(sm):.2f} / {np.percentile(sm, 95):.2f}  "
            f"replans {c['replans']}  avoid episodes {c['avoid_episodes']}  "
            f"skipped {c['skipped']}  min clearance {min_clear:.2f} m")


def run_offline(seed: int, crowd: int = 0, meter_dwell: float = 0.0,
                trace: bool = False) -> tuple[str, int]:
    route = load_route(DEFAULT_ROUTE)
    for p in route.points:  # the relay's wall-time inspection, in sim seconds
        if p.gauge:
            p.dwell_s = max(p.dwell_s, meter_dwell)
    op = OfflinePatrol(SimConfig(seed=seed, video=False))
    add_crowd(op.world, crowd, seed)
    speeds = watch_speed(op.world)
    op.nav.warm_up()  # as the relay does before its first mission
    ptimes = time_planner(op.nav.executor.planner)
    tracer = Tracer(op.world, op.nav) if trace else None
    t0 = time.perf_counter()
    state = op.run(route, max_sim_s=1800)
    wall = time.perf_counter() - t0
    reached = len(op.codes("point_reached"))
    print(_row("offline", seed, state, reached, len(route.points), len(op.world.collisions),
               op.nav, op.nav.executor, op.t, wall, op.min_clearance_m), flush=True)
    print(planner_line(ptimes), flush=True)
    report_collisions(op.world.collisions, speeds)
    if tracer:
        tracer.print()
    return state, len(op.world.collisions)


def run_relay(seed: int, scale: float, crowd: int = 0, trace: bool = False
              ) -> tuple[str, int]:
    route = load_route(DEFAULT_ROUTE)
    robot = SimRobot(SimConfig(seed=seed, video=False, time_scale=scale))
    add_crowd(robot.world, crowd, seed)
    speeds = watch_speed(robot.world)
    robot.start()
    try:
        if not robot.relay.nav_ready.wait(60):
            raise RuntimeError("navigation did not start")
        ptimes = time_planner(robot.relay.nav.executor.planner)
        tracer = Tracer(robot.world, robot.relay.nav) if trace else None
        ok, why = robot.relay.handle_command(Command("start_patrol", {}))
        if not ok:
            raise RuntimeError(why)
        ex = robot.relay.nav.executor
        t0 = time.perf_counter()
        s0 = robot.clock.now()
        min_clear = math.inf
        while ex.owns_motors and time.perf_counter() - t0 < 1800 / scale + 60:
            p = robot.world.pose
            min_clear = min(min_clear, robot.world.clearance(p.x, p.y))
            time.sleep(0.05)
        wall = time.perf_counter() - t0
        reached = sum(p["state"] == "done" for p in ex.status().points)
        print(_row(f"relay{scale:g}x", seed, ex.state, reached, len(route.points),
                   len(robot.world.collisions), robot.relay.nav, ex, robot.clock.now() - s0,
                   wall, min_clear), flush=True)
        print(planner_line(ptimes), flush=True)
        report_collisions(robot.world.collisions, speeds)
        if tracer:
            tracer.print()
        return ex.state, len(robot.world.collisions)
    finally:
        robot.close()


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mode", choices=("relay", "offline", "both"), default="both")
    ap.add_argument("--time-scale", type=float, default=20.0)
    ap.add_argument("--seeds", type=int, nargs="+", default=[1])
    ap.add_argument("--crowd", type=int, default=0, metavar="N",
                    help=f"add N (<= {len(CROSSING_Y)}) workers crossing the route's road")
    ap.add_argument("--meter-dwell", type=float, default=0.0, metavar="S",
                    help="offline: each meter point dwells at least S sim seconds (50 is "
                         "what the relay's 2.5 s wall-time inspection costs at 20x)")
    ap.add_argument("--trace", action="store_true",
                    help="print the navigation steps of the last seconds before each contact")
    a = ap.parse_args()
    logging.basicConfig(level=logging.WARNING)
    logging.getLogger("sim_robot").setLevel(logging.ERROR)  # gas alarms etc. are not news here
    bad = 0
    for seed in a.seeds:
        if a.mode in ("offline", "both"):
            state, col = run_offline(seed, a.crowd, a.meter_dwell, a.trace)
            bad += state != "done" or col > 0
        if a.mode in ("relay", "both"):
            state, col = run_relay(seed, a.time_scale, a.crowd, a.trace)
            bad += state != "done" or col > 0
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())

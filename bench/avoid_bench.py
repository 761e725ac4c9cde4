"""Moving-obstacle avoidance: the hybrid planner with APF or DWA as local planner.

Random scenarios on a 12 m × 12 m yard (0.05 m cells) with box and tank
obstacles; 1–5 moving obstacles (discs, r 0.2–0.35 m, 0.03–0.12 m/s) are
launched so that each crosses the robot's static path near the time the robot
gets there; none is drawn within 0.3 m of the robot's start or goal.
Obstacles do not react to the robot and are seen (position, velocity, radius)
within the sensing range of the robot's centre (3 m; 8 m at station speeds,
the patrol tracker's range; --sense-m overrides). The robot is a unicycle with
seed 003's Table 3 limits (0.15 m/s, 0.5 rad/s). Reported per local planner:
goal reached, collisions, contacts "struck while stopped", travelled length
over the static optimum, and the time of one control step — steps that
replan apart from the others, in wall time and in the thread's CPU time
(less sensitive to other load on the machine), after a warm-up scenario has
loaded the compiled kernels. The static optimum is the length of the
any-angle shortened A* path on the inflated map.

    .venv/bin/python bench/avoid_bench.py [--n 200] [--seed 1] [--config table3|station]

--config station: station-realistic speeds instead — the robot of
sim_robot's patrol (0.6 m/s, may back away at 0.2 m/s, 1 rad/s, 0.5 m/s²,
2 rad/s²) and walkers at 0.5–1.4 m/s.

Every contact is listed (scenario, obstacle, time, robot speed, planner
status). A scenario counts as a collision when the robot touches a wall, or
touches a moving obstacle while moving or while an escape still existed.
Contacts where a moving obstacle runs into the robot while it stands
(|v| < 0.01 m/s) and, from the robot's state 1 s before contact, no motion
within its kinematic limits (any target (v, ω) on an 11 × 11 grid over
[v_min, v_max] × [−ω_max, ω_max], reached at the acceleration limits and
held) would have kept it clear of every obstacle (true future positions) and
of the walls for 3 s are counted apart, as "struck while stopped".
"""

from __future__ import annotations

import argparse
import gc
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from app.core.planner import GridMap, astar  # noqa: E402
from app.core.planner.anyangle import polyline_length, shorten  # noqa: E402
from app.core.planner.dwa import Kinematics  # noqa: E402
from app.core.planner.hybrid import (  # noqa: E402
    NO_PATH,
    REACHED,
    HybridConfig,
    HybridPlanner,
    rollout_ramp,
)

RES = 0.05
SIZE_M = 12.0
ROBOT_R = 0.25
DT = 0.1
SPAWN_GAP_M = 0.3  # an obstacle is never drawn closer than this to the robot's start or goal
CONFIGS = {
    # seed 003 Table 3 robot; obstacles slower than it
    "table3": {"kin": Kinematics(), "obs_speed": (0.03, 0.12), "sense_m": 3.0},
    # sim_robot's patrol robot; people walking
    "station": {
        "kin": Kinematics(
            v_max_mps=0.6, v_min_mps=-0.2, omega_max_rps=1.0, accel_mps2=0.5, alpha_rps2=2.0
        ),
        "obs_speed": (0.5, 1.4),
        # what the patrol's tracker uses (sim_robot/tracker.py, range_max_m)
        "sense_m": 8.0,
    },
}


def make_world(rng: np.random.Generator) -> GridMap:
    n = int(SIZE_M / RES)
    b = np.zeros((n, n), bool)
    yy, xx = np.mgrid[0:n, 0:n]
    for _ in range(rng.integers(3, 7)):
        if rng.random() < 0.5:  # tank
            cx, cy, r = rng.uniform(2, 10), rng.uniform(2, 10), rng.uniform(0.4, 1.0)
            b |= (xx * RES - cx) ** 2 + (yy * RES - cy) ** 2 <= r * r
        else:  # box / pipe rack
            x0, y0 = rng.uniform(1, 10), rng.uniform(1, 10)
            w, h = rng.uniform(0.3, 2.0), rng.uniform(0.3, 2.0)
            b[int(y0 / RES) : int((y0 + h) / RES), int(x0 / RES) : int((x0 + w) / RES)] = True
    b[:2, :] = b[-2:, :] = True
    b[:, :2] = b[:, -2:] = True
    return GridMap(b, RES, (0.0, 0.0))


def scenario(rng, hp: HybridPlanner, grid: GridMap, obs_speed=(0.03, 0.12)):
    """Start, goal, static path and obstacles; None when the draw is unusable."""
    free = grid.distance_m > ROBOT_R + 0.15
    cells = np.argwhere(free)
    for _ in range(50):
        a, b = cells[rng.integers(len(cells))], cells[rng.integers(len(cells))]
        sa, sb = grid.cell_to_world(*a), grid.cell_to_world(*b)
        if math.dist(sa, sb) >= 6.0:
            break
    else:
        return None
    path = np.asarray(hp.plan(sa, sb))
    if len(path) < 2:
        return None
    opt = astar(hp.inflated.blocked, tuple(a), tuple(b))
    if not opt.found:
        return None
    # Static optimum: the any-angle (line-of-sight shortened) A* path, metres.
    opt_m = polyline_length(shorten(hp.inflated.blocked, opt.cells)) * RES
    seg = np.linalg.norm(np.diff(path, axis=0), axis=1)
    s = np.concatenate([[0], np.cumsum(seg)])
    v_nom = 0.7 * hp.cfg.kin.v_max_mps
    obstacles = []
    for _ in range(rng.integers(1, 6)):
        si = rng.uniform(0.2, 0.85) * s[-1]
        i = min(int(np.searchsorted(s, si)), len(path) - 1)
        p = path[i]
        tang = path[min(i + 1, len(path) - 1)] - path[max(i - 1, 0)]
        ang = math.atan2(tang[1], tang[0]) + rng.choice([-1, 1]) * rng.uniform(
            math.radians(45), math.radians(135)
        )
        u = rng.uniform(*obs_speed)
        t_hit = si / v_nom + rng.uniform(-10, 10) * 0.15 / hp.cfg.kin.v_max_mps
        d = np.array([math.cos(ang), math.sin(ang)])
        p0 = p - d * u * max(t_hit, 0.0)
        r = rng.uniform(0.2, 0.35)
        if min(math.dist(p0, sa), math.dist(p0, sb)) < r + ROBOT_R + SPAWN_GAP_M:
            continue  # never drawn on (or touching) the robot at its start, nor on the goal
        obstacles.append([p0[0], p0[1], u * d[0], u * d[1], r])
    if not obstacles:
        return None
    init_th = math.atan2(path[1][1] - path[0][1], path[1][0] - path[0][0])
    return np.array(sa), init_th, np.array(sb), opt_m, np.array(obstacles)


def escape_existed(grid, hp: HybridPlanner, state, obs, horizon=3.0) -> bool:
    """Whether some motion within the robot's limits, started from state
    (x, y, θ, v, ω), keeps clear of obstacles obs (positions at that moment,
    true velocities) and of the walls over the horizon."""
    k = hp.cfg.kin
    x, y, th, v, w = state
    dist = np.ascontiguousarray(grid.distance_m, dtype=np.float64)
    for tv in np.linspace(k.v_min_mps, k.v_max_mps, 11):
        for tw in np.linspace(-k.omega_max_rps, k.omega_max_rps, 11):
            ds, dm, _ = rollout_ramp(
                x,
                y,
                th,
                v,
                w,
                tv,
                tw,
                k.accel_mps2,
                k.alpha_rps2,
                horizon,
                DT / 2,
                dist,
                RES,
                0.0,
                0.0,
                obs,
                ROBOT_R,
            )
            if min(ds, dm) > 0.0:
                return True
    return False


def run(local: str, scenarios, worlds, max_time_factor=4.0, kin=None, sense_m=3.0):
    out = {
        "reached": 0,
        "collided": 0,  # scenarios with a contact the robot is to blame for
        "struck_stopped": 0,  # scenarios whose only contacts hit a standing robot with no escape
        "ratio": [],
        "step_ms": [],  # steps that did not replan
        "replan_ms": [],  # steps that replanned
        "step_cpu_ms": [],  # the same, in this thread's CPU time (less sensitive to load)
        "replan_cpu_ms": [],
        "gc_step": [],  # per non-replanning step: did a garbage collection run inside it
        "gc_ms": [],  # the collections' own durations
        "governor": 0,
        "estop": 0,
        "hits": [],
        "replans": 0,
        "n": 0,
    }
    gc_runs = [0]
    gc_t0 = [0.0]

    def on_gc(phase, _info):
        if phase == "start":
            gc_runs[0] += 1
            gc_t0[0] = time.perf_counter()
        else:
            out["gc_ms"].append((time.perf_counter() - gc_t0[0]) * 1e3)

    gc.callbacks.append(on_gc)
    try:
        _run(local, scenarios, worlds, max_time_factor, kin, sense_m, out, gc_runs)
    finally:
        gc.callbacks.remove(on_gc)
    return out


def _run(local, scenarios, worlds, max_time_factor, kin, sense_m, out, gc_runs):
    for idx, ((start, th, goal, opt_m, obs0), grid) in enumerate(
        zip(scenarios, worlds, strict=True)
    ):
        cfg = HybridConfig(robot_radius_m=ROBOT_R, local_planner=local)
        if kin is not None:
            cfg.kin = kin
        hp = HybridPlanner(grid, cfg)
        if not hp.plan(tuple(start), tuple(goal)):
            continue
        out["n"] += 1
        x, y = start
        v = w = 0.0
        obs = obs0.copy()
        travelled = 0.0
        t_max = max_time_factor * opt_m / hp.cfg.kin.v_max_mps + 30.0
        t = 0.0
        status = ""
        history = []  # (x, y, θ, v, ω, obstacles) per step
        touching = np.zeros(len(obs), bool)
        on_wall = False
        hits = []  # one per contact onset: (t, v, status, what, to blame)
        while t < t_max:
            history.append((x, y, th, v, w, obs.copy()))
            seen = obs[np.hypot(obs[:, 0] - x, obs[:, 1] - y) < sense_m]
            n_replans = hp.replan_count
            g0 = gc_runs[0]
            t0, c0 = time.perf_counter(), time.thread_time()
            cv, cw, status = hp.step((x, y, th), (v, w), seen, DT)
            ms = (time.perf_counter() - t0) * 1e3
            cpu_ms = (time.thread_time() - c0) * 1e3
            kind = "replan" if hp.replan_count > n_replans else "step"
            out[kind + "_ms"].append(ms)
            out[kind + "_cpu_ms"].append(cpu_ms)
            if kind == "step":
                out["gc_step"].append(gc_runs[0] != g0)
            if status in (REACHED, NO_PATH):
                break
            k = hp.cfg.kin
            assert k.v_min_mps - 1e-9 <= cv <= k.v_max_mps + 1e-9
            assert abs(cw) <= k.omega_max_rps + 1e-9
            v, w = cv, cw
            nx, ny = x + v * math.cos(th) * DT, y + v * math.sin(th) * DT
            travelled += math.hypot(nx - x, ny - y) if cv >= 0 else 0.0
            x, y, th = nx, ny, th + w * DT
            obs[:, 0] += obs[:, 2] * DT
            obs[:, 1] += obs[:, 3] * DT
            t += DT
            now = np.hypot(obs[:, 0] - x, obs[:, 1] - y) < obs[:, 4] + ROBOT_R
            for m in np.flatnonzero(now & ~touching):
                # Struck while stopped: the robot stood, and from its state 1 s
                # before no motion within its limits would have kept it clear.
                back = max(0, len(history) - int(round(1.0 / DT)))
                hx, hy, hth, hv, hw, hobs = history[back]
                stopped = abs(v) < 0.01 and not escape_existed(
                    grid, hp, (hx, hy, hth, hv, hw), hobs
                )
                hits.append((t, v, status, f"moving obstacle {m}", not stopped))
            touching = now
            wall = not grid.is_free_xy(x, y) or grid.distance_m[grid.world_to_cell(x, y)] < ROBOT_R
            if wall and not on_wall:
                hits.append((t, v, status, "wall", True))
            on_wall = wall
        if hits:
            blamed = any(h[4] for h in hits)
            out["collided"] += blamed
            out["struck_stopped"] += not blamed
            for h in hits:
                out["hits"].append((idx, len(obs0), *h, hp.cornered_count, hp.estop_count))
        out["reached"] += status == REACHED
        out["governor"] += hp.governor_count
        out["estop"] += hp.estop_count
        out["replans"] += hp.replan_count
        if status == REACHED:
            out["ratio"].append(travelled / opt_m)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", choices=sorted(CONFIGS), default="table3")
    ap.add_argument("--n", type=int, default=200, help="scenarios")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--planners", default="apf,dwa")
    ap.add_argument("--only", default="", help="comma-separated scenario numbers to run")
    ap.add_argument(
        "--sense-m", type=float, default=None, help="sensing range (default: per config)"
    )
    args = ap.parse_args(argv)
    conf = CONFIGS[args.config]
    rng = np.random.default_rng(args.seed)
    scenarios, worlds = [], []
    while len(scenarios) < args.n:
        grid = make_world(rng)
        hp = HybridPlanner(grid, HybridConfig(robot_radius_m=ROBOT_R))
        hp.cfg.kin = conf["kin"]
        sc = scenario(rng, hp, grid, conf["obs_speed"])
        if sc is not None:
            scenarios.append(sc)
            worlds.append(grid)
    if args.only:
        keep = [int(i) for i in args.only.split(",")]
        scenarios = [scenarios[i] for i in keep]
        worlds = [worlds[i] for i in keep]
    n_obs = [len(s[4]) for s in scenarios]
    print(
        f"config {args.config}: robot v {conf['kin'].v_min_mps}..{conf['kin'].v_max_mps} m/s, "
        f"obstacles {conf['obs_speed'][0]}..{conf['obs_speed'][1]} m/s, seed {args.seed}"
    )
    print(
        f"{len(scenarios)} scenarios, moving obstacles per scenario: "
        f"{np.bincount(n_obs, minlength=6)[1:].tolist()} (1..5)"
    )
    sense_m = args.sense_m if args.sense_m is not None else conf["sense_m"]
    print(f"moving obstacles seen within {sense_m:g} m of the robot's centre")
    print(
        f"{'local planner':14} {'reached':>9} {'collisions':>11} {'struck stopped':>15} "
        f"{'len/opt med':>12} {'p95':>6} {'step ms med':>12} {'p95':>6} {'max':>6} "
        f"{'replan ms med':>14} {'max':>6} {'governor':>9} {'e-stop':>7}"
    )
    for local in args.planners.split(","):
        # Warm-up: the kernels loaded (or compiled) as the robot does at start.
        HybridPlanner(
            worlds[0], HybridConfig(robot_radius_m=ROBOT_R, local_planner=local, kin=conf["kin"])
        ).warm_up()
        run(local, scenarios[:1], worlds[:1], kin=conf["kin"], sense_m=sense_m)
        t0 = time.perf_counter()
        r = run(local, scenarios, worlds, kin=conf["kin"], sense_m=sense_m)
        ratio = np.array(r["ratio"]) if r["ratio"] else np.array([np.nan])
        st = np.array(r["step_ms"])
        rp = np.array(r["replan_ms"]) if r["replan_ms"] else np.array([np.nan])
        print(
            f"{local + '-hybrid':14} {r['reached']:>4}/{r['n']:<4} {r['collided']:>11} "
            f"{r['struck_stopped']:>15} "
            f"{np.median(ratio):>12.3f} {np.percentile(ratio, 95):>6.3f} "
            f"{np.median(st):>12.3f} {np.percentile(st, 95):>6.3f} {st.max():>6.1f} "
            f"{np.median(rp):>14.2f} {np.max(rp):>6.1f} "
            f"{r['governor']:>9} {r['estop']:>7}   ({len(rp) if r['replan_ms'] else 0} replans, "
            f"{time.perf_counter() - t0:.0f} s)"
        )
        sc = np.array(r["step_cpu_ms"])
        rc = np.array(r["replan_cpu_ms"]) if r["replan_cpu_ms"] else np.array([np.nan])
        print(
            f"{'':14} thread CPU time: step ms med {np.median(sc):.3f} p95 "
            f"{np.percentile(sc, 95):.3f} max {sc.max():.1f}; replan ms med "
            f"{np.median(rc):.2f} max {np.max(rc):.1f}"
        )
        g = np.array(r["gc_step"], bool)
        gm = np.array(r["gc_ms"]) if r["gc_ms"] else np.zeros(1)
        print(
            f"{'':14} garbage collections ran inside {g.sum()} of {len(g)} steps (longest "
            f"{gm.max():.1f} ms); step max without one: wall {st[~g].max():.1f} ms, "
            f"CPU {sc[~g].max():.1f} ms"
        )
        for idx, n, t, v, status, what, blamed, cornered, estop in r["hits"]:
            print(
                f"{'':14} scenario {idx}: {n} obstacles, {what} at t={t:.1f} s, "
                f"robot v={v:.3f} m/s, status {status}, cornered steps {cornered}, "
                f"e-stop steps {estop}" + ("" if blamed else " — struck while stopped, no escape")
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

"""CPU the simulated robot spends per simulated second, by component.

Runs the patrol in lock-step in this process (:class:`OfflinePatrol`, the
skid-steer robot, and :class:`FwsOfflinePatrol`, the 4WS one; no threads,
sockets or desk), on the default route with the crowd of workers crossing the
road, as tests/sim/test_patrol_crowd.py and tests/sim/test_fws_patrol.py run
them, and charges the process's CPU time (``time.process_time``) to the
component running: each timed function's time excludes the timed functions
it calls (the lidar's scan excludes the people model it asks where the
people are, and so on). "other" is the loop and everything untimed.

    python bench/sim_cpu_bench.py [--sim-s 300] [--robot skid|fws|both] [--root DIR]
    python bench/sim_cpu_bench.py --threaded 36 [--wall-s 40] [--robot skid|fws]

``--threaded SCALE`` runs the robot as ``python -m sim_robot`` does instead
(SimRobot: its MCU model's, navigation's and relay's threads on the sim clock
at time scale SCALE; no desk connected, so no camera frames or messages), starts
the default patrol with the crowd, and prints the process's CPU per sim second
and each thread's share (read from /proc, Linux only), until the patrol ends
or ``--wall-s`` have passed.

``--root`` imports the robot from another checkout (for before/after figures
of the same bench). Camera frames are not drawn here (the relay draws them only
while a desk is connected), nor are messages encoded for a desk.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

# component: (module, class or None, attribute) — timed exclusive of the others
TIMED = {
    "lidar ray casting": ("sim_robot.lidar", "Lidar", "scan"),
    "ultrasonic ray casting (board)": ("sim_robot.sensors", "Ultrasonic", "sample"),
    "people/vehicles model": ("sim_robot.world", "World", "people"),
    "body motion + contacts": ("sim_robot.world", "World", "move_robot"),
    "board model (other)": ("sim_robot.mcu", "McuModel", "step"),
    "serial frames (encode/decode)": ("sim_robot.patrol_sim", "OfflinePatrol", "_send"),
    "odometry": ("sim_robot.odometry", "Odometry", "update"),
    "localisation (scan match)": ("sim_robot.navigation", "Navigation", "_localise_waiting"),
    "tracker": ("sim_robot.tracker", "ObstacleTracker", "detect"),
    "tracker ": ("sim_robot.tracker", "ObstacleTracker", "update"),
    "mission + planner": ("sim_robot.patrol", "PatrolExecutor", "tick"),
    "navigation (other)": ("sim_robot.navigation", "Navigation", "step"),
}


class Meter:
    """Exclusive CPU time per component: the innermost timed call is charged."""

    def __init__(self) -> None:
        self.cpu: dict[str, float] = {}
        self.calls: dict[str, int] = {}
        self._stack: list[str] = []
        self._last = time.process_time()

    def _switch(self) -> None:
        t = time.process_time()
        if self._stack:
            top = self._stack[-1]
            self.cpu[top] = self.cpu.get(top, 0.0) + t - self._last
        self._last = t

    def wrap(self, name: str, fn):
        def timed(*a, **k):
            self._switch()
            if not self._stack or self._stack[-1] != name:  # (a subclass's step calls its base's)
                self.calls[name] = self.calls.get(name, 0) + 1
            self._stack.append(name)
            try:
                return fn(*a, **k)
            finally:
                self._switch()
                self._stack.pop()
        return timed


def instrument(meter: Meter) -> list:
    import importlib

    undo = []
    for name, (mod, cls, attr) in TIMED.items():
        owner = getattr(importlib.import_module(mod), cls)
        if attr not in vars(owner):
            continue
        fn = vars(owner)[attr]
        setattr(owner, attr, meter.wrap(name.strip(), fn))
        undo.append((owner, attr, fn))
    # the 4WS board's own step (a subclass of the skid-steer board's)
    fws = importlib.import_module("sim_robot.fws_mcu")
    for cls in vars(fws).values():
        if isinstance(cls, type) and "step" in vars(cls) and cls.__module__ == fws.__name__:
            fn = vars(cls)["step"]
            cls.step = meter.wrap("board model (other)", fn)
            undo.append((cls, "step", fn))
    return undo


def _patrol_bench():
    """bench/patrol_bench.py (its crowd of workers crossing the road)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("patrol_bench",
                                                  ROOT / "bench" / "patrol_bench.py")
    pb = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(pb)
    return pb


def run(robot: str, sim_s: float, seed: int, crowd: int) -> None:
    from sim_robot.config import SimConfig
    from sim_robot.fws_robot import FwsOfflinePatrol
    from sim_robot.patrol_sim import OfflinePatrol
    from sim_robot.route import DEFAULT_ROUTE, load_route

    pb = _patrol_bench()
    route = load_route(DEFAULT_ROUTE)
    for p in route.points:
        if p.gauge:
            p.dwell_s = 50.0
    cls = FwsOfflinePatrol if robot == "fws" else OfflinePatrol
    op = cls(SimConfig(seed=seed, video=False))
    pb.add_crowd(op.world, crowd, seed)
    op.nav.warm_up()
    ok, why = op.nav.executor.start(route, op.t)
    assert ok, why
    for _ in range(20):  # kernels loaded, first plan made
        op.step()
    meter = Meter()
    undo = instrument(meter)
    try:
        t0, c0, w0 = op.t, time.process_time(), time.perf_counter()
        meter._last = c0
        while op.t < t0 + sim_s:
            op.step()
        sim = op.t - t0
        cpu = time.process_time() - c0
        wall = time.perf_counter() - w0
    finally:
        for owner, attr, fn in undo:
            setattr(owner, attr, fn)
    print(f"\n{robot} robot, seed {seed}, {crowd} crossing workers: {sim:.0f} s of sim time, "
          f"{cpu:.2f} s CPU ({wall:.2f} s wall), {cpu / sim * 1000:.1f} ms CPU per sim s, "
          f"state {op.nav.executor.state}")
    rows = sorted(meter.cpu.items(), key=lambda kv: -kv[1])
    rows.append(("other (loop, untimed)", cpu - sum(meter.cpu.values())))
    for name, c in rows:
        print(f"  {name:32s} {c / sim * 1000:7.2f} ms/sim s  {100 * c / cpu:5.1f} %"
              f"  {meter.calls.get(name, 0):7d} calls")


def _thread_cpu() -> dict[str, float]:
    """CPU seconds of each of this process's threads, by Python thread name."""
    import os
    import threading

    names = {t.native_id: t.name for t in threading.enumerate()}
    tick = os.sysconf("SC_CLK_TCK")
    out: dict[str, float] = {}
    for tid in os.listdir("/proc/self/task"):
        try:
            with open(f"/proc/self/task/{tid}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        name = names.get(int(tid), "other (numba, numpy, OpenCV pools)")
        out[name] = out.get(name, 0.0) + (int(fields[11]) + int(fields[12])) / tick
    return out


def run_threaded(robot: str, scale: float, wall_s: float, seed: int, crowd: int) -> None:
    from sim_robot.config import SimConfig
    from sim_robot.fws_robot import FwsSim
    from sim_robot.patrol import ACTIVE
    from sim_robot.route import DEFAULT_ROUTE
    from sim_robot.sim import SimRobot

    pb = _patrol_bench()
    cls = FwsSim if robot == "fws" else SimRobot
    r = cls(SimConfig(seed=seed, video=False, time_scale=scale))
    pb.add_crowd(r.world, crowd, seed)
    r.start()
    try:
        r.relay.nav_ready.wait(600)
        time.sleep(2.0)
        route = json.loads(DEFAULT_ROUTE.read_text(encoding="utf-8"))
        for p in route["points"]:  # the meter stops as long as the tests make them
            if p.get("gauge"):
                p["dwell_s"] = 50.0
        with r.relay._lock:
            ok, why = r.relay._mission_command("start_patrol", {"route": route})
        assert ok, why
        time.sleep(2.0)
        ex = r.relay.nav.executor
        c0, s0, w0, th0 = time.process_time(), r.clock.now(), time.monotonic(), _thread_cpu()
        while time.monotonic() - w0 < wall_s and ex.state in ACTIVE:  # until the patrol ends
            time.sleep(0.2)
        cpu, sim, th1 = time.process_time() - c0, r.clock.now() - s0, _thread_cpu()
        wall_s = time.monotonic() - w0
        state = ex.state
    finally:
        r.close()
    print(f"\n{robot} robot threaded at time scale {scale:g}, {crowd} crossing workers: "
          f"{wall_s:.0f} s wall, {sim:.0f} s sim, {cpu:.2f} s CPU = "
          f"{cpu / wall_s * 100:.0f} % of a core, {cpu / sim * 1000:.1f} ms CPU per sim s, "
          f"sim time held back {r.clock.held_s:.1f} s, state {state}")
    for name in sorted(th1, key=lambda n: -(th1[n] - th0.get(n, 0.0))):
        c = th1[name] - th0.get(name, 0.0)
        if c > 0.005 * cpu:
            print(f"  {name:36s} {c / sim * 1000:7.2f} ms/sim s  {100 * c / max(cpu, 1e-9):5.1f} %")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sim-s", type=float, default=300.0)
    ap.add_argument("--robot", choices=("skid", "fws", "both"), default="both")
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--crowd", type=int, default=6)
    ap.add_argument("--root", type=Path, default=ROOT,
                    help="checkout to import app and sim_robot from")
    ap.add_argument("--threaded", type=float, metavar="SCALE",
                    help="run SimRobot's threads at this time scale instead of lock-step")
    ap.add_argument("--wall-s", type=float, default=40.0)
    a = ap.parse_args()
    sys.path.insert(0, str(a.root.resolve()))
    if a.threaded:
        run_threaded("fws" if a.robot == "fws" else "skid", a.threaded, a.wall_s, a.seed,
                     a.crowd)
        return
    for robot in (("skid", "fws") if a.robot == "both" else (a.robot,)):
        run(robot, a.sim_s, a.seed, a.crowd)


if __name__ == "__main__":
    main()

"""The patrol robot on a busy host: the real relay threads (navigation, MCU
model, publishers) in this process at a high time scale, patrolling the
default route again and again; prints what the robot did with the CPU it got.

Prints: wall and sim seconds (the effective time scale), sim time the clock
held back waiting for the navigation (``SimClock.held_s``), navigation steps
and their gaps in sim time (median, 99th percentile, largest), the steps the
staleness cap slowed, how far sim time ran ahead of the MCU model's sampling
(the board's lag: a starved MCU thread caught up in one burst on its last
command), contacts (ground truth, as the world records them), recoveries,
patrols done / failed, points skipped, localisation lost / found again by the
robot itself / not found, and the estimate's error against the truth when it
was lost (the bench may read the truth; the robot never does).

``--burn N`` adds N busy threads to this process, which take the CPU (and the
interpreter lock) from the relay's threads as a loaded host does. ``--idle S``
lets the robot stand S wall seconds with no desk and no mission first (as
before a desk that is slow to start connects) and prints how far its estimate
was off when the first patrol started.

    .venv/bin/python bench/starved_patrol_bench.py --seconds 90 --time-scale 36
    .venv/bin/python bench/starved_patrol_bench.py --seconds 90 --control-lead 0   # no pacing
    .venv/bin/python bench/starved_patrol_bench.py --seconds 300 --burn 2   # starved harder
    .venv/bin/python bench/starved_patrol_bench.py --seconds 90 --burn 2 --idle 30
"""

from __future__ import annotations

import argparse
import logging
import math
import statistics
import sys
import threading
import time
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from sim_robot.config import SimConfig  # noqa: E402
from sim_robot.sim import SimRobot  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=90.0, help="wall seconds to run")
    ap.add_argument("--time-scale", type=float, default=36.0)
    ap.add_argument("--control-lead", type=float, default=getattr(SimConfig, "control_lead_s", 0.0),
                    help="sim seconds the clock may run past the last control step (0: off)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--burn", type=int, default=0, help="busy threads starving the relay")
    ap.add_argument("--idle", type=float, default=0.0,
                    help="wall seconds standing with no desk and no mission first")
    a = ap.parse_args()
    logging.basicConfig(level=logging.ERROR)
    cfg = SimConfig(seed=a.seed, video=False, time_scale=a.time_scale)
    cfg.control_lead_s = a.control_lead  # (a tree without pacing ignores it)
    robot = SimRobot(cfg)
    relay = robot.relay
    steps: list[float] = []
    events: Counter[str] = Counter()
    contacts: list[dict] = []
    lock = threading.Lock()
    paced = getattr(relay, "on_control_step", None)
    if paced is None:  # a tree without pacing: time the steps by the executor's ticks
        tick = relay.nav.executor.tick

        def timed_tick(t, *args):
            steps.append(t)
            return tick(t, *args)
        relay.nav.executor.tick = timed_tick

    board = robot.mcu_thread.model
    lag = [0.0]
    lost_errors: list[tuple[float, float]] = []

    def on_step(t: float) -> None:
        steps.append(t)
        if len(steps) > 100:  # once the board samples (its model's time starts at 0)
            lag[0] = max(lag[0], robot.clock.now() - board.t)
        paced(t)

    def on_event(level, code, text, **data) -> None:
        with lock:
            events[code] += 1
        if code == "localisation_lost":  # how wrong the estimate was (the truth: bench only)
            lost_errors.append(_error(relay.nav.localiser.pose, robot.world.pose))
        emit(level, code, text, **data)

    relay.on_control_step = on_step
    emit = relay.event
    relay.event = on_event
    relay.nav.emit = on_event
    relay.nav.executor.emit = on_event
    robot.world.on_collision = lambda rec: contacts.append(rec)
    route = str(ROOT / "app" / "resources" / "routes" / "default.json")
    stop = threading.Event()

    def burn() -> None:
        x = 0
        while not stop.is_set():
            for i in range(20000):
                x += i * i

    for _ in range(a.burn):
        threading.Thread(target=burn, daemon=True).start()
    operator = [0]  # relocalisation failures the operator has answered
    robot.start()
    t0, cpu0 = time.monotonic(), time.process_time()
    sim0 = robot.clock.now()
    idle_off = None  # the estimate's error when the first patrol started (after --idle)
    try:
        while time.monotonic() - t0 < a.idle:
            time.sleep(0.5)
        if a.idle:
            with relay._lock:
                idle_off = (robot.clock.now() - sim0, *_error(relay.nav.localiser.pose,
                                                              robot.world.pose),
                            relay.nav.localiser.lost)
        while time.monotonic() - t0 < a.seconds:
            time.sleep(0.5)
            ex = relay.nav.executor
            if relay.nav.localiser.lost and events["relocalisation_failed"] > operator[0]:
                # the robot did not find itself: the operator sets its pose (the
                # truth, 5 cm and 2° off, as read off the map) and resumes
                operator[0] = events["relocalisation_failed"]
                p = robot.world.pose
                with relay._lock:
                    relay.nav.set_pose(p.x + 0.05, p.y, p.theta + math.radians(2))
                    ex.resume()
            if not ex.running:
                with relay._lock:
                    relay._mission_command("start_patrol", {"route": _route(route)})
    finally:
        stop.set()
        wall = time.monotonic() - t0
        cpu = time.process_time() - cpu0
        sim = robot.clock.now() - sim0
        held = getattr(robot.clock, "held_s", 0.0)
        nav = relay.nav
        robot.close()
    gaps = sorted(b - a for a, b in zip(steps, steps[1:], strict=False))
    print(f"time scale {a.time_scale:g}x, control lead {a.control_lead:g} s (sim), "
          f"{wall:.0f} s wall, {cpu:.0f} s CPU of this process")
    print(f"sim time {sim:.0f} s: effective scale {sim / wall:.1f}x; held back {held:.0f} s")
    if idle_off is not None:
        print(f"after {a.idle:g} s wall ({idle_off[0]:.0f} s sim) standing with no desk: "
              f"estimate {idle_off[1]:.2f} m / {idle_off[2]:.0f}° off"
              + (", lost" if idle_off[3] else ""))
    if gaps:
        p99 = gaps[min(len(gaps) - 1, int(0.99 * len(gaps)))]
        print(f"navigation steps {len(steps)}: gap median {statistics.median(gaps):.3f} s, "
              f"p99 {p99:.3f} s, largest {gaps[-1]:.3f} s (sim)")
    print(f"speed capped for stale control on {getattr(nav, 'stale_capped', 0)} steps; "
          f"sim time ahead of the MCU model's sampling at most {lag[0]:.1f} s")
    print(f"contacts {len(contacts)}: " + ", ".join(
        f"{c['what']} at ({c['x_m']:.2f}, {c['y_m']:.2f})" for c in contacts[:10]))
    keys = ("patrol_started", "patrol_done", "patrol_failed", "point_skipped", "blocked",
            "recovering", "avoiding")
    print("events: " + ", ".join(f"{k} {events[k]}" for k in keys))
    keys = ("localisation_lost", "localisation_recovered", "relocalisation_failed", "pose_set")
    print("localisation: " + ", ".join(f"{k} {events[k]}" for k in keys) + "".join(
        f"; lost {d:.2f} m / {e:.0f}° off" for d, e in lost_errors))


def _error(est, truth) -> tuple[float, float]:
    """Metres and degrees between the estimate and the truth (the bench may read it)."""
    x, y, th = est
    return (math.hypot(x - truth.x, y - truth.y),
            abs(math.degrees((th - truth.theta + math.pi) % (2 * math.pi) - math.pi)))


def _route(path: str) -> dict:
    import json
    return json.loads(Path(path).read_text(encoding="utf-8"))


if __name__ == "__main__":
    main()

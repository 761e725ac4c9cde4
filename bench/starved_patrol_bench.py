"""The patrol robot on a busy host: the real relay threads (navigation, MCU
model, publishers) in this process at a high time scale, patrolling the
default route again and again; prints what the robot did with the CPU it got.

Prints: wall and sim seconds (the effective time scale), sim time the clock
held back waiting for the navigation (``SimClock.held_s``), navigation steps
and their gaps in sim time (median, 99th percentile, largest), the steps the
staleness cap slowed, contacts (ground truth, as the world records them),
recoveries, patrols done / failed, points skipped.

    .venv/bin/python bench/starved_patrol_bench.py --seconds 90 --time-scale 36
    .venv/bin/python bench/starved_patrol_bench.py --seconds 90 --control-lead 0   # no pacing
"""

from __future__ import annotations

import argparse
import logging
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

    def on_step(t: float) -> None:
        steps.append(t)
        paced(t)

    def on_event(level, code, text, **data) -> None:
        with lock:
            events[code] += 1
        emit(level, code, text, **data)

    relay.on_control_step = on_step
    emit = relay.event
    relay.event = on_event
    relay.nav.emit = on_event
    relay.nav.executor.emit = on_event
    robot.world.on_collision = lambda rec: contacts.append(rec)
    route = str(ROOT / "app" / "resources" / "routes" / "default.json")
    robot.start()
    t0, cpu0 = time.monotonic(), time.process_time()
    sim0 = robot.clock.now()
    try:
        while time.monotonic() - t0 < a.seconds:
            time.sleep(0.5)
            ex = relay.nav.executor
            if not ex.running:
                with relay._lock:
                    relay._mission_command("start_patrol", {"route": _route(route)})
    finally:
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
    if gaps:
        p99 = gaps[min(len(gaps) - 1, int(0.99 * len(gaps)))]
        print(f"navigation steps {len(steps)}: gap median {statistics.median(gaps):.3f} s, "
              f"p99 {p99:.3f} s, largest {gaps[-1]:.3f} s (sim)")
    print(f"speed capped for stale control on {getattr(nav, 'stale_capped', 0)} steps")
    print(f"contacts {len(contacts)}: " + ", ".join(
        f"{c['what']} at ({c['x_m']:.2f}, {c['y_m']:.2f})" for c in contacts[:10]))
    keys = ("patrol_started", "patrol_done", "patrol_failed", "point_skipped", "blocked",
            "recovering", "avoiding")
    print("events: " + ", ".join(f"{k} {events[k]}" for k in keys))


def _route(path: str) -> dict:
    import json
    return json.loads(Path(path).read_text(encoding="utf-8"))


if __name__ == "__main__":
    main()

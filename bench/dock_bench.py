"""The patrol robot standing on its charger for hours: lock-step (no threads,
no sockets), the navigation stepped as the relay steps it between missions
(a scan matched to the map every ``--scan-gap`` seconds of sim time, the
board's DOCKED flag passed on); prints whether it stayed localised.

The desk soak at 36x lost the robot on its dock at robot hour 64: its gyro's
bias had wandered to -0.117 rad/s (the archive's yaw-rate telemetry while it
stood there), the odometry integrated it, and a lapse of the scan matches left
the heading too far off for them to catch it again. ``--bias`` starts the
gyro there (the bias wanders on from it, as the sensor model makes it);
``--scan-gap`` plays a starved host's slow matching (the relay's own is
0.2 s), ``--lapse S`` one lapse of S sim seconds with no scan matched, a third
of the way in (a navigation thread starved, or scans waiting for late odometry).

``--lose-every S`` also throws the robot's estimate off (100° of heading) and
marks it lost every S sim seconds, to count how many of those loss episodes
ended in an event (``localisation_recovered`` or ``relocalisation_failed``)
before the next one — every one should.

Prints: sim hours, losses (own / forced), episodes ended by an event and not,
recovered / failed, the longest episode (sim seconds from the loss to its
event, or to the end of the run when none came), the heading's error against
the truth (the bench may read it; the robot never does): worst while not
lost, and at the end; CPU seconds.

    .venv/bin/python bench/dock_bench.py --hours 0.5 --scan-gap 0.2,2,5
    .venv/bin/python bench/dock_bench.py --hours 0.5 --scan-gap 0.2 --lapse 10
    .venv/bin/python bench/dock_bench.py --hours 0.5 --lose-every 300 --noise 0.05
"""

from __future__ import annotations

import argparse
import logging
import math
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from app.comm.protocol import RobotMode  # noqa: E402
from sim_robot.config import SimConfig  # noqa: E402
from sim_robot.patrol_sim import OfflinePatrol  # noqa: E402
from sim_robot.world import World  # noqa: E402

SOAK_BIAS_RPS = -0.117  # the soak's gyro on the dock at robot hour 64


def run(hours: float, scan_gap_s: float, bias: float, lose_every_s: float,
        noise: float, seed: int, lapse_s: float = 0.0) -> dict:
    cfg = SimConfig(seed=seed, video=False)
    op = OfflinePatrol(cfg)
    op.mcu.imu.bias = bias
    nav, loc = op.nav, op.nav.localiser
    rng = np.random.default_rng(seed)
    step_nav = nav.step

    def noisy_step(t, dt, odom, vel=(0.0, 0.0), *a):
        # the odometry's speeds as a noisy board reports them at rest
        v, w = vel
        return step_nav(t, dt, odom, (v + noise * rng.standard_normal(),
                                      w + noise * rng.standard_normal()), *a)

    nav.step = noisy_step
    ended = {"localisation_recovered", "relocalisation_failed"}
    episodes = ended_n = open_episode = 0
    lost_t, longest = 0.0, 0.0  # when the open episode began; the longest that ended
    forced = 0
    worst = 0.0
    next_loss = lose_every_s if lose_every_s > 0 else math.inf
    cpu0 = time.process_time()
    end = hours * 3600.0
    lapse = (end / 3, end / 3 + lapse_s)
    seen = 0
    while op.t < end:
        op.step()
        rep = op.mcu.report
        nav.docked = rep is not None and rep.mode == RobotMode.DOCKED
        if not nav.executor.owns_motors and not lapse[0] <= op.t < lapse[1] and (
                nav.scan_t is None or op.t - nav.scan_t >= scan_gap_s - 1e-6):
            nav.perceive(op.t)
        for _, code, _ in op.events[seen:]:
            if code == "localisation_lost":
                episodes += 1
                open_episode, lost_t = 1, op.t
            elif code in ended and open_episode:
                open_episode = 0
                ended_n += 1
                longest = max(longest, op.t - lost_t)
        seen = len(op.events)
        if op.t >= next_loss and op.t < end - 60.0:  # (none left unfinished at the end)
            next_loss += lose_every_s
            x, y, th = loc.pose
            loc.set_pose(x, y, th + math.radians(100))
            loc.map.lost = True
            forced += 1
        truth = World.pose.fget(op.world)  # the bench may read the truth
        if not loc.lost:
            err = abs((loc.pose[2] - truth.theta + math.pi) % (2 * math.pi) - math.pi)
            worst = max(worst, err)
    truth = World.pose.fget(op.world)
    final = abs((loc.pose[2] - truth.theta + math.pi) % (2 * math.pi) - math.pi)
    codes = [c for _, c, _ in op.events]
    return {"hours": op.t / 3600.0, "lost": codes.count("localisation_lost"),
            "forced": forced, "episodes": episodes,
            "unended": episodes - ended_n, "open_at_end": open_episode,
            "longest_s": max(longest, op.t - lost_t if open_episode else 0.0),
            "recovered": codes.count("localisation_recovered"),
            "failed": codes.count("relocalisation_failed"),
            "worst_deg": math.degrees(worst), "final_deg": math.degrees(final),
            "lost_at_end": loc.lost, "gyro_bias_end": op.mcu.imu.bias,
            "cpu_s": time.process_time() - cpu0}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hours", type=float, default=0.5, help="sim hours on the dock")
    ap.add_argument("--scan-gap", default="0.2,2,5",
                    help="sim seconds between scans matched while standing (comma list)")
    ap.add_argument("--bias", type=float, default=SOAK_BIAS_RPS,
                    help="the gyro's bias at the start, rad/s")
    ap.add_argument("--lose-every", type=float, default=0.0,
                    help="throw the estimate off and mark it lost every S sim seconds")
    ap.add_argument("--noise", type=float, default=0.0,
                    help="noise (sd) added to the odometry's speeds, m/s and rad/s")
    ap.add_argument("--lapse", type=float, default=0.0,
                    help="one lapse of this many sim seconds with no scan matched")
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    logging.basicConfig(level=logging.ERROR)
    print(f"dock bench: {a.hours} h on the charger, gyro bias {a.bias} rad/s at the start, "
          f"forced loss every {a.lose_every or '-'} s, speed noise {a.noise}, "
          f"one lapse of {a.lapse} s")
    for gap in (float(g) for g in a.scan_gap.split(",")):
        r = run(a.hours, gap, a.bias, a.lose_every, a.noise, a.seed, a.lapse)
        print(f"scan gap {gap:4.1f} s: {r['hours']:.2f} h, lost {r['lost']} "
              f"(forced {r['forced']}), episodes {r['episodes']}, without an ending "
              f"event {r['unended']} (open at the end {r['open_at_end']}), "
              f"recovered {r['recovered']}, failed {r['failed']}, longest episode "
              f"{r['longest_s']:.0f} s; "
              f"heading error worst {r['worst_deg']:.1f}° "
              f"(while not lost), at the end {r['final_deg']:.1f}°"
              f"{' LOST' if r['lost_at_end'] else ''}; gyro bias at the end "
              f"{r['gyro_bias_end']:.3f} rad/s; cpu {r['cpu_s']:.1f} s", flush=True)


if __name__ == "__main__":
    main()

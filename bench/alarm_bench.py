"""Alarm rules: chatter suppression and the monitor's cost per telemetry sample.

Prints, for a noisy value hovering at a high limit (400 samples at 10 Hz, uniform
noise of +-0.4 around a limit of 45), how many alarms are raised with no deadband,
with a deadband and with an on-delay; and how many telemetry samples per second the
ISA-18.2 monitor takes with the default rule file (4 channels, rate of rise on gas,
stale data, the robot's flag word).

    .venv/bin/python bench/alarm_bench.py [--samples 20000] [--seed 3]
"""

from __future__ import annotations

import argparse
import os
import random
import time

from app.core.alarms import AlarmMonitor, LimitRule, default_alarm_config


def chatter(seed: int) -> None:
    rnd = random.Random(seed)
    vals = [45.0 + rnd.uniform(-0.4, 0.4) for _ in range(400)]
    for name, rule in (("no deadband", LimitRule("temp_c", high=45.0)),
                       ("deadband 1.0", LimitRule("temp_c", high=45.0, deadband=1.0)),
                       ("on-delay 3 s", LimitRule("temp_c", high=45.0, on_delay_s=3.0))):
        m = AlarmMonitor([rule])
        n = sum(tr.raised for i, v in enumerate(vals) for tr in m.update("temp_c", v, i * 0.1))
        print(f"  {name:>14}: {n:4d} alarms raised over 400 noisy samples at the limit")


def throughput(n: int, seed: int) -> None:
    rnd = random.Random(seed)
    m = AlarmMonitor.from_config(default_alarm_config())
    t0 = time.perf_counter()
    for i in range(n):
        t = 1.7e9 + i * 0.1
        m.update_many({"gas_lel_pct": 5 + rnd.gauss(0, .2), "temp_c": 25.0,
                       "humidity_pct": 50.0, "battery_v": 24.0}, t)
        m.update_flags(0, t)
        if i % 10 == 0:
            m.tick(t)
    dt = time.perf_counter() - t0
    print(f"  monitor: {n} samples (4 channels + flags, default rules, 10 Hz) in {dt:.2f} s"
          f" = {n / dt:,.0f} samples/s, {1e6 * dt / n:.0f} us per sample")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=20000)
    ap.add_argument("--seed", type=int, default=3)
    a = ap.parse_args()
    print(f"alarm bench: load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cpus")
    print("chatter at a limit:")
    chatter(a.seed)
    print("cost:")
    throughput(a.samples, a.seed)


if __name__ == "__main__":
    main()

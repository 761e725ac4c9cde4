"""A canary on one CPU: tells whether that CPU ran this machine's ordinary work.

It pins itself to ``--cpu``, asks for a real-time priority (``SCHED_FIFO``; it then
runs before every ordinary thread of the machine on that CPU) and sleeps ``--period-ms``
at a time, noting every wake-up that came more than ``--gap-ms`` late, as ``due_s late_s``
lines in ``--out`` (when it was due and how late it came, on ``CLOCK_MONOTONIC``,
which every process of the machine shares). A late wake-up of a real-time thread
means the CPU was not running the machine's ordinary threads at all in that time: the hypervisor ran
something else on it (a virtual CPU preempted by the host), or the kernel did
(interrupts, a real-time kernel thread). A desk stall that a canary gap on the
desk's CPU overlaps is therefore not the desk's own doing
(``bench/desk_soak.py --pin 0 --canary``).

    sudo python bench/cpu_canary.py --cpu 0 --out /tmp/canary.tsv   # until killed

Linux only; without the privilege for ``SCHED_FIFO`` it says so and runs at the
highest ordinary priority it may have (a weaker canary: then ordinary threads can
delay it too).
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
import time


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cpu", type=int, required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--period-ms", type=float, default=5.0)
    ap.add_argument("--gap-ms", type=float, default=20.0)
    ap.add_argument("--fifo", type=int, default=50, help="SCHED_FIFO priority")
    args = ap.parse_args(argv)
    if not sys.platform.startswith("linux"):
        print("cpu_canary: Linux only", file=sys.stderr)
        return 2
    os.sched_setaffinity(0, {args.cpu})
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(args.fifo))
        kind = f"SCHED_FIFO {args.fifo}"
    except PermissionError:
        kind = "ordinary priority (no privilege for SCHED_FIFO)"
    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    period, gap = args.period_ms / 1000, args.gap_ms / 1000
    wakes = 0
    with open(args.out, "w", buffering=1) as out:
        out.write(f"# cpu {args.cpu}, {kind}, period {args.period_ms} ms, gaps over "
                  f"{args.gap_ms} ms\n")
        last = time.monotonic()
        while not stop:
            time.sleep(period)
            now = time.monotonic()
            wakes += 1
            if now - last - period > gap:
                out.write(f"{last + period:.6f}\t{now - last - period:.6f}\n")
            last = now
        out.write(f"# end: {wakes} wake-ups\n")
    return 0


def read_gaps(path: str) -> list[tuple[float, float]]:
    """The canary's late wake-ups: (monotonic s it was due, s late) each."""
    gaps = []
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            t, late = line.split("\t")
            gaps.append((float(t), float(late)))
    return gaps


def overlap_s(due_s: float, late_s: float, gaps: list[tuple[float, float]]) -> float:
    """Seconds of the late window ``[due_s, due_s + late_s]`` (a desk beat's) in which
    the canary was late too."""
    end = due_s + late_s
    return sum(max(0.0, min(end, g0 + g) - max(due_s, g0)) for g0, g in gaps
               if g0 < end and g0 + g > due_s)


if __name__ == "__main__":
    sys.exit(main())

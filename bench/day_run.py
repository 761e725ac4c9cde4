"""A patrol day at a high time scale, headless: desk memory, rows stored, nothing lost.

Starts sim_robot at ``--time-scale K`` and the headless desk (``station-patrol --connect
... --headless --patrol``) as a separate process for ``hours * 3600 / K`` wall seconds,
samples the desk's resident memory (RSS) every second, then opens the archive and prints:

- desk RSS at start (first sample after ``--warmup`` s) and at the end, and the growth;
- rows stored per table;
- nothing lost: telemetry messages the desk received (its summary) = rows stored, and,
  when the telemetry carries the robot's counter (``tel_seq``), that the stored counters
  form one unbroken run (count sent while connected = count stored).

The robot sends telemetry at 10 Hz of wall time whatever the time scale, so a "day" at
K = 200 is 432 s of wall time and ~4300 telemetry messages; ``--telemetry-hz`` raises
the robot's telemetry and pose rate (10 x K gives a real day's count of messages).

    .venv/bin/python bench/day_run.py --hours 24 --time-scale 200
    .venv/bin/python bench/day_run.py --hours 1 --time-scale 60      # a short run
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from app.core.records import Archive  # noqa: E402
from app.sim_process import SimRobotProcess  # noqa: E402


def rss_mb(pid: int) -> float | None:
    try:
        text = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return None
    m = re.search(r"VmRSS:\s+(\d+) kB", text)
    return int(m.group(1)) / 1024 if m else None


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--hours", type=float, default=24.0, help="simulated hours")
    ap.add_argument("--time-scale", type=float, default=200.0)
    ap.add_argument("--warmup", type=float, default=15.0,
                    help="wall seconds before the start RSS is taken")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--telemetry-hz", type=float, default=None,
                    help="the robot's telemetry (and pose) rate in wall time (default 10): "
                    "10 x the time scale sends a real day's message count")
    ap.add_argument("--keep", metavar="DIR", help="keep the archive and results here")
    args = ap.parse_args(argv)
    wall_s = args.hours * 3600.0 / args.time_scale
    folder = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="day-run-"))
    folder.mkdir(parents=True, exist_ok=True)
    data, out = folder / "data", folder / "out"
    print(f"day run: {args.hours:g} simulated h at time scale {args.time_scale:g} = "
          f"{wall_s:.0f} s of wall time; load {os.getloadavg()[0]:.2f} "
          f"({os.cpu_count()} CPUs); files in {folder}", flush=True)
    extra = []
    if args.telemetry_hz is not None:
        sim_cfg = folder / "sim.toml"
        sim_cfg.write_text(f"telemetry_hz = {args.telemetry_hz}\npose_hz = {args.telemetry_hz}\n")
        extra = ["--config", str(sim_cfg)]
        print(f"robot telemetry and poses at {args.telemetry_hz:g} Hz of wall time", flush=True)
    sim = SimRobotProcess(seed=args.seed, time_scale=args.time_scale, extra=extra).start()
    env = dict(os.environ, QT_QPA_PLATFORM="offscreen")
    log = open(folder / "desk.log", "w")
    desk = subprocess.Popen(
        [sys.executable, "-m", "app.cli", "--connect", f"{sim.host}:{sim.port}", "--headless",
         "--patrol", "--duration", f"{wall_s:.1f}", "--out", str(out), "--data-dir", str(data),
         "--log-level", "WARNING"], stdout=log, stderr=subprocess.STDOUT,
        stdin=subprocess.DEVNULL, env=env, cwd=ROOT)
    samples: list[tuple[float, float]] = []
    t_start = time.monotonic()
    try:
        while desk.poll() is None:
            r = rss_mb(desk.pid)
            if r is not None:
                samples.append((time.monotonic() - t_start, r))
            time.sleep(1.0)
        desk.wait()
    finally:
        if desk.poll() is None:
            desk.kill()
            desk.wait(10)
        log.close()
        sim_lines = list(sim.output)
        sim.stop()
    elapsed = time.monotonic() - t_start
    if desk.returncode != 0:
        print(f"the desk exited with {desk.returncode}; its log:\n"
              + (folder / "desk.log").read_text()[-3000:])
    after = [r for t, r in samples if t >= args.warmup] or [r for _t, r in samples]
    if after:
        start, end, peak = after[0], after[-1], max(after)
        print(f"desk RSS: start {start:.1f} MB (after {args.warmup:g} s), end {end:.1f} MB, "
              f"peak {peak:.1f} MB; growth {100 * (end - start) / start:+.1f} % "
              f"(goal <= 10 %) over {elapsed:.0f} s, {len(samples)} samples")
        # a steady climb shows in the slope of the second half
        half = [(t, r) for t, r in samples if t >= samples[-1][0] / 2]
        if len(half) > 10:
            k = np.polyfit([t for t, _ in half], [r for _, r in half], 1)[0]
            print(f"  RSS slope over the second half: {k * 3600:+.1f} MB per wall hour")
    summary = json.loads((out / "summary.json").read_text())
    received = summary["counts"].get("telemetry", 0)
    a = Archive(data / "archive.sqlite3")
    try:
        counts = a.counts()
        print("rows stored: " + ", ".join(f"{k} {v}" for k, v in counts.items()))
        print(f"archive file {(data / 'archive.sqlite3').stat().st_size / 1e6:.1f} MB; "
              f"integrity_check: {a.integrity_check()}; writer: {summary.get('archive')}")
        print(f"telemetry: received by the desk {received}, stored {counts['telemetry']} -> "
              f"{'nothing lost' if received == counts['telemetry'] else 'MISMATCH'}")
        if "tel_seq" in a.channels():
            _t, _seq, v = a.telemetry_values(["tel_seq"])
            s = v[:, 0][np.isfinite(v[:, 0])].astype(np.int64)
            if len(s):
                sent = int(s.max() - s.min() + 1)
                gaps = int(np.count_nonzero(np.diff(np.sort(s)) > 1))
                print(f"robot counter (tel_seq): {s.min()}..{s.max()} -> sent while connected "
                      f"{sent}, stored {len(s)}, distinct {len(np.unique(s))}, gaps {gaps} -> "
                      f"{'count sent = count stored' if sent == len(s) else 'LOST ROWS'}")
        else:
            print("robot counter: the telemetry carries no tel_seq field here; "
                  "compare with the robot's own count below")
        stats = [ln for ln in sim_lines if "stats:" in ln]
        if stats:
            m = re.search(r"'telemetry': (\d+)", stats[-1])
            if m:
                print(f"robot's last logged telemetry count (includes messages before the "
                      f"desk connected): {m.group(1)}")
    finally:
        a.close()
    print(f"load at the end {os.getloadavg()[0]:.2f}")
    return 0 if desk.returncode == 0 else 1


if __name__ == "__main__":
    sys.exit(main())

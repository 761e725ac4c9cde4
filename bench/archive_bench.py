"""Archive benchmark: write rate and long-range query time.

1. Write capacity: N telemetry rows (all 16 telemetry channels) added as fast as the
   caller can, timed until they are on disk (rows/s), through the same ``add_telemetry``
   path the desk uses.
2. With the desk live: a headless desk session (the real RobotLink and DeskSession) on a
   real sim_robot at a high time scale, plus a synthetic feed of ``--extra-hz`` telemetry
   rows/s into the same archive. Prints rows written per second by table, the most rows
   pending, and the longest stall of the desk's event loop (the archive must never stall
   it).
3. ``series()`` over 24 h of 10 Hz data (864 000 rows written through the same path into
   a temporary archive): one channel down-sampled to ~2000 points, cold and warm, and
   shorter ranges for comparison. Goal: <= 200 ms.
4. The kill test, repeated: the headless desk SIGKILLed after ~5 s of recording; how far
   before the kill the newest stored row is (goal: < 1 s), and the file's integrity.

    .venv/bin/python bench/archive_bench.py [--hours 24] [--live-seconds 20]
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import threading
import time
from pathlib import Path

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from app.core.records import Archive  # noqa: E402

CHANNELS = ("mcu_time_ms", "gas_lel_pct", "temp_c", "humidity_pct", "obstacle_left_m",
            "obstacle_front_m", "obstacle_right_m", "battery_v", "wheel_left_mps",
            "wheel_right_mps", "yaw_rate_rps", "cmd_linear_mps", "cmd_angular_rps",
            "alarm_flags", "mode", "tel_seq")
T0 = 1_790_000_000.0


def synthetic(n: int, hz: float = 10.0, seed: int = 1):
    rng = np.random.default_rng(seed)
    t = T0 + np.arange(n) / hz
    v = rng.normal(0.0, 1.0, (n, len(CHANNELS))).cumsum(axis=0) * 0.01 + 20.0
    v[:, -1] = np.arange(n)
    return t, v


def feed(archive: Archive, t: np.ndarray, v: np.ndarray) -> None:
    names = CHANNELS
    for i in range(len(t)):
        row = v[i]
        archive.add_telemetry(float(t[i]), dict(zip(names, row.tolist(), strict=True)), seq=i)


def bench_write_capacity(folder: Path, n: int) -> None:
    t, v = synthetic(n)
    a = Archive(folder / "capacity.sqlite3")
    t_start = time.perf_counter()
    feed(a, t, v)
    t_added = time.perf_counter()
    assert a.flush(timeout=600)
    t_done = time.perf_counter()
    st = a.stats()
    a.close()
    print(f"write capacity: {n} telemetry rows x {len(CHANNELS)} channels")
    print(f"  add_telemetry calls: {n / (t_added - t_start):,.0f} rows/s "
          f"({(t_added - t_start) / n * 1e6:.1f} us per call on the caller's thread)")
    print(f"  on disk (incl. roll-ups): {n / (t_done - t_start):,.0f} rows/s sustained; "
          f"written={st['written']} dropped={st['dropped']} failures={st['failures']}")


def bench_live(folder: Path, seconds: float, time_scale: float, extra_hz: float) -> None:
    from PySide6.QtCore import QCoreApplication, QElapsedTimer, QTimer

    from app.comm.link import LinkSettings, RobotLink
    from app.session import DeskSession
    from app.sim_process import SimRobotProcess

    app = QCoreApplication.instance() or QCoreApplication(sys.argv[:1])
    sim = SimRobotProcess(seed=1, time_scale=time_scale).start()
    archive = Archive(folder / "live.sqlite3")
    link = RobotLink(LinkSettings())
    session = DeskSession(link, None, archive=archive)
    stall = {"max_ms": 0.0}
    timer = QElapsedTimer()
    timer.start()

    def tick() -> None:
        gap = timer.restart() - 5
        stall["max_ms"] = max(stall["max_ms"], gap)

    beat = QTimer()
    beat.timeout.connect(tick)
    beat.start(5)
    pending_max = [0]
    stop = threading.Event()

    def extra_feed() -> None:
        """``extra_hz`` synthetic rows/s on a thread of its own (a second robot)."""
        if extra_hz <= 0:
            return
        period = 1.0 / extra_hz
        nxt = time.perf_counter()
        i = 0
        while not stop.is_set():
            now = time.perf_counter()
            k = max(1, int((now - nxt) / period) + 1) if now >= nxt else 0
            for _ in range(k):
                archive.add_telemetry(time.time(), {f"extra_{j}": float(i + j)
                                                    for j in range(16)}, seq=i)
                i += 1
                nxt += period
            time.sleep(0.002)

    def sample() -> None:
        pending_max[0] = max(pending_max[0], archive.stats()["pending"])

    probe = QTimer()
    probe.timeout.connect(sample)
    probe.start(100)
    session.gateway.send_when_connected("start_patrol", {})  # journaled, as the desk does
    link.connect_to(sim.host, sim.port)
    feeder = threading.Thread(target=extra_feed, daemon=True)
    QTimer.singleShot(int(seconds * 1000), app.quit)
    t_start = time.perf_counter()
    feeder.start()
    app.exec()
    stop.set()
    feeder.join()
    elapsed = time.perf_counter() - t_start
    link.shutdown()
    t_close = time.perf_counter()
    session.close()
    close_s = time.perf_counter() - t_close
    sim.stop()
    st = archive.stats()
    total = sum(st["written"].values())
    print(f"with the desk live ({seconds:.0f} s, sim time scale {time_scale:g}, "
          f"synthetic extra feed {extra_hz:g} rows/s):")
    print(f"  rows written: {total} = {total / elapsed:,.0f} rows/s; by table: "
          + ", ".join(f"{k} {v} ({v / elapsed:.1f}/s)" for k, v in sorted(st["written"].items())))
    print(f"  most rows pending at once: {pending_max[0]}; close (final flush) took "
          f"{close_s * 1000:.0f} ms; failures {st['failures']}, dropped {st['dropped']}")
    print(f"  longest event-loop stall: {stall['max_ms']:.0f} ms (5 ms timer)")


def bench_query(folder: Path, hours: float, repeats: int) -> None:
    n = int(hours * 3600 * 10)
    path = folder / "day.sqlite3"
    a = Archive(path, batch_rows=20000)
    t, v = synthetic(n)
    t_start = time.perf_counter()
    chunk = 100_000
    for s in range(0, n, chunk):
        feed(a, t[s:s + chunk], v[s:s + chunk])
        a.flush(timeout=600)
    gen_s = time.perf_counter() - t_start
    a.close()
    size_mb = path.stat().st_size / 1e6
    print(f"query: {hours:g} h of 10 Hz telemetry = {n} rows x {len(CHANNELS)} channels "
          f"written in {gen_s:.1f} s ({n / gen_s:,.0f} rows/s); file {size_mb:.0f} MB")
    b = Archive(path)  # a fresh reader, as the history view would have
    t0, t1 = float(t[0]), float(t[-1])
    for label, lo in ((f"{hours:g} h", t0), ("1 h", t1 - 3600), ("10 min", t1 - 600)):
        times = []
        for r in range(repeats):
            q = time.perf_counter()
            s = b.series("temp_c", lo, t1, max_points=2000)
            times.append((time.perf_counter() - q) * 1000)
            if r == 0:
                cold = times[0]
        i0 = int((lo - t0) * 10)
        exact = (s.vmin.min() == v[i0:, 2].min(), s.vmax.max() == v[i0:, 2].max())
        print(f"  series(temp_c, {label}, max_points=2000): {len(s)} points from {s.source}; "
              f"cold {cold:.1f} ms, warm median {statistics.median(times[1:] or times):.1f} ms; "
              f"min/max kept exactly: {all(exact)}")
    b.close()


def bench_kill(folder: Path, rounds: int, seconds: float) -> None:
    """SIGKILL the headless desk after ``seconds`` of recording, ``rounds`` times: how much
    older than the kill is the newest stored telemetry row, and is the file sound."""
    import csv
    import signal
    import sqlite3
    import subprocess
    from datetime import datetime

    from app.sim_process import SimRobotProcess

    sim = SimRobotProcess(seed=1).start()
    gaps, missing_all = [], []
    try:
        for r in range(rounds):
            data, out = folder / f"kill{r}" / "data", folder / f"kill{r}" / "out"
            desk = subprocess.Popen(
                [sys.executable, "-m", "app.cli", "--connect", f"{sim.host}:{sim.port}",
                 "--headless", "--duration", "600", "--out", str(out), "--data-dir", str(data),
                 "--log-level", "WARNING"], stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL, cwd=ROOT)
            path = data / "archive.sqlite3"
            end = time.monotonic() + 60
            while time.monotonic() < end:
                try:
                    con = sqlite3.connect(f"file:{path}?mode=ro", uri=True)
                    n = con.execute("SELECT count(*) FROM telemetry").fetchone()[0]
                    con.close()
                except sqlite3.Error:
                    n = 0
                if n >= seconds * 10:
                    break
                time.sleep(0.1)
            desk.send_signal(signal.SIGKILL)
            kill_t = time.time()
            desk.wait(10)
            a = Archive(path)
            ok = a.integrity_check()
            gap = kill_t - a.time_range()[1]
            stored = set(a.telemetry_seqs().tolist())
            rows = list(csv.DictReader((out / "telemetry.csv").open()))
            older = [int(x["seq"]) for x in rows
                     if datetime.fromisoformat(x["received_utc"]).timestamp() < kill_t - 1.0]
            missing = sum(1 for q in older if q not in stored)
            a.close()
            gaps.append(gap)
            missing_all.append(missing)
            print(f"  kill {r + 1}: newest stored row {gap * 1000:.0f} ms before the kill; "
                  f"integrity_check {ok}; rows received > 1 s before the kill but missing: "
                  f"{missing} of {len(older)}")
    finally:
        sim.stop()
    print(f"kill test x{rounds}: newest row before the kill: median "
          f"{statistics.median(gaps) * 1000:.0f} ms, worst {max(gaps) * 1000:.0f} ms "
          f"(goal < 1000 ms); missing older rows in all: {sum(missing_all)}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rows", type=int, default=200_000, help="rows for the capacity test")
    ap.add_argument("--hours", type=float, default=24.0, help="hours of 10 Hz data to query")
    ap.add_argument("--live-seconds", type=float, default=20.0)
    ap.add_argument("--time-scale", type=float, default=20.0)
    ap.add_argument("--extra-hz", type=float, default=500.0,
                    help="synthetic telemetry rows/s added during the live test")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--kills", type=int, default=5, help="rounds of the kill test")
    ap.add_argument("--skip", nargs="*", default=[],
                    choices=["capacity", "live", "query", "kill"])
    args = ap.parse_args(argv)
    print(f"load before: {os.getloadavg()[0]:.2f} (1-min average, {os.cpu_count()} CPUs)")
    with tempfile.TemporaryDirectory(prefix="archive-bench-") as d:
        folder = Path(d)
        if "capacity" not in args.skip:
            bench_write_capacity(folder, args.rows)
        if "live" not in args.skip:
            bench_live(folder, args.live_seconds, args.time_scale, args.extra_hz)
        if "query" not in args.skip:
            bench_query(folder, args.hours, args.repeats)
        if "kill" not in args.skip:
            bench_kill(folder, args.kills, 5.0)
    print(f"load after: {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

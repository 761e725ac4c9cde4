"""Desk soak: the operator's window, open offscreen, in real time for hours, on a
simulated robot that runs many times faster (72 robot hours in 2 desk hours at x36).

The desk is built as ``station-patrol --connect`` builds it (window, desk session,
archive, rotating log files) in this process; the robot is a ``sim-robot`` process on
patrol (asked to patrol again whenever its patrol has ended). Measured in the desk
process:

- memory: resident set size (RSS) after the warm-up and at the end, and the growth;
- event-loop stalls: a 20 ms QTimer probe; each tick's lateness beyond its interval is
  a stall; the longest, the 99.9th percentile and the count over 50 ms;
- open file handles and threads at the start (after the warm-up) and at the end;
- the log folder: files, bytes and rollovers, with a small ``--log-max-bytes`` so that
  rotation happens within the run and its bound (``max_bytes * (max_files + 1)``) shows.

It prints a line every ``--every`` seconds and the figures at the end:

    QT_QPA_PLATFORM=offscreen .venv/bin/python bench/desk_soak.py --minutes 120 --time-scale 36
    QT_QPA_PLATFORM=offscreen .venv/bin/python bench/desk_soak.py --minutes 2   # a smoke run
    QT_QPA_PLATFORM=offscreen .venv/bin/python bench/desk_soak.py --minutes 5 --stalls
        # ... and where the GUI thread's stalled time went (bench/stall_profile.py)

Memory, handles and threads are read from /proc (Linux); elsewhere they print as "n/a".
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
import tempfile
import threading
import time
from pathlib import Path

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402


def _status(field: str) -> int | None:
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith(field + ":"):
                return int(line.split()[1])
    except OSError:
        pass
    return None


def rss_mb() -> float | None:
    kb = _status("VmRSS")
    return None if kb is None else kb / 1024


def os_threads() -> int | None:
    return _status("Threads")


def open_handles() -> int | None:
    try:
        return len(os.listdir("/proc/self/fd"))
    except OSError:
        return None


def folder_bytes(folder: Path) -> tuple[int, int]:
    files = [p for p in folder.iterdir() if p.is_file()]
    return len(files), sum(p.stat().st_size for p in files)


class LatencyProbe:
    """A QTimer at ``period_ms``: how late each tick is beyond its period.

    The lateness record is one array allocated (and written, so its pages are resident)
    before the start figures are taken: the probe must not add its own growth to the
    memory figure it helps to measure. Ticks beyond ``capacity`` only update ``max_ms``
    and ``overflow``."""

    def __init__(self, period_ms: int = 20, capacity: int = 1 << 20) -> None:
        from PySide6.QtCore import Qt, QTimer
        self.period_s = period_ms / 1000
        self._late = np.full(int(capacity), 0.0)
        self.n = 0
        self.max_ms = 0.0
        self.overflow = 0
        self.stalls: list[tuple[float, float]] = []  # (monotonic s due, s late) over 50 ms
        self._last = time.perf_counter()
        self.timer = QTimer()
        self.timer.setTimerType(Qt.TimerType.PreciseTimer)
        self.timer.timeout.connect(self._tick)
        self.timer.start(period_ms)

    @property
    def late_ms(self) -> np.ndarray:
        return self._late[:self.n]

    def _tick(self) -> None:
        now = time.perf_counter()
        late = max(0.0, (now - self._last - self.period_s) * 1000)
        if late > 50.0:  # perf_counter is CLOCK_MONOTONIC on Linux: comparable across
            self.stalls.append((time.monotonic() - late / 1000, late / 1000))  # processes
        self._last = now
        self.max_ms = max(self.max_ms, late)
        if self.n < len(self._late):
            self._late[self.n] = late
            self.n += 1
        else:
            self.overflow += 1

    def reset(self) -> None:
        self.n = 0
        self.max_ms = 0.0
        self.overflow = 0
        self.stalls = []
        self._last = time.perf_counter()


def pin_process(cpu: int) -> set[int]:
    """Every thread of this process on ``cpu`` (threads made later inherit it); the
    other CPUs, returned, are for the profiler's sampler and the canary's rivals."""
    for tid in os.listdir("/proc/self/task"):
        os.sched_setaffinity(int(tid), {cpu})
    return set(range(os.cpu_count() or 1)) - {cpu}


def sample(probe, log_dir: Path, handler) -> dict:
    n, size = folder_bytes(log_dir)
    return {"t": time.monotonic(), "rss_mb": rss_mb(), "handles": open_handles(),
            "threads": threading.active_count(), "os_threads": os_threads(),
            "log_files": n, "log_bytes": size, "rollovers": handler.rollovers,
            "ticks": probe.n + probe.overflow, "max_late_ms": probe.max_ms}


def snap_total(snapshot) -> float:
    return sum(s.size for s in snapshot.statistics("filename")) / 1e6


def _load() -> str:
    try:
        return "/".join(f"{v:.1f}" for v in os.getloadavg())
    except (AttributeError, OSError):
        return "n/a"


def _fmt(v, spec: str = "") -> str:
    return "n/a" if v is None else format(v, spec)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--minutes", type=float, default=120.0, help="desk wall minutes")
    ap.add_argument("--time-scale", type=float, default=36.0, help="the robot's speed-up")
    ap.add_argument("--warmup", type=float, default=60.0,
                    help="wall seconds before the start figures are taken")
    ap.add_argument("--every", type=float, default=300.0, help="progress line period (s)")
    ap.add_argument("--log-max-bytes", type=int, default=200_000)
    ap.add_argument("--log-max-files", type=int, default=5)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--keep", metavar="DIR", help="keep archive and logs here")
    ap.add_argument("--start-timeout", type=float, default=600.0,
                    help="seconds the robot may take to start (a first run compiles)")
    ap.add_argument("--probe", action="store_true",
                    help="also count objects (start vs end) and print RSS after malloc_trim")
    ap.add_argument("--no-warm", action="store_true",
                    help="without the meter reader's warm-up at start (to compare)")
    ap.add_argument("--no-trim", action="store_true",
                    help="without the desk's heap trimmer (to compare)")
    ap.add_argument("--trace", action="store_true",
                    help="with --probe: trace Python allocations too (slows the desk)")
    ap.add_argument("--stalls", action="store_true",
                    help="sample the GUI thread's stack while it stalls over 50 ms and "
                         "print where the stalled time went (bench/stall_profile.py)")
    ap.add_argument("--trace-frames", type=int, default=1,
                    help="with --trace: frames kept per allocation (>1 prints tracebacks)")
    ap.add_argument("--record", metavar="FILE",
                    help="keep what the link reported after the warm-up as a tape "
                         "(bench/link_tape.py) for bench/desk_replay_ab.py")
    ap.add_argument("--probe-at", default="",
                    help="with --probe: also probe at these minutes after the start, "
                         "e.g. 3,6,11; each probe is compared with the one before")
    ap.add_argument("--pin", type=int, metavar="CPU",
                    help="run the desk's threads on this CPU only (Linux); the robot "
                         "process and --stalls' sampler run on the others")
    ap.add_argument("--canary", action="store_true",
                    help="with --pin: a real-time canary on the desk's CPU "
                         "(bench/cpu_canary.py); stalls it also saw are printed apart")
    args = ap.parse_args(argv)
    from app.allocator import settle_allocator, start_heap_trimmer

    settle_allocator()  # as station-patrol does (app/cli.py)
    trimmer = None if args.no_trim else start_heap_trimmer()

    folder = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="desk-soak-"))
    folder.mkdir(parents=True, exist_ok=True)
    os.environ["STATION_PATROL_DATA_DIR"] = str(folder / "data")
    os.environ["STATION_PATROL_KEY_FILE"] = str(folder / "station.key")
    os.environ["XDG_CONFIG_HOME"] = str(folder / "config")  # QSettings, not the user's

    from PySide6.QtCore import QTimer, qInstallMessageHandler
    from PySide6.QtWidgets import QApplication

    def qt_message(_mode, _ctx, text: str) -> None:  # the offscreen plugin's size-hint note
        if "propagateSizeHints" not in text:
            print(f"Qt: {text}", file=sys.stderr)

    qInstallMessageHandler(qt_message)

    from app.comm.link import RobotLink
    from app.config import DeskConfig
    from app.core.recorder import SessionRecorder  # noqa: F401 - as run_window imports it
    from app.logs import LogSettings, RotatingLogHandler, setup_logging
    from app.session import open_desk_archive
    from app.sim_process import SimRobotProcess
    from app.ui.app import build_window
    from app.ui.theme import apply_theme

    log_dir = folder / "log"
    setup_logging("INFO", LogSettings(dir=str(log_dir), max_bytes=args.log_max_bytes,
                                      max_files=args.log_max_files), console=False)
    handler = next(h for h in logging.getLogger().handlers
                   if isinstance(h, RotatingLogHandler))
    wall_s = args.minutes * 60.0
    print(f"desk soak: {args.minutes:g} min of desk time, robot at x{args.time_scale:g} "
          f"({wall_s * args.time_scale / 3600:.1f} robot hours); files in {folder}; "
          f"load {_load()} on {os.cpu_count()} CPUs", flush=True)

    sim = SimRobotProcess(seed=args.seed, time_scale=args.time_scale,
                          key_file=str(folder / "station.key"),
                          start_timeout_s=args.start_timeout).start()
    others: set[int] = set()
    canary = canary_file = None
    if args.pin is not None:
        others = pin_process(args.pin)
        if others:
            os.sched_setaffinity(sim.proc.pid, others)  # its main thread; most of its work
        if args.canary:
            import subprocess

            canary_file = folder / "canary.tsv"
            canary = subprocess.Popen([sys.executable, str(ROOT / "bench" / "cpu_canary.py"),
                                       "--cpu", str(args.pin), "--out", str(canary_file)])
        print(f"desk pinned to CPU {args.pin}; robot on {sorted(others)}; canary "
              f"{'pid ' + str(canary.pid) if canary else 'none'}", flush=True)
    app = QApplication.instance() or QApplication(sys.argv[:1])
    apply_theme(app)
    cfg = DeskConfig()
    link = RobotLink(cfg.link)
    archive, archive_error = open_desk_archive(cfg)
    win = build_window(link, None, archive, archive_error)
    win.resize(1440, 900)
    win.show()
    desk = win.desk
    if not args.no_warm:
        desk.pipeline.meters.warm_up()  # as run_window does
    desk.gateway.send_when_connected("start_patrol", {})
    link.connect_to(sim.host, sim.port)
    from app.ui.app import freeze_startup_heap

    freeze_startup_heap()  # as run_window does

    # the robot patrols again whenever its patrol has ended (a day of rounds)
    from app.ui.map_model import PATROL_ACTIVE

    seen = {"telemetry": 0, "patrols": 0, "state": ""}
    desk.pipeline.listen("values", lambda *_: seen.__setitem__("telemetry",
                                                                  seen["telemetry"] + 1))
    desk.pipeline.listen("patrol_status", lambda m, *_: seen.__setitem__(
        "state", str((m or {}).get("state", "")) if isinstance(m, dict) else
        str(getattr(m, "state", ""))))

    paused_checks = {"n": 0, "resumes": 0}
    # the robot's own account: patrols done, localisation lost and found again
    # by itself (an operator's set_pose needs someone who sees where the robot
    # is; the soak has no such operator, so a robot that cannot find itself
    # stands for the rest of the run, and the figures say so)
    from collections import Counter

    robot_events: Counter[str] = Counter()
    counted = ("patrol_done", "patrol_failed", "localisation_lost", "localisation_recovered",
               "relocalisation_failed", "recovering", "collision")

    def on_robot_event(ev, *_):
        code = str(getattr(ev, "code", ""))
        if code in counted:
            robot_events[code] += 1
            if code in ("localisation_lost", "localisation_recovered",
                        "relocalisation_failed", "collision"):
                print(f"  robot event at {(time.monotonic() - t0) / 60:.1f} min: {code}: "
                      f"{getattr(ev, 'text', '')}", flush=True)

    desk.pipeline.listen("event", on_robot_event)

    def repatrol() -> None:
        """Once a minute, act as the operator of a day of rounds: start a new patrol
        when the last one ended, and resume one that has stood paused (a gas alarm,
        a lost lease) for two checks running, through the window's own F7 path.
        A patrol paused for lost localisation is the robot's to resume once it
        has found itself; the soak leaves it alone."""
        if not desk.gateway.link_up:
            return
        if seen["state"] == "paused" and robot_events["localisation_lost"] > \
                robot_events["localisation_recovered"]:
            return
        if seen["state"] == "paused":
            paused_checks["n"] += 1
            if paused_checks["n"] >= 2:
                paused_checks["n"] = 0
                paused_checks["resumes"] += 1
                win.resume_patrol()
            return
        paused_checks["n"] = 0
        if seen["state"] not in PATROL_ACTIVE:
            seen["patrols"] += 1
            desk.gateway.send("start_patrol", {})

    again = QTimer()
    again.timeout.connect(repatrol)
    again.start(60_000)

    if args.probe:
        import tracemalloc

        from bench import soak_probe

        if args.trace:
            tracemalloc.start(max(1, args.trace_frames))
        found: dict = {}
        stages = sorted(float(m) for m in args.probe_at.split(",") if m.strip())

        def take() -> dict:
            return {"counts": soak_probe.count_objects(win), "types": soak_probe.type_counts(),
                    "snap": tracemalloc.take_snapshot() if args.trace else None}

        def report(a: dict, b: dict, top: int = 15) -> None:
            """What grew from probe ``a`` to probe ``b`` (printed as it is found)."""
            print("  object counts:", *[line for line in soak_probe.diff_counts(
                a["counts"], b["counts"]) if not line.endswith("(+0)")], sep="\n")
            print("  Python objects by type, most grown:",
                  *soak_probe.diff_types(a["types"], b["types"], top), sep="\n")
            if b["snap"] is not None:
                key = "traceback" if args.trace_frames > 1 else "lineno"
                print(f"  Python traced {snap_total(b['snap']):.1f} MB (was "
                      f"{snap_total(a['snap']):.1f} MB); allocations grown:",
                      *soak_probe.diff_tracemalloc(a["snap"], b["snap"], top, key), sep="\n")
            sys.stdout.flush()
    # room for every tick of the run, with a quarter to spare
    probe = LatencyProbe(20, capacity=int((args.minutes * 60 + args.warmup) * 50 * 1.25) + 1000)
    stalls = None
    if args.stalls:
        from bench.stall_profile import StallSampler

        stalls = StallSampler(sampler_cpus=others or None).start()
    samples: list[dict] = []
    t0 = time.monotonic()
    start: dict | None = None
    tape = None

    def tick() -> None:
        nonlocal start
        nonlocal tape
        elapsed = time.monotonic() - t0
        if start is None and elapsed >= args.warmup:
            if args.record:
                from bench.link_tape import TapeRecorder

                tape = TapeRecorder(link)
            probe.reset()  # stalls count from here (start-up compiles and loads)
            if stalls is not None:
                stalls.reset()
            if args.probe:
                soak_probe.trim_rss()
                found.update(take())
                found["last"] = dict(found)
            start = sample(probe, log_dir, handler)
            print(f"start ({elapsed:.0f} s): RSS {_fmt(start['rss_mb'], '.1f')} MB, "
                  f"handles {_fmt(start['handles'])}, threads {start['threads']} "
                  f"(OS {_fmt(start['os_threads'])})", flush=True)
            return
        if start is None:
            return
        if args.probe and stages and elapsed - start["t"] + t0 >= stages[0] * 60:
            minute = stages.pop(0)
            rss_before = rss_mb()
            now = take()
            print(f"== probe at {minute:g} min after the start: RSS {_fmt(rss_before, '.1f')} "
                  f"MB (no trim); compared with the probe before ==", flush=True)
            report(found["last"], now)
            found["last"] = now
        s = sample(probe, log_dir, handler)
        samples.append(s)
        if len(samples) % max(1, int(args.every / 10)) == 0:
            print(f"{elapsed / 60:6.1f} min: RSS {_fmt(s['rss_mb'], '.1f')} MB, handles "
                  f"{_fmt(s['handles'])}, threads {s['threads']}, longest stall "
                  f"{s['max_late_ms']:.0f} ms, log {s['log_files']} files "
                  f"{s['log_bytes'] / 1e6:.2f} MB ({s['rollovers']} rollovers), "
                  f"telemetry {seen['telemetry']}, patrol {seen['state'] or '-'}", flush=True)

    every = QTimer()
    every.timeout.connect(tick)
    every.start(10_000)
    QTimer.singleShot(int((wall_s + args.warmup) * 1000), win.close)
    cpu0 = time.process_time()
    app.exec()
    cpu = time.process_time() - cpu0
    if args.probe and start is not None:
        counts, types = soak_probe.count_objects(win), soak_probe.type_counts()
        snap = tracemalloc.take_snapshot() if args.trace else None
        rss_before_trim = rss_mb()
        soak_probe.trim_rss()
        print(f"\n== probe: RSS {_fmt(rss_before_trim, '.1f')} MB, after malloc_trim "
              f"{_fmt(rss_mb(), '.1f')} MB ==")
        print("object counts (start -> end):", *soak_probe.diff_counts(found["counts"], counts),
              sep="\n")
        print("Python objects by type, most grown:",
              *soak_probe.diff_types(found["types"], types), sep="\n")
        if snap is not None:
            print(f"Python traced {snap_total(snap):.1f} MB (start "
                  f"{snap_total(found['snap']):.1f} MB); allocations grown, by line:",
                  *soak_probe.diff_tracemalloc(found["snap"], snap), sep="\n")
    end = sample(probe, log_dir, handler)
    if args.probe and start is not None:  # after the end figures: it allocates as it looks
        print("what holds the most grown:", *soak_probe.holders(
            soak_probe.grown_types(found["types"], types)), sep="\n")
    late = probe.late_ms.copy()
    if tape is not None:
        tape.save(args.record)
        print(f"tape: {len(tape.events)} messages, {tape.frames} frames, in {args.record}")
    if stalls is not None:
        stalls.stop()
    link.shutdown()
    desk.close()
    sim.stop()
    if canary is not None:
        canary.terminate()
        canary.wait(10)

    if start is None:
        print("the run ended before the warm-up; no figures")
        return 1
    mins = (end["t"] - start["t"]) / 60
    print(f"\n== desk soak: {mins:.1f} min measured (after {args.warmup:g} s warm-up), "
          f"robot x{args.time_scale:g} = {mins * args.time_scale / 60:.1f} robot hours; "
          f"desk CPU {cpu:.0f} s; load {_load()} (1/5/15 min) on {os.cpu_count()} CPUs ==")
    if start["rss_mb"] is not None and end["rss_mb"] is not None:
        peak = max([start["rss_mb"]] + [s["rss_mb"] for s in samples if s["rss_mb"]])
        print(f"memory (RSS): start {start['rss_mb']:.1f} MB, end {end['rss_mb']:.1f} MB, "
              f"peak {peak:.1f} MB; growth "
              f"{100 * (end['rss_mb'] - start['rss_mb']) / start['rss_mb']:+.2f} %")
    else:
        print("memory (RSS): n/a on this platform")
    print(f"event loop: {late.size} probe ticks (20 ms); lateness max {late.max():.1f} ms, "
          f"p99.9 {np.percentile(late, 99.9):.1f} ms, p99 {np.percentile(late, 99):.1f} ms; "
          f"stalls over 50 ms: {int((late > 50).sum())} ({(late > 50).sum() / mins:.1f} per "
          f"minute)" if late.size else
          "event loop: no probe ticks")
    if canary_file is not None:
        from bench.cpu_canary import overlap_s, read_gaps

        gaps = read_gaps(str(canary_file))
        seen_too = [(due, lt, overlap_s(due, lt, gaps)) for due, lt in probe.stalls]
        host = [x for x in seen_too if x[1] - x[2] <= 0.05]  # under 50 ms without it
        t_gap = [g for g in gaps if start["t"] <= g[0] <= end["t"]]
        print(f"canary on CPU {args.pin}: {len(t_gap)} late wake-ups over 20 ms in the "
              f"measured time, longest {1000 * max((g[1] for g in t_gap), default=0):.0f} ms; "
              f"stalls over 50 ms it also saw (the CPU ran no ordinary thread for all but "
              f"50 ms of the stall): {len(host)} of {len(probe.stalls)}")
        for due, lt, ov in seen_too:
            print(f"  stall at {(due - start['t']) / 60:6.1f} min: {1000 * lt:.0f} ms late; "
                  f"canary late {1000 * ov:.0f} ms of it")
    print(f"file handles: start {_fmt(start['handles'])}, end {_fmt(end['handles'])}; "
          f"threads: start {start['threads']} (OS {_fmt(start['os_threads'])}), "
          f"end {end['threads']} (OS {_fmt(end['os_threads'])})")
    bound = args.log_max_bytes * (args.log_max_files + 1)
    if trimmer is not None:
        print(f"heap trimmer: {trimmer.trims} trims, longest {1000 * trimmer.longest_s:.1f} ms "
              f"(its own thread)")
    print(f"log folder: {end['log_files']} files, {end['log_bytes'] / 1e6:.2f} MB "
          f"(bound {bound / 1e6:.2f} MB), {end['rollovers']} rollovers")
    print(f"patrol: {seen['patrols']} new patrols started, {paused_checks['resumes']} paused "
          f"patrols resumed (F7), last state {seen['state'] or '-'}")
    print("robot: " + ", ".join(f"{k} {robot_events[k]}" for k in counted))
    run_s = max(time.monotonic() - t0, 1e-9)
    print("desk messages per second (whole run): " + ", ".join(
        f"{k} {v / run_s:.1f}" for k, v in sorted(desk.pipeline.counts.items())))
    if stalls is not None:
        print(stalls.report())
    if archive is not None:
        print(f"archive: {archive.path} ({Path(archive.path).stat().st_size / 1e6:.1f} MB)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

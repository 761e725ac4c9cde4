"""Soak run: the robot and the desk's link at a high time scale, with injected
link drops and robot restarts.

A TCP proxy in this script sits between the desk (RobotLink, no window) and
sim_robot; at random times it cuts every connection through it (a link drop),
and now and then the robot process is stopped — SIGKILL or SIGTERM, in turn —
and started again on the same port (a robot restart). The desk stores every
telemetry sample it receives in an archive (app.core.records.Archive).

Prints: simulated and wall length, link drops and restarts injected and
recovered (telemetry flowing again) with recovery times, frames received by
type, frames the robot produced by type (from the stop report of the robots
stopped with SIGTERM), rejected frames by reason on both sides, desk and
robot memory (RSS) at start and end, and telemetry lost while the link was
up: per connection, the robot's telemetry counter range against the samples
the desk received, and the archive's row count against the samples received.

    .venv/bin/python bench/soak.py --quick            # 1 simulated hour, 5 drops, 1 restart
    .venv/bin/python bench/soak.py                    # 24 simulated hours, 50 drops
    .venv/bin/python bench/soak.py --sim-hours 24 --time-scale 200 --drops 50 --restarts 4
"""

from __future__ import annotations

import argparse
import ast
import os
import random
import signal
import socket
import sys
import tempfile
import threading
import time
from collections import Counter
from pathlib import Path

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from PySide6.QtCore import QCoreApplication, QEventLoop, QTimer  # noqa: E402

from app.comm.link import LinkSettings, RobotLink  # noqa: E402
from app.core.records import Archive  # noqa: E402
from app.sim_process import SimRobotProcess  # noqa: E402


def rss_mib(pid: int | str = "self") -> float | None:
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    except OSError:
        return None
    return None


class Proxy:
    """A TCP relay on loopback; ``cut()`` closes every connection through it."""

    def __init__(self, upstream: tuple[str, int]) -> None:
        self.upstream = upstream
        self.srv = socket.create_server(("127.0.0.1", 0))
        self.srv.settimeout(0.2)
        self.port = self.srv.getsockname()[1]
        self._pairs: list[tuple[socket.socket, socket.socket]] = []
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self.accepted = 0
        self.upstream_refused = 0
        threading.Thread(target=self._accept, daemon=True, name="proxy").start()

    def _accept(self) -> None:
        while not self._stop.is_set():
            try:
                a, _ = self.srv.accept()
            except TimeoutError:
                continue
            except OSError:
                return
            try:
                b = socket.create_connection(self.upstream, timeout=2)
            except OSError:
                self.upstream_refused += 1
                a.close()
                continue
            self.accepted += 1
            with self._lock:
                self._pairs.append((a, b))
            for src, dst in ((a, b), (b, a)):
                threading.Thread(target=self._pump, args=(src, dst), daemon=True).start()

    @staticmethod
    def _pump(src: socket.socket, dst: socket.socket) -> None:
        try:
            while True:
                data = src.recv(65536)
                if not data:
                    break
                dst.sendall(data)
        except OSError:
            pass
        for s in (src, dst):
            try:
                s.shutdown(socket.SHUT_RDWR)
            except OSError:
                pass

    def cut(self) -> int:
        with self._lock:
            pairs, self._pairs = self._pairs, []
        for a, b in pairs:
            for s in (a, b):
                try:
                    s.shutdown(socket.SHUT_RDWR)
                except OSError:
                    pass
                s.close()
        return len(pairs)

    def close(self) -> None:
        self._stop.set()
        self.cut()
        self.srv.close()


class Desk:
    """RobotLink plus an archive; counts what arrives and checks telemetry numbering."""

    def __init__(self, archive: Archive) -> None:
        self.link = RobotLink(LinkSettings(reconnect_every_s=0.5))
        self.archive = archive
        self.rx = Counter()
        self.sessions: list[list[int]] = []  # per connection: [first seq, last seq, count]
        self.last_tel_mono = 0.0
        self.rejections: dict[str, int] = {}
        self.states = Counter()
        lk = self.link
        lk.telemetry_received.connect(self._on_tel)
        lk.state_changed.connect(self._on_state)
        for sig, name in ((lk.pose_received, "pose"), (lk.scan_received, "lidar_scan"),
                          (lk.event_received, "event"), (lk.ack_received, "command_ack"),
                          (lk.frame_decoded, "video_frame"), (lk.map_received, "map"),
                          (lk.path_received, "path"),
                          (lk.patrol_status_received, "patrol_status"),
                          (lk.obstacles_received, "obstacles")):
            sig.connect(lambda _m, name=name: self.rx.update([name]))
        self.stats = None
        lk.stats_changed.connect(self._on_stats)

    def _on_state(self, s: str) -> None:
        self.states[s] += 1
        if s == "connected":
            self.sessions.append([0, 0, 0])

    def _on_stats(self, s) -> None:
        self.stats = s

    def _on_tel(self, m) -> None:
        self.rx["telemetry"] += 1
        self.last_tel_mono = time.monotonic()
        if self.sessions:
            ses = self.sessions[-1]
            if not ses[2]:
                ses[0] = m.tel_seq
            ses[1] = m.tel_seq
            ses[2] += 1
        self.archive.add_telemetry(m.received_s, {"gas_lel_pct": m.gas_lel_pct,
                                                  "battery_v": m.battery_v}, seq=m.tel_seq)


def spin(app, seconds: float) -> None:
    loop = QEventLoop()
    QTimer.singleShot(max(1, int(seconds * 1000)), loop.quit)
    loop.exec()


def parse_stop_report(lines) -> dict | None:
    for line in reversed(list(lines)):
        if "stopped: {" in line:
            try:
                return ast.literal_eval(line.split("stopped: ", 1)[1])
            except (ValueError, SyntaxError):
                return None
    return None


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sim-hours", type=float, default=24.0, help="simulated length")
    ap.add_argument("--time-scale", type=float, default=100.0,
                    help="sim time runs this many times faster than wall time")
    ap.add_argument("--drops", type=int, default=50, help="link drops to inject")
    ap.add_argument("--restarts", type=int, default=4, help="robot restarts to inject")
    ap.add_argument("--fps", type=float, default=2.0, help="camera frames per second")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--quick", action="store_true",
                    help="1 simulated hour, 5 drops, 1 restart")
    a = ap.parse_args()
    if a.quick:
        a.sim_hours, a.drops, a.restarts = 1.0, 5, 1
    wall_s = a.sim_hours * 3600 / a.time_scale
    rng = random.Random(a.seed)
    warm_s = min(10.0, 0.1 * wall_s)
    # injected faults: (wall time from start, kind), never two within 4 s
    times: list[float] = []
    while len(times) < a.drops + a.restarts:
        t = rng.uniform(warm_s, wall_s - 5.0)
        if all(abs(t - u) > 4.0 for u in times):
            times.append(t)
    kinds = ["drop"] * a.drops + ["restart"] * a.restarts
    rng.shuffle(kinds)
    plan = sorted(zip(times, kinds, strict=True))

    app = QCoreApplication.instance() or QCoreApplication([])
    extra = ["--fps", str(a.fps)]
    sim = SimRobotProcess(seed=a.seed, time_scale=a.time_scale, extra=extra).start()
    port = sim.port
    robot_rss_start = None
    proxy = Proxy((sim.host, port))
    tmp = tempfile.TemporaryDirectory(prefix="soak-")
    archive = Archive(Path(tmp.name) / "soak.sqlite")
    desk = Desk(archive)
    desk.link.connect_to("127.0.0.1", proxy.port)
    t0 = time.monotonic()
    produced = Counter()
    robots_killed = 0
    results: list[tuple[str, float | None]] = []
    desk_rss_start = None
    pending: tuple[str, float] | None = None  # fault waiting for recovery
    restart_kill = True
    i = 0
    print(f"soak: {a.sim_hours:g} simulated h at {a.time_scale:g}x = {wall_s:.0f} s wall, "
          f"{a.drops} drops, {a.restarts} restarts", flush=True)
    while True:
        spin(app, 0.05)
        now = time.monotonic() - t0
        if desk_rss_start is None and now >= warm_s:
            desk_rss_start = rss_mib()
            robot_rss_start = rss_mib(sim.proc.pid)
        if pending is not None and desk.last_tel_mono > pending[1]:
            results.append((pending[0], desk.last_tel_mono - pending[1]))
            pending = None
        if now >= wall_s:
            break
        if i < len(plan) and now >= plan[i][0] and pending is None:
            kind = plan[i][1]
            i += 1
            t_fault = time.monotonic()
            if kind == "drop":
                proxy.cut()
            else:
                if restart_kill:
                    sim.kill()
                    robots_killed += 1
                else:
                    sim.stop()
                    rep = parse_stop_report(sim.output)
                    if rep:
                        produced.update(rep.get("counters", {}))
                restart_kill = not restart_kill
                proxy.cut()
                sim = SimRobotProcess(seed=a.seed, time_scale=a.time_scale, port=port,
                                      extra=extra).start()
            pending = (kind, t_fault)
        elif pending is not None and time.monotonic() - pending[1] > 60:
            results.append((pending[0], None))
            pending = None
    if pending is not None:
        results.append((pending[0], None))
    spin(app, 1.2)  # a last stats report
    desk_rss_end = rss_mib()
    robot_rss_end = rss_mib(sim.proc.pid)
    stats = desk.stats
    desk.link.shutdown()
    sim.stop()
    rep = parse_stop_report(sim.output)
    if rep:
        produced.update(rep.get("counters", {}))
        robot_rej = rep.get("rejections", {})
    else:
        robot_rej = {}
    proxy.close()
    archive.flush(10)
    stored = archive.counts().get("telemetry", 0)
    archive.close()
    tmp.cleanup()

    rec = {k: [r for r in results if r[0] == k] for k in ("drop", "restart")}
    ran = time.monotonic() - t0
    print(f"run: {ran:.0f} s wall = {ran * a.time_scale / 3600:.1f} simulated h; "
          f"load average {os.getloadavg()[0]:.1f}")
    for k, rs in rec.items():
        ok = [t for _, t in rs if t is not None]
        print(f"  {k}s injected {len(rs):3d}, recovered {len(ok):3d}"
              + (f"; telemetry again after median {sorted(ok)[len(ok) // 2]:.2f} s, "
                 f"max {max(ok):.2f} s" if ok else ""))
    print(f"  desk connections {desk.states['connected']}, proxy connections "
          f"{proxy.accepted}, refused while the robot was down {proxy.upstream_refused}")
    print("frames received by the desk, by type: "
          + ", ".join(f"{k} {v}" for k, v in sorted(desk.rx.items())))
    if stats is not None:
        print(f"frames received {stats.rx_frames} in all, sent by the desk "
              f"{stats.tx_frames}")
    print("frames the robot produced, by type (robots stopped with SIGTERM; "
          f"{robots_killed} killed without a report): "
          + ", ".join(f"{k} {v}" for k, v in sorted(produced.items())))
    own = {k: v for k, v in (stats.by_reason if stats else {}).items() if v}
    print(f"rejected by the desk's decoder (current connection), by reason: {own or 'none'}")
    robot_rej = {k: v for k, v in robot_rej.items() if v}
    print(f"rejected by the robot (last robot), by reason: {robot_rej or 'none'}")
    lost_gaps = sum(max(0, (s[1] - s[0] + 1) - s[2]) for s in desk.sessions if s[2])
    received = desk.rx["telemetry"]
    print(f"telemetry: received {received}, archive rows {stored}; lost while the link "
          f"was up (counter gaps within a connection) {lost_gaps}"
          + (f", link's own count {stats.telemetry_lost}, late {stats.telemetry_reordered}"
             if stats else "") + "   (goal 0)")
    print(f"telemetry received but not in the archive: {received - stored}   (goal 0)")

    def growth(s, e):
        return f"{(e - s) / s * 100:+.1f} %" if s and e else "n/a"

    print(f"memory: desk RSS {desk_rss_start:.1f} -> {desk_rss_end:.1f} MiB "
          f"({growth(desk_rss_start, desk_rss_end)}, goal <= +10 %); first robot "
          f"{robot_rss_start or 0:.1f} MiB at start, last robot {robot_rss_end or 0:.1f} MiB "
          f"at end")
    failed = sum(1 for r in results if r[1] is None) + lost_gaps + (received - stored)
    return 1 if failed else 0


if __name__ == "__main__":
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    sys.exit(main())

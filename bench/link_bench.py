"""Robot link benchmark: sim_robot + the desk (offscreen window) on loopback.

Prints telemetry messages per second, video frames per second, frame latency
(robot capture -> decoded on the desk; median, p95), the longest stall of the
desk's event loop, and the link-health figures: after the driving desk
vanishes (SIGKILL) or freezes (SIGSTOP), the time until the robot commands its
motors to stop (the deadman, goal <= 0.5 s) and until its wheels stand still
(plus braking); link loss shown; reconnect after the robot returns.

    .venv/bin/python bench/link_bench.py --seconds 20
"""

from __future__ import annotations

import argparse
import os
import signal
import socket
import subprocess
import sys
import textwrap
import time
from pathlib import Path

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402
from PySide6.QtCore import QElapsedTimer, QEventLoop, QTimer  # noqa: E402
from PySide6.QtWidgets import QApplication  # noqa: E402

from app.comm import protocol as P  # noqa: E402
from app.comm.link import RobotLink  # noqa: E402
from app.sim_process import SimRobotProcess  # noqa: E402


class StallMeter:
    """A 5 ms timer on the GUI thread; the longest gap beyond its period is the
    longest stall of the event loop."""

    def __init__(self, period_ms: int = 5) -> None:
        self.period_ms = period_ms
        self.clock = QElapsedTimer()
        self.clock.start()
        self.last = self.clock.nsecsElapsed()
        self.gaps: list[float] = []
        self.timer = QTimer()
        self.timer.setInterval(period_ms)
        self.timer.timeout.connect(self._tick)
        self.timer.start()

    def _tick(self) -> None:
        now = self.clock.nsecsElapsed()
        self.gaps.append((now - self.last) / 1e6 - self.period_ms)
        self.last = now

    def reset(self) -> None:
        self.gaps.clear()
        self.last = self.clock.nsecsElapsed()


def spin(app: QApplication, seconds: float, until=None) -> bool:
    """Run the Qt event loop for ``seconds`` or until ``until()`` holds."""
    loop = QEventLoop()
    check = QTimer()
    check.timeout.connect(lambda: loop.quit() if until is not None and until() else None)
    check.start(10)
    QTimer.singleShot(int(seconds * 1000), loop.quit)
    loop.exec()
    check.stop()
    return until() if until is not None else True


def streaming(app, seconds: float, with_window: bool, patrol: bool = False) -> dict:
    with SimRobotProcess(seed=3) as sim:
        link = RobotLink()
        tel, lat = [], []
        link.telemetry_received.connect(lambda m: tel.append(time.monotonic()))
        link.frame_decoded.connect(lambda f: lat.append((time.monotonic(), f.latency_ms)))
        win = None
        if with_window:
            from app.ui.main_window import MainWindow

            win = MainWindow(link)
            win.resize(1400, 900)
            win.show()
        link.connect_to(sim.host, sim.port)
        if not spin(app, 15, lambda: link.state == "connected" and lat):
            raise SystemExit("benchmark: the desk did not connect to the robot")
        if patrol:  # the robot drives its default route: map, paths, obstacles stream too
            link.send_command("start_patrol", {})
        spin(app, 1.0)  # settle: the first frames include start-up
        stall = StallMeter()
        t0 = time.monotonic()
        tel.clear()
        lat.clear()
        spin(app, seconds)
        dt = time.monotonic() - t0
        gaps = np.array(stall.gaps)
        lats = np.array([x for _, x in lat])
        link.shutdown()
        if win is not None:
            win.close()
    return {
        "telemetry_per_s": len(tel) / dt,
        "video_fps": len(lat) / dt,
        "latency_median_ms": float(np.median(lats)) if lats.size else float("nan"),
        "latency_p95_ms": float(np.percentile(lats, 95)) if lats.size else float("nan"),
        "stall_max_ms": float(gaps.max()) if gaps.size else float("nan"),
        "stall_p99_ms": float(np.percentile(gaps, 99)) if gaps.size else float("nan"),
        "stalls_over_50ms": int((gaps > 50).sum()),
        "seconds": dt,
    }


DRIVER = textwrap.dedent("""
    import socket, sys, time
    from app.comm import auth, protocol as P
    s = socket.create_connection((sys.argv[1], int(sys.argv[2])))
    enc = P.FrameEncoder(signer=auth.CommandSigner(auth.load_or_create_key()[0], "bench"))
    while True:  # a desk holding the forward key: renew the drive command at 5 Hz
        s.sendall(enc.encode(P.Heartbeat()) + enc.encode(P.Command("drive",
                  {"linear_mps": 0.4, "angular_rps": 0.0})))
        time.sleep(0.2)
""")


class Watcher:
    """A plain-socket observer desk: decodes telemetry, answers heartbeats."""

    def __init__(self, host: str, port: int) -> None:
        self.sock = socket.create_connection((host, port))
        self.sock.settimeout(0.05)
        self.dec = P.FrameDecoder()
        self.enc = P.FrameEncoder()
        self.last_tel: P.Telemetry | None = None
        self.stop_events: list[tuple[str, float]] = []  # (code, robot's UTC time s)
        self._hb = 0.0

    def poll(self) -> None:
        if time.monotonic() - self._hb > 0.5:
            self._hb = time.monotonic()
            self.sock.sendall(self.enc.encode(P.Heartbeat()))
        try:
            data = self.sock.recv(1 << 16)
        except TimeoutError:
            return
        for f in self.dec.feed(data):
            if f.msg_type == P.MsgType.TELEMETRY:
                self.last_tel = f.message
            elif f.msg_type == P.MsgType.EVENT and f.message.code in ("deadman_stop",
                                                                        "failsafe_stop"):
                self.stop_events.append((f.message.code, f.timestamp_us / 1e6))

    def moving(self) -> bool:
        t = self.last_tel
        return t is not None and (abs(t.wheel_left_mps) + abs(t.wheel_right_mps)) > 0.02

    def stopped(self) -> bool:
        return not self.moving()

    def stop_commanded(self) -> bool:
        t = self.last_tel
        return t is not None and t.cmd_linear_mps == 0.0 and t.cmd_angular_rps == 0.0

    def wait(self, cond, timeout: float) -> float | None:
        t0 = time.monotonic()
        while time.monotonic() - t0 < timeout:
            self.poll()
            if cond():
                return time.monotonic() - t0
        return None


def failsafe(trials: int, how: signal.Signals) -> list[tuple]:
    """Desk drives, then vanishes (SIGKILL: its socket closes) or freezes (SIGSTOP:
    its socket stays open, it falls silent): the time until the robot orders its
    motors to stop (its deadman_stop / failsafe_stop event's own timestamp, one
    host, one clock), until its telemetry shows the MCU executing zero, and until
    the wheels stand still. Telemetry comes at 10 Hz, so the last two may read up
    to 0.1 s late."""
    out = []
    with SimRobotProcess(seed=4) as sim:
        for _ in range(trials):
            w = Watcher(sim.host, sim.port)
            drv = subprocess.Popen([sys.executable, "-c", DRIVER, sim.host, str(sim.port)],
                                   cwd=ROOT)
            if w.wait(w.moving, 10) is None:
                drv.kill()
                raise SystemExit("benchmark: the robot never started moving")
            w.wait(lambda: False, 0.5)
            n_ev = len(w.stop_events)
            t_signal = time.time()
            drv.send_signal(how)
            t0 = time.monotonic()
            w.wait(w.stop_commanded, 5)
            t_cmd = time.monotonic() - t0 if w.stop_commanded() else None
            w.wait(w.stopped, 5)
            t_wheels = time.monotonic() - t0 if w.stopped() else None
            w.wait(lambda w=w, n=n_ev: len(w.stop_events) > n, 2)
            ev = w.stop_events[n_ev] if len(w.stop_events) > n_ev else None
            out.append((None if ev is None else ev[1] - t_signal,
                        None if ev is None else ev[0], t_cmd, t_wheels))
            drv.kill()
            drv.wait()
            w.sock.close()
            time.sleep(0.5)  # let the robot settle before the next trial
    return out


def loss_and_reconnect(app, trials: int) -> list[tuple[float | None, float | None]]:
    """Kill the robot: time until the desk shows 'lost'. Restart it on the same
    port: time until the desk is connected again."""
    res = []
    sim = SimRobotProcess(seed=5).start()
    port = sim.port
    link = RobotLink()
    link.connect_to(sim.host, port)
    spin(app, 15, lambda: link.state == "connected")
    for _ in range(trials):
        t0 = time.monotonic()
        sim.kill()
        lost = spin(app, 8, lambda: link.state in ("lost", "reconnecting"))
        t_lost = time.monotonic() - t0 if lost else None
        spin(app, 1.0)
        sim = SimRobotProcess(seed=5, port=port).start()
        t1 = time.monotonic()
        ok = spin(app, 10, lambda: link.state == "connected")
        res.append((t_lost, time.monotonic() - t1 if ok else None))
    link.shutdown()
    sim.stop()
    return res


def frozen_robot(app) -> tuple[float | None, float | None]:
    """Freeze the robot (SIGSTOP: the socket stays open, nothing arrives): time
    until the desk shows 'lost'. Thaw it (SIGCONT): time until connected again."""
    with SimRobotProcess(seed=6) as sim:
        link = RobotLink()
        link.connect_to(sim.host, sim.port)
        spin(app, 15, lambda: link.state == "connected")
        t0 = time.monotonic()
        sim.proc.send_signal(signal.SIGSTOP)
        lost = spin(app, 8, lambda: link.state in ("lost", "reconnecting"))
        t_lost = time.monotonic() - t0 if lost else None
        t1 = time.monotonic()
        sim.proc.send_signal(signal.SIGCONT)
        ok = spin(app, 10, lambda: link.state == "connected")
        t_back = time.monotonic() - t1 if ok else None
        link.shutdown()
    return t_lost, t_back


def deadman(trials: int) -> None:
    for how, what in ((signal.SIGKILL, "killed (SIGKILL)"), (signal.SIGSTOP, "frozen (SIGSTOP)")):
        fs = failsafe(trials, how)
        def f(x):
            return "never" if x is None else f"{x:.2f}"

        print(f"driving desk {what}:")
        print("  robot orders stop, s (goal <= 0.5)    "
              + ", ".join(f"{f(r[0])} ({r[1]})" for r in fs))
        print("  telemetry shows MCU at zero, s        " + ", ".join(f(r[2]) for r in fs))
        print("  wheels stopped, s                     " + ", ".join(f(r[3]) for r in fs),
              flush=True)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seconds", type=float, default=20.0, help="streaming run length")
    ap.add_argument("--no-window", action="store_true", help="link only, no main window")
    ap.add_argument("--trials", type=int, default=3, help="failsafe / reconnect trials")
    ap.add_argument("--patrol", action="store_true",
                    help="the robot patrols its default route while streaming")
    ap.add_argument("--deadman-only", action="store_true",
                    help="only the desk-killed / desk-frozen trials")
    a = ap.parse_args()
    app = QApplication.instance() or QApplication([])
    if a.deadman_only:
        deadman(a.trials)
        return 0
    s = streaming(app, a.seconds, not a.no_window, a.patrol)
    print(f"streaming {s['seconds']:.1f} s, desk {'window' if not a.no_window else 'link only'}"
          f"{', robot on patrol' if a.patrol else ''}")
    print(f"  telemetry messages/s      {s['telemetry_per_s']:8.1f}")
    print(f"  video frames/s            {s['video_fps']:8.1f}")
    print(f"  frame latency median ms   {s['latency_median_ms']:8.1f}   (goal <= 30)")
    print(f"  frame latency p95 ms      {s['latency_p95_ms']:8.1f}   (goal <= 60)")
    print(f"  event-loop stall max ms   {s['stall_max_ms']:8.1f}   (goal <= 50)")
    print(f"  event-loop stall p99 ms   {s['stall_p99_ms']:8.1f}")
    print(f"  stalls over 50 ms         {s['stalls_over_50ms']:8d}")
    deadman(a.trials)
    lr = loss_and_reconnect(app, a.trials)
    print("link loss shown, s (goal <= 4): "
          + ", ".join("never" if x is None else f"{x:.2f}" for x, _ in lr))
    print("reconnect after robot restart, s (goal <= 3): "
          + ", ".join("never" if y is None else f"{y:.2f}" for _, y in lr))
    fl, fb = frozen_robot(app)
    print(f"robot frozen (SIGSTOP): link loss shown after "
          f"{'never' if fl is None else f'{fl:.2f}'} s (goal <= 4); after thawing "
          f"reconnected in {'never' if fb is None else f'{fb:.2f}'} s (goal <= 3)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

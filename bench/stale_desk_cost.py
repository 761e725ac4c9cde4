"""What a desk whose link is lost costs its GUI thread while it only shows ages.

The window is built offscreen on a stand-in link (tests/ui/fakes.FakeLink), given
a few seconds of telemetry, poses, camera frames, a patrol status and the control
lease, and then the link is lost. From then on nothing arrives: the freshness
model's half-second tick is all that runs, and every display that shows a value's
age ("last known 15:17:21, 40 s ago") is redrawn when the model announces a
change. The model's clock is then driven by hand, ``--minutes`` of half-second
ticks (each followed by the event loop's pending work, paints included), and this
prints the announcements per minute and the GUI thread's CPU (``time.thread_time``)
per minute of stale desk, in the first minute (ages in seconds) and after it
(ages in minutes):

    QT_QPA_PLATFORM=offscreen .venv/bin/python bench/stale_desk_cost.py --minutes 5
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--minutes", type=float, default=5.0, help="stale desk time driven")
    args = ap.parse_args(argv)

    from PySide6.QtWidgets import QApplication

    app = QApplication.instance() or QApplication(sys.argv[:1])
    from app.comm import protocol as P
    from app.comm.link import ControlState
    from app.ui.main_window import MainWindow
    from app.ui.theme import apply_theme
    from tests.ui.fakes import FakeLink, make_frame

    apply_theme(app)
    link = FakeLink()
    win = MainWindow(link)
    win.resize(1440, 900)
    win.show()
    link.set_state("connected")
    link.control_changed.emit(ControlState("me", True, None, ""))
    link.patrol_status_received.emit(P.PatrolStatus(state="driving", route="north"))
    for k in range(30):  # 3 s at 10 Hz
        link.send_telemetry(gas_lel_pct=2.0 + 0.01 * k)
        link.pose_received.emit(P.Pose(x_m=1.0 + 0.01 * k, y_m=2.0, theta_rad=0.1))
        link.frame_decoded.emit(make_frame(k + 1, 640, 480))
        app.processEvents()
        time.sleep(0.1)
    link.set_state("lost")
    app.processEvents()

    fresh = win.freshness
    fresh._timer.stop()  # its ticks are driven below, on the clock below
    now = {"t": time.monotonic()}
    fresh.tracker._mono = lambda: now["t"]
    told = {"n": 0}
    fresh.changed.connect(lambda _s: told.__setitem__("n", told["n"] + 1))

    def run(minutes: float) -> tuple[float, float]:
        told["n"] = 0
        c0 = time.thread_time()
        for _ in range(int(minutes * 120)):
            now["t"] += 0.5
            fresh.refresh()
            app.processEvents()
        return told["n"] / minutes, (time.thread_time() - c0) * 1000 / minutes

    for name, minutes in (("first minute (ages in seconds)", 1.0),
                          (f"next {args.minutes - 1:g} min (ages in minutes)",
                           max(args.minutes - 1, 1.0))):
        per_min, cpu_ms = run(minutes)
        print(f"{name:34}: {per_min:6.1f} announcements/min, GUI CPU {cpu_ms:7.1f} ms/min",
              flush=True)
    print(f"pose shown: {win.pose_label.text()!r}")
    win.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())

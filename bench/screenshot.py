"""Render the desk window against a live simulated robot and save PNGs: the
camera tab while the robot inspects a gauge, the map tab during a patrol, and
the same desk a few seconds after the robot process was killed mid-patrol
(every value in its "last known" look, control "no link").

    QT_QPA_PLATFORM=offscreen .venv/bin/python bench/screenshot.py docs/screenshot.png
    (also writes docs/screenshot-map.png and docs/screenshot-lost-link.png beside it)
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from PySide6.QtWidgets import QApplication  # noqa: E402

from app.comm.link import RobotLink  # noqa: E402
from app.sim_process import SimRobotProcess  # noqa: E402
from app.ui.main_window import MainWindow  # noqa: E402
from app.ui.theme import apply_theme  # noqa: E402


def main() -> int:
    out = Path(sys.argv[1] if len(sys.argv) > 1 else "docs/screenshot.png")
    app = QApplication.instance() or QApplication([])
    apply_theme(app)
    out.parent.mkdir(parents=True, exist_ok=True)
    map_out = out.with_name(out.stem + "-map" + out.suffix)
    lost_out = out.with_name(out.stem + "-lost-link" + out.suffix)

    def run(seconds: float) -> None:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            app.processEvents()
            time.sleep(0.01)

    with SimRobotProcess(seed=2, time_scale=5.0) as sim:
        link = RobotLink()
        win = MainWindow(link)
        win.resize(1440, 900)
        win.show()
        link.connect_to(sim.host, sim.port)
        run(3)
        link.send_command("start_patrol", {})
        run(25)  # the robot drives along its route
        win.views.setCurrentWidget(win.map_panel)
        run(1)
        ok = win.grab().save(str(map_out))
        # the robot process dies mid-patrol: the desk shows what it last knew, and how old
        sim.kill()
        run(8)
        ok = win.grab().save(str(lost_out)) and ok
        win.views.setCurrentWidget(win.video_panel)
        link.shutdown()
        win.close()
    # the camera tab: the robot in front of a gauge, the desk reading it
    with SimRobotProcess(seed=2, extra=["--start-at", "PG-102"]) as sim:
        link = RobotLink()
        win = MainWindow(link)
        win.resize(1440, 900)
        win.show()
        link.connect_to(sim.host, sim.port)
        run(3)
        if hasattr(win, "meter_model"):
            win.meter_model.request_read("PG-102")
            # grab while the head is on the dial and the overlay is up
            end = time.monotonic() + 10
            while time.monotonic() < end and not win.meter_model.records():
                run(0.05)
        ok = win.grab().save(str(out)) and ok
        link.shutdown()
    print(f"{'wrote' if ok else 'could not write'} {out}, {map_out} and {lost_out}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())

"""Render the desk window against a live simulated robot and save a PNG.

    QT_QPA_PLATFORM=offscreen .venv/bin/python bench/screenshot.py docs/screenshot.png
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
    with SimRobotProcess(seed=2, time_scale=20.0) as sim:
        link = RobotLink()
        win = MainWindow(link)
        win.resize(1440, 900)
        win.show()
        link.connect_to(sim.host, sim.port)
        end = time.monotonic() + 12
        link.drive(0.4, 0.15)
        while time.monotonic() < end:
            app.processEvents()
            time.sleep(0.01)
        link.stop()
        for _ in range(50):
            app.processEvents()
            time.sleep(0.01)
        out.parent.mkdir(parents=True, exist_ok=True)
        ok = win.grab().save(str(out))
        link.shutdown()
    print(f"{'wrote' if ok else 'could not write'} {out}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())

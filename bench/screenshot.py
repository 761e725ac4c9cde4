"""Render the desk window against a live simulated robot and save PNGs:

- ``screenshot.png``: the camera tab while the desk reads a pressure gauge (the
  reading's overlay on the dial);
- ``screenshot-map.png``: the map tab during a patrol;
- ``screenshot-lost-link.png``: the same desk a few seconds after the robot process
  was killed mid-patrol (every value in its "last known … ago" look, control "no link");
- ``screenshot-replay.png``: a replay at ×2 of the archive that desk recorded during
  that run (view only, banner "REPLAY hh:mm:ss ×2").

The windows are built as ``station-patrol`` builds them (app/ui/app.build_window,
app/ui/replay.open_replay_window), around the desk pipeline; the archive lives in a
temporary folder and is removed at the end.

    QT_QPA_PLATFORM=offscreen .venv/bin/python bench/screenshot.py docs/screenshot.png
    (also writes docs/screenshot-map.png, -lost-link.png and -replay.png beside it)
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from PySide6.QtWidgets import QApplication  # noqa: E402

from app.comm.link import RobotLink  # noqa: E402
from app.core.records import Archive  # noqa: E402
from app.core.records.queries import choose_session  # noqa: E402
from app.session import open_archive  # noqa: E402
from app.sim_process import SimRobotProcess  # noqa: E402
from app.ui.app import build_window  # noqa: E402
from app.ui.main_window import MainWindow  # noqa: E402
from app.ui.replay import open_replay_window  # noqa: E402
from app.ui.theme import apply_theme  # noqa: E402

SIZE = (1440, 900)
PATROL_S = 25.0  # desk seconds of patrol before the map shot (the robot runs ×5)
LOST_S = 8.0  # seconds between killing the robot and the lost-link shot
REPLAY_AT_S = 12.0  # where in the recorded run (about 30 s) the replay shot starts


def run(app: QApplication, seconds: float) -> None:
    """Let the event loop run for ``seconds`` of wall time."""
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        app.processEvents()
        time.sleep(0.01)


def save(win, path: Path) -> bool:
    ok = win.grab().save(str(path))
    print(f"{'wrote' if ok else 'could not write'} {path}")
    return ok


def patrol_and_lose_link(app: QApplication, archive_path: Path, map_out: Path,
                         lost_out: Path) -> bool:
    """A desk with an archive on a patrolling robot; the map tab; then the robot dies."""
    archive, err = open_archive(path=archive_path, retention_days=None)
    if archive is None:
        raise RuntimeError(f"cannot open an archive at {archive_path}: {err}")
    with SimRobotProcess(seed=2, time_scale=5.0) as sim:
        link = RobotLink()
        win = build_window(link, archive=archive)
        win.resize(*SIZE)
        win.show()
        win.desk.gateway.send_when_connected("start_patrol", {})
        link.connect_to(sim.host, sim.port)
        win.views.setCurrentWidget(win.map_panel)
        run(app, PATROL_S)
        ok = save(win, map_out)
        # the robot process dies mid-patrol: the desk shows what it last knew, and how old
        sim.kill()
        run(app, LOST_S)
        ok = save(win, lost_out) and ok
        link.shutdown()
        win.desk.close()  # writes what is pending and closes the archive
        win.close()
    return ok


def replay(app: QApplication, archive_path: Path, out: Path) -> bool:
    """The run just recorded, played back at ×2 from REPLAY_AT_S into it."""
    archive = Archive(archive_path)
    try:
        rows, which = choose_session(archive, "latest")
        win, link = open_replay_window(MainWindow, rows, which)
        win.resize(*SIZE)
        win.show()
        link.start()
        link.set_speed(2.0)
        link.seek(link.clock.t0 + REPLAY_AT_S)
        link.play()
        win.views.setCurrentWidget(win.map_panel)
        run(app, 3.0)
        ok = save(win, out)
        link.shutdown()
        win.desk.close()
        win.close()
    finally:
        archive.close()
    return ok


def read_gauge(app: QApplication, out: Path) -> bool:
    """The robot in front of PG-102, the desk reading it: grabbed while the reading's
    overlay is on the dial (the overlay goes when the reading session ends)."""
    with SimRobotProcess(seed=2, extra=["--start-at", "PG-102"]) as sim:
        link = RobotLink()
        win = build_window(link)
        win.resize(*SIZE)
        win.show()
        link.connect_to(sim.host, sim.port)
        run(app, 3.0)
        shots = []
        # connected after the video view, so the grab shows the overlay just set
        win.meter_model.overlays_changed.connect(
            lambda overlays: shots.append(win.grab()) if overlays else None)
        win.meter_model.request_read("PG-102")
        end = time.monotonic() + 15
        while time.monotonic() < end and not win.meter_model.records():
            run(app, 0.05)
        pixmap = shots[-1] if shots else win.grab()
        if not shots:
            print("no meter reading came: the camera shot has no overlay")
        ok = pixmap.save(str(out))
        print(f"{'wrote' if ok else 'could not write'} {out}")
        link.shutdown()
        win.desk.close()
        win.close()
    return ok and bool(shots)


def main() -> int:
    out = Path(sys.argv[1] if len(sys.argv) > 1 else "docs/screenshot.png")
    app = QApplication.instance() or QApplication([])
    apply_theme(app)
    out.parent.mkdir(parents=True, exist_ok=True)

    def beside(tag: str) -> Path:
        return out.with_name(f"{out.stem}-{tag}{out.suffix}")

    with tempfile.TemporaryDirectory(prefix="screenshot-") as tmp:
        archive_path = Path(tmp) / "archive.sqlite"
        ok = patrol_and_lose_link(app, archive_path, beside("map"), beside("lost-link"))
        ok = replay(app, archive_path, beside("replay")) and ok
    ok = read_gauge(app, out) and ok
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())

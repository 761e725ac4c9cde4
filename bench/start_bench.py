"""Window start to first frame shown, in English and in Simplified Chinese.

Each run is a fresh Python process that does what ``station-patrol --connect`` does
before the robot answers: import the desk, make the QApplication, choose and install
the language (app/i18n: catalogue, CJK font), apply the theme, build the desk window
around a RobotLink (not connected: no robot is needed) and show it. The clock runs
from the process's first line to the window's first paint (its first frame on the
screen, or on Qt's offscreen surface without a display). Printed: the median of the
runs per language, wall time and the process's CPU time (the machine is shared, so
the CPU time is the steadier figure).

    QT_QPA_PLATFORM=offscreen .venv/bin/python bench/start_bench.py [--runs 3]
"""

from __future__ import annotations

import time

T0_WALL, T0_CPU = time.perf_counter(), time.process_time()

import argparse  # noqa: E402
import json  # noqa: E402
import os  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
from pathlib import Path  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
GOAL_S = 3.0


def one_start(lang: str) -> dict:
    """In this process: start the desk window in ``lang``; the figures at its first paint."""
    sys.path.insert(0, str(ROOT))
    from PySide6.QtCore import QEvent, QObject, QTimer
    from PySide6.QtWidgets import QApplication

    from app.comm.link import RobotLink
    from app.config import DeskConfig
    from app.i18n import start_language
    from app.ui.app import build_window
    from app.ui.theme import apply_theme

    app = QApplication(sys.argv[:1])
    installed = start_language(app, lang)
    apply_theme(app)
    cfg = DeskConfig()
    link = RobotLink(cfg.link)
    win = build_window(link)
    out: dict = {"lang": installed, "title": win.windowTitle()}

    class FirstPaint(QObject):
        def eventFilter(self, obj, ev):  # noqa: N802 (Qt's name)
            if ev.type() == QEvent.Type.Paint and "wall_s" not in out:
                out["wall_s"] = time.perf_counter() - T0_WALL
                out["cpu_s"] = time.process_time() - T0_CPU
                QTimer.singleShot(0, app.quit)
            return False

    spy = FirstPaint()
    win.installEventFilter(spy)
    win.resize(1440, 900)
    win.show()
    QTimer.singleShot(30_000, app.quit)  # a window that never paints ends the run too
    app.exec()
    link.shutdown()
    win.desk.close()
    return out


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--runs", type=int, default=3, help="fresh processes per language")
    p.add_argument("--one", metavar="LANG", help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    if args.one:
        print(json.dumps(one_start(args.one)), flush=True)
        return 0
    env = dict(os.environ)
    env.setdefault("QT_QPA_PLATFORM", "offscreen")
    ok = True
    with tempfile.TemporaryDirectory() as data:
        env["STATION_PATROL_DATA_DIR"] = data  # the desk's archive: not the user's
        for lang in ("en", "zh_CN"):
            runs = []
            for _ in range(args.runs):
                r = subprocess.run([sys.executable, __file__, "--one", lang], env=env,
                                   capture_output=True, text=True, timeout=120, cwd=ROOT)
                lines = [ln for ln in r.stdout.splitlines() if ln.startswith("{")]
                if r.returncode != 0 or not lines:
                    print(f"{lang}: the run failed:\n{r.stderr[-2000:]}", file=sys.stderr)
                    return 1
                runs.append(json.loads(lines[-1]))
            if any("wall_s" not in x or x["lang"] != lang for x in runs):
                print(f"{lang}: no first paint, or not in {lang}: {runs}", file=sys.stderr)
                return 1
            wall = statistics.median(x["wall_s"] for x in runs)
            cpu = statistics.median(x["cpu_s"] for x in runs)
            ok &= wall <= GOAL_S
            print(f"{lang:6s} window start -> first frame: {wall:.2f} s wall, {cpu:.2f} s CPU "
                  f"(median of {len(runs)}; title {runs[0]['title']!r}; goal <= {GOAL_S:g} s)")
    if hasattr(os, "getloadavg"):
        print(f"load average during the runs: {os.getloadavg()[0]:.1f} "
              f"on {os.cpu_count()} cores (wall time stretches with it; CPU time does not)")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())

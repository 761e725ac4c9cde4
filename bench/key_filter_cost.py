"""What the control panel's application-wide key filter costs each event delivered.

The filter (app.ui.control_panel._KeyFilter) sees every event the application
delivers (paints, timers, queued calls), not only keys. This sends a plain event to a
QObject many times, with and without one control panel's filter installed, in each
source tree given (interleaved rounds), and prints the difference per event in
microseconds of CPU (``time.thread_time``):

    QT_QPA_PLATFORM=offscreen .venv/bin/python bench/key_filter_cost.py /tmp/desk-base .
"""

from __future__ import annotations

import importlib
import os
import sys
import time

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")


def main(trees: list[str], n: int = 100_000, rounds: int = 3) -> int:
    from PySide6.QtCore import QCoreApplication, QEvent, QObject
    from PySide6.QtWidgets import QApplication, QWidget

    app = QApplication(sys.argv[:1])
    mods = {}
    for tree in trees:  # each tree's own control panel module
        sys.path.insert(0, os.path.abspath(tree))
        for name in [k for k in sys.modules if k == "app" or k.startswith("app.")]:
            del sys.modules[name]
        mods[tree] = importlib.import_module("app.ui.control_panel")
        sys.path.pop(0)
    target = QObject()

    def per_event_us() -> float:
        ev = QEvent(QEvent.Type.User)
        t = time.thread_time()
        for _ in range(n):
            QCoreApplication.sendEvent(target, ev)
        return (time.thread_time() - t) / n * 1e6

    window = QWidget()
    window.show()
    got: dict[str, list[float]] = {t: [] for t in trees}
    for _ in range(rounds):
        for tree, mod in mods.items():
            base = min(per_event_us() for _ in range(2))
            panel = mod.ControlPanel(window)
            with_filter = min(per_event_us() for _ in range(2))
            app.removeEventFilter(panel._key_filter)
            got[tree].append(with_filter - base)
    for tree, costs in got.items():
        print(f"{tree}: key filter CPU per event delivered, us ({rounds} rounds interleaved): "
              + ", ".join(f"{c:.2f}" for c in costs))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:] or ["."]))

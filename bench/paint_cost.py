"""What one redraw of the desk's busiest views costs on the GUI thread (CPU time).

The window is built offscreen on a stand-in link (tests/ui/fakes.FakeLink) and
given ten minutes of 10 Hz telemetry; then each of these is done ``--n`` times
and its CPU time (``time.process_time``, so other programs on a shared machine
count little) per repetition printed:

- plot: the data plots' refresh (the 10 min window) and their repaint;
- video: a 640 x 480 camera frame shown and the video view repainted;
- telemetry: one telemetry message through the pipeline into the views and painted;
- window: a repaint of the whole window.

    QT_QPA_PLATFORM=offscreen .venv/bin/python bench/paint_cost.py --n 50

``--ab ROUNDS`` instead compares the plots' old and new set-up in the same
window: pyqtgraph's own DateAxisItem (drawn anew at every range change) and
curves clipped to the view, against the strip's SlidingTimeAxis and no clipping,
swapped in and measured alternately, plot refresh and whole-window repaint,
ROUNDS times; it prints each round and the median of each.
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

import numpy as np  # noqa: E402


def cpu_ms(fn, n: int) -> float:
    t0 = time.process_time()
    for _ in range(n):
        fn()
    return (time.process_time() - t0) * 1000 / n


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, default=50, help="repetitions of each")
    ap.add_argument("--minutes", type=float, default=10.0, help="telemetry history")
    ap.add_argument("--ab", type=int, default=0, metavar="ROUNDS",
                    help="compare old and new time axes, alternating")
    args = ap.parse_args(argv)

    from PySide6.QtWidgets import QApplication

    app = QApplication.instance() or QApplication(sys.argv[:1])
    from app.ui.main_window import MainWindow
    from app.ui.theme import apply_theme
    from tests.ui.fakes import FakeLink, make_frame

    apply_theme(app)
    link = FakeLink()
    win = MainWindow(link)
    win.resize(1440, 900)
    win.show()
    link.set_state("connected")
    rng = np.random.default_rng(1)
    now = time.time()
    n_hist = int(args.minutes * 600)
    for i in range(n_hist):
        link.send_telemetry(received_s=now - (n_hist - i) / 10,
                            gas_lel_pct=2 + rng.normal(0, 0.3),
                            temp_c=25 + rng.normal(0, 0.2), humidity_pct=50 + rng.normal(0, 1))
    app.processEvents()
    frame = make_frame(1, 640, 480)
    frame.image[:] = rng.integers(0, 255, frame.image.shape, dtype=np.uint8)
    strip = win.data_panel.strip
    k = {"i": 0}

    def plot() -> None:  # the scene paints from the event loop, not in repaint()
        strip.mark_dirty()
        strip.refresh()
        app.processEvents()

    def video() -> None:
        k["i"] += 1
        frame.frame_id = k["i"]
        win.video_model.on_frame(frame)
        app.processEvents()

    def telemetry() -> None:
        link.send_telemetry(gas_lel_pct=2 + rng.normal(0, 0.3), temp_c=25.0,
                            humidity_pct=50.0)
        app.processEvents()

    if args.ab:
        ab_axes(strip, {"plot": plot, "window": win.repaint}, args.n, args.ab)
        win.close()
        return 0
    for name, fn in (("plot", plot), ("video", video), ("telemetry", telemetry),
                     ("window", win.repaint)):
        fn()  # the first time builds caches
        print(f"{name:>10}: {cpu_ms(fn, args.n):7.2f} ms CPU each", flush=True)
    win.close()
    return 0


def use_time_axes(strip, cls) -> None:
    """Give every plot of ``strip`` a new time axis of class ``cls``, set up as the
    strip sets up its own (grid, only the lowest labelled); with pyqtgraph's own
    axis also the curves' clipping to the view of the strip's earlier set-up."""
    import pyqtgraph as pg

    keys = strip.channels()
    for i, key in enumerate(keys):
        plot = strip.plot_item(key)
        plot.setAxisItems({"bottom": cls(orientation="bottom")})
        plot.updateGrid()  # showGrid() again would not reach an axis swapped in
        plot.getAxis("bottom").setStyle(showValues=i == len(keys) - 1)
        plot.setClipToView(cls is pg.DateAxisItem)
    strip.refresh()


def ab_axes(strip, fns: dict, n: int, rounds: int) -> None:
    import statistics

    import pyqtgraph as pg

    from app.widgets.time_axis import SlidingTimeAxis

    got: dict[tuple[str, str], list[float]] = {}
    for r in range(rounds):
        for label, cls in (("old", pg.DateAxisItem), ("new", SlidingTimeAxis)):
            use_time_axes(strip, cls)
            for name, fn in fns.items():
                fn()
                ms = cpu_ms(fn, n)
                got.setdefault((name, label), []).append(ms)
                print(f"round {r}: {name:>6} {label}: {ms:7.2f} ms CPU each", flush=True)
    for name in fns:
        old = statistics.median(got[(name, "old")])
        new = statistics.median(got[(name, "new")])
        print(f"{name:>6}: old {old:7.2f} ms, new {new:7.2f} ms (medians of {rounds})")


if __name__ == "__main__":
    sys.exit(main())

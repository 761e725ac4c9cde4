"""Where the desk's memory goes on a recorded patrol: Python-side or native.

A tape (``bench/desk_soak.py --record TAPE``) is played into the full window
(offscreen, with its archive, built by ``bench/isolated_desk.py`` as for
``bench/desk_replay_ab.py``), round after round, with ``tracemalloc`` on. After the
warm-up and then every ``--every`` minutes it prints the resident set size, what
``tracemalloc`` traces (Python's allocations), glibc's heap in use and free (native and
Python alike), and, against the first probe, the object counts that changed
(bench/soak_probe.py) and the allocation sites grown most.
RSS growth not matched by traced growth is native (Qt, numpy buffers, SQLite) or the
allocator's free-but-kept memory.

    QT_QPA_PLATFORM=offscreen .venv/bin/python bench/tape_memory.py \\
        --tape /tmp/patrol.tape --minutes 12 --every 4
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import tracemalloc
from pathlib import Path

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def _rss_mb() -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tape", required=True)
    ap.add_argument("--minutes", type=float, default=12.0, help="measured, after the warm-up")
    ap.add_argument("--every", type=float, default=4.0, help="minutes between probes")
    ap.add_argument("--warmup", type=float, default=60.0, help="seconds")
    ap.add_argument("--frames", type=int, default=1, help="traceback depth traced")
    ap.add_argument("--top", type=int, default=15)
    args = ap.parse_args(argv)

    from PySide6.QtCore import QTimer

    from bench import soak_probe
    from bench.isolated_desk import open_desk

    app, link, win = open_desk(args.tape, "desk-memory-")
    tracemalloc.start(max(1, args.frames))
    link.start()
    key = "traceback" if args.frames > 1 else "lineno"
    probes: list[dict] = []
    t0 = time.monotonic()

    def probe() -> None:
        soak_probe.trim_rss()
        p = {"t": time.monotonic() - t0, "rss": _rss_mb(), "counts": soak_probe.count_objects(win),
             "snap": tracemalloc.take_snapshot()}
        traced = sum(s.size for s in p["snap"].statistics("filename")) / 2**20
        c = p["counts"]
        print(f"\n== probe at {p['t'] / 60:.1f} min: RSS {p['rss']:.1f} MB, traced {traced:.1f} MB"
              f", malloc in use {c.get('malloc_kb:in_use', 0) / 1024:.1f} MB"
              f", malloc free {c.get('malloc_kb:free', 0) / 1024:.1f} MB"
              f", tape round {link.rounds}, {link.emitted} messages", flush=True)
        if probes:
            a = probes[0]
            print(f"  since the first probe: RSS {p['rss'] - a['rss']:+.1f} MB", flush=True)
            print("  object counts changed:", *[ln for ln in soak_probe.diff_counts(
                a["counts"], c) if not ln.endswith("(+0)")], sep="\n")
            print("  allocations grown most:",
                  *soak_probe.diff_tracemalloc(a["snap"], p["snap"], args.top, key), sep="\n",
                  flush=True)
            p["snap"] = None  # only the first is compared against: keep no more
        probes.append(p)

    timer = QTimer()
    timer.timeout.connect(probe)
    QTimer.singleShot(int(args.warmup * 1000), lambda: (probe(), timer.start(
        int(args.every * 60_000))))
    QTimer.singleShot(int((args.warmup + args.minutes * 60) * 1000 + 5000), win.close)
    app.exec()
    win.desk.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())

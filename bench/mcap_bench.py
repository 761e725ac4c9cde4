"""MCAP export benchmark: a 24 h session (the archive bench's 864 000-row day of 10 Hz
telemetry, 16 channels, plus poses at ``--pose-hz``) exported with ``export_mcap``.
Goal: <= 60 s. Prints the wall and CPU time, rows/s, the file's size, and checks the
file with the ``mcap`` reader's summary (every channel's message count).

    .venv/bin/python bench/mcap_bench.py [--hours 24] [--pose-hz 1] [--keep DIR]

``--keep DIR`` keeps (and reuses) the built archive there; building the day takes
about as long as the export.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from app.core.records import Archive  # noqa: E402
from bench.archive_bench import CHANNELS, feed, synthetic  # noqa: E402


def build_day(path: Path, hours: float, pose_hz: float) -> None:
    n = int(hours * 3600 * 10)
    a = Archive(path, batch_rows=20000)
    a.begin_session("bench", "synthetic")
    t, v = synthetic(n)
    chunk = 100_000
    started = time.perf_counter()
    for s in range(0, n, chunk):
        feed(a, t[s:s + chunk], v[s:s + chunk])
        if pose_hz > 0:
            step = max(1, int(round(10 / pose_hz)))
            for i in range(s - s % step + (step if s % step else 0), min(s + chunk, n), step):
                a.add_pose(float(t[i]), float(v[i, 4]), float(v[i, 5]), float(v[i, 6]))
        a.flush(timeout=600)
    a.close()
    print(f"built {hours:g} h: {n} telemetry rows x {len(CHANNELS)} channels, poses at "
          f"{pose_hz:g} Hz, in {time.perf_counter() - started:.1f} s; "
          f"{path.stat().st_size / 1e6:.0f} MB", flush=True)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--hours", type=float, default=24.0)
    ap.add_argument("--pose-hz", type=float, default=1.0)
    ap.add_argument("--keep", metavar="DIR", help="build the archive here once and reuse it")
    args = ap.parse_args(argv)
    from mcap.reader import make_reader

    from app.core.records.mcap_export import export_mcap
    from app.core.records.queries import choose_session

    with tempfile.TemporaryDirectory(prefix="mcap-bench-") as tmp:
        folder = Path(args.keep) if args.keep else Path(tmp)
        folder.mkdir(parents=True, exist_ok=True)
        db = folder / f"day-{args.hours:g}h-pose{args.pose_hz:g}.sqlite3"
        if not db.exists():
            build_day(db, args.hours, args.pose_hz)
        out = Path(tmp) / "day.mcap"
        a = Archive(db)
        rows, which = choose_session(a, "latest")
        marks: list[str] = []
        w0, c0 = time.perf_counter(), time.process_time()

        def progress(f: float) -> None:
            marks.append(f"{f * 100:.0f}%@{time.perf_counter() - w0:.0f}s")

        res = export_mcap(rows, out, progress=progress)
        wall, cpu = time.perf_counter() - w0, time.process_time() - c0
        a.close()
        print(f"export {which}: {res.messages} messages on {len(res.topics)} topics; "
              f"wall {wall:.1f} s, CPU {cpu:.1f} s ({res.messages / wall:,.0f} msg/s); "
              f"file {out.stat().st_size / 1e6:.0f} MB; goal <= 60 s", flush=True)
        print(f"  progress lines: {len(marks)} ({', '.join(marks[:3])} ... {marks[-1]})")
        with open(out, "rb") as f:
            summary = make_reader(f).get_summary()
        counts = summary.statistics.channel_message_counts
        for cid, ch in summary.channels.items():
            schema = summary.schemas[ch.schema_id].name
            ok = counts[cid] == res.topics[ch.topic].count
            print(f"  {ch.topic:<12} {schema:<28} {counts[cid]:>8} messages "
                  f"(matches the archive: {ok})")
    return 0


if __name__ == "__main__":
    sys.exit(main())

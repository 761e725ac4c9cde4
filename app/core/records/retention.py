"""The archive's retention: rows older than a cutoff are deleted in small chunks
(between write batches, in the writer thread), optionally exported first as CSV
files. Mixed into :class:`app.core.records.archive.Archive`; nothing here imports Qt.
"""

from __future__ import annotations

import csv
import math
import sqlite3
from datetime import UTC, datetime
from pathlib import Path

from app.core.records.queries import _iso
from app.core.records.schema import ROLLUP_LEVELS_S, TIMED_TABLES


class ArchiveRetention:
    """Pruning (and exporting) rows older than a cutoff, one chunk per call."""

    PRUNE_CHUNK = 5000

    def _prune_step(self, con: sqlite3.Connection, job: list) -> bool:
        """Export (once) and delete one chunk of rows older than the cutoff.
        Returns True when the job is done."""
        cutoff, export_dir = job[0], job[1]
        try:
            if export_dir is not None and len(job) == 3:
                job.append(self._export_old(con, cutoff, Path(export_dir)))
            for table in TIMED_TABLES:
                cur = con.execute(f"DELETE FROM {table} WHERE id IN (SELECT id FROM {table} "
                                  f"WHERE t < ? ORDER BY t LIMIT ?)",
                                  (cutoff, self.PRUNE_CHUNK))
                if cur.rowcount:
                    with self._lock:
                        self._pruned[table] = self._pruned.get(table, 0) + cur.rowcount
                    return False
            channels = [r[0] for r in con.execute("SELECT id FROM channel")]
            for level in ROLLUP_LEVELS_S:
                end = math.floor(cutoff / level)
                for cid in channels:
                    first = con.execute("SELECT min(bucket) FROM rollup WHERE level=? AND "
                                        "channel=?", (level, cid)).fetchone()[0]
                    if first is None or first >= end:
                        continue
                    cur = con.execute(
                        "DELETE FROM rollup WHERE level=? AND channel=? AND bucket < ?",
                        (level, cid, min(end, first + self.PRUNE_CHUNK)))
                    with self._lock:
                        self._pruned["rollup"] = self._pruned.get("rollup", 0) + cur.rowcount
                    return False
        except Exception as e:  # retention must never stop the writer
            self._report_failure(f"archive retention step failed: {e}")
            return True
        return True

    def _export_old(self, con: sqlite3.Connection, cutoff: float, folder: Path) -> list[str]:
        folder.mkdir(parents=True, exist_ok=True)
        stamp = datetime.fromtimestamp(cutoff, UTC).strftime("%Y%m%dT%H%M%SZ")
        written = []
        for table in TIMED_TABLES:
            if con.execute(f"SELECT 1 FROM {table} WHERE t < ? LIMIT 1", (cutoff,)).fetchone() \
                    is None:
                continue
            out = folder / f"{table}-before-{stamp}.csv"
            if table == "telemetry":
                self._export_telemetry(con, None, -math.inf, cutoff, out, upper_open=True)
            else:
                cur = con.execute(f"SELECT * FROM {table} WHERE t < ? ORDER BY t", (cutoff,))
                cols = [d[0] for d in cur.description]
                with open(out, "w", newline="", encoding="utf-8") as f:
                    w = csv.writer(f)
                    w.writerow(["time_utc", *cols])
                    for row in cur:
                        w.writerow([_iso(row[cols.index("t")]),
                                    *(f"<{len(x)} bytes>" if isinstance(x, bytes) else x
                                      for x in row)])
            written.append(str(out))
        with self._lock:
            self._exported.extend(written)
        return written

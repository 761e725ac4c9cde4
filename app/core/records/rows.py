"""The SQL that writes one batch of archive rows, inside one transaction.

Each queued item (kind, args) becomes its table's row; telemetry rows share a
channel layout and feed the per-level rollups (count, sum, min and max per bucket); a
snapshot given as an RGB image is made into a small JPEG here, in the writer
thread. Mixed into :class:`app.core.records.archive.Archive`; nothing here
imports Qt.
"""

from __future__ import annotations

import json
import logging
import sqlite3
from typing import Any

import numpy as np

from app.core.records.schema import ROLLUP_LEVELS_S

log = logging.getLogger("app.core.records.archive")  # the archive's one logger

# errors that dropping the row fixes (SQLite refused a value), unlike a full, locked or
# read-only disk, which retrying fixes
BAD_ITEM = (sqlite3.InterfaceError, sqlite3.ProgrammingError, sqlite3.DataError,
            sqlite3.IntegrityError, TypeError, ValueError, KeyError, OverflowError)
SNAPSHOT_WIDTH_PX = 320
SNAPSHOT_QUALITY = 70


def small_jpeg(image: Any, width: int = SNAPSHOT_WIDTH_PX) -> bytes | None:
    """A small JPEG (at most ``width`` px wide) of an RGB uint8 image, or None."""
    try:
        import cv2

        img = np.asarray(image)
        if img.dtype != np.uint8 or img.ndim != 3 or img.shape[2] != 3 or not img.size:
            return None
        h, w = img.shape[:2]
        if w > width:
            img = cv2.resize(img, (width, max(1, round(h * width / w))),
                             interpolation=cv2.INTER_AREA)
        ok, buf = cv2.imencode(".jpg", cv2.cvtColor(img, cv2.COLOR_RGB2BGR),
                               [cv2.IMWRITE_JPEG_QUALITY, SNAPSHOT_QUALITY])
        return buf.tobytes() if ok else None
    except Exception as e:  # a snapshot is a convenience; never stop recording
        log.warning("could not make a snapshot: %s", e)
        return None


def _json(d: Any) -> str:
    return json.dumps(d, default=str, separators=(",", ":"))


class ArchiveRows:
    """The writer thread's SQL: channels, layouts, rows and rollups of one batch."""

    def _channel_id(self, con: sqlite3.Connection, name: str) -> int:
        cid = self._chan_ids.get(name)
        if cid is None:
            con.execute("INSERT OR IGNORE INTO channel(name) VALUES (?)", (name,))
            cid = con.execute("SELECT id FROM channel WHERE name=?", (name,)).fetchone()[0]
            self._chan_ids[name] = cid
        return cid

    def _layout(self, con: sqlite3.Connection, names: tuple[str, ...]) -> tuple[int, list[int]]:
        got = self._layout_ids.get(names)
        if got is None:
            key = _json(list(names))
            con.execute("INSERT OR IGNORE INTO telemetry_layout(channels) VALUES (?)", (key,))
            lid = con.execute("SELECT id FROM telemetry_layout WHERE channels=?",
                              (key,)).fetchone()[0]
            got = (lid, [self._channel_id(con, n) for n in names])
            self._layout_ids[names] = got
        return got

    def _write_items(self, con: sqlite3.Connection, items: list,
                     careful: bool = False) -> dict[str, int]:
        """Write ``items`` in one transaction. ``careful``: each item in a savepoint of its
        own, and an item SQLite refuses (a bad value, not a bad disk) is dropped, counted
        and logged instead of failing the batch."""
        counts: dict[str, int] = {}
        tel_rows: list[tuple] = []
        by_layout: dict[int, tuple[list[int], list[float], list[bytes]]] = {}
        con.execute("BEGIN IMMEDIATE")
        for kind, a in items:
            if careful:
                con.execute("SAVEPOINT item")
                try:
                    self._write_one(con, kind, a, tel_rows, by_layout, careful)
                except BAD_ITEM as e:
                    con.execute("ROLLBACK TO item")
                    self._chan_ids.clear()  # a channel or layout this row added is gone
                    self._layout_ids.clear()
                    with self._lock:
                        self._dropped[f"bad_{kind}"] = self._dropped.get(f"bad_{kind}", 0) + 1
                    log.error("archive: a %s row was refused and dropped: %s", kind, e)
                    con.execute("RELEASE item")
                    continue
                con.execute("RELEASE item")
            else:
                self._write_one(con, kind, a, tel_rows, by_layout, careful)
            counts[kind] = counts.get(kind, 0) + 1
        if tel_rows:
            con.executemany("INSERT INTO telemetry(t, seq, layout, data, session) "
                            "VALUES (?,?,?,?,?)", tel_rows)
        for cids, ts, blobs in by_layout.values():
            self._upsert_rollups(con, cids, np.asarray(ts),
                                 np.frombuffer(b"".join(blobs), np.float64)
                                 .reshape(len(ts), len(cids)))
        con.execute("COMMIT")
        return counts

    def _write_one(self, con: sqlite3.Connection, kind: str, a: tuple, tel_rows: list,
                   by_layout: dict, careful: bool) -> None:
        *a, sid = a  # the session the row belongs to (stamped by _put)
        if kind == "telemetry":
            t, seq, names, data = a
            lid, cids = self._layout(con, names)
            if careful:  # row by row, so a refused row does not take the others along
                con.execute("INSERT INTO telemetry(t, seq, layout, data, session) "
                            "VALUES (?,?,?,?,?)", (t, seq, lid, data, sid))
            else:
                tel_rows.append((t, seq, lid, data, sid))
            g = by_layout.setdefault(lid, (cids, [], []))
            g[1].append(t)
            g[2].append(data)
        elif kind == "pose":
            con.execute("INSERT INTO pose(t, x, y, theta, session) VALUES (?,?,?,?,?)",
                        (*a, sid))
        elif kind == "event":
            con.execute("INSERT INTO event(t, kind, data, session) VALUES (?,?,?,?)", (*a, sid))
        elif kind == "scan":
            con.execute("INSERT INTO scan(t, angle_min, angle_increment, range_max, ranges, "
                        "session) VALUES (?,?,?,?,?,?)", (*a, sid))
        elif kind == "alarm_transition":
            con.execute(
                "INSERT INTO alarm_transition(t, alarm, source, priority, from_state, "
                "to_state, value, limit_value, unit, text, user, reason, origin, session) "
                "VALUES (?,?,?,?,?,?,?,?,?,?,?,?,?,?)", (*a, sid))
        elif kind == "command":
            t, user, command, args, seq, acked = a
            con.execute("INSERT INTO command(t, user, command, args, seq, acked, session) "
                        "VALUES (?,?,?,?,?,?,?)",
                        (t, user, command, args, seq,
                         None if acked is None else int(bool(acked)), sid))
        elif kind == "ack":
            seq, ok, reason, t = a
            cur = con.execute(
                "UPDATE command SET acked=?, ack_reason=?, ack_t=? WHERE id = ("
                "SELECT id FROM command WHERE seq=? AND session IS ? ORDER BY id DESC LIMIT 1)",
                (int(ok), reason, t, seq, sid))
            if cur.rowcount == 0:  # an ack for a command we never saw: keep it anyway
                con.execute("INSERT INTO event(t, kind, data, session) VALUES (?,?,?,?)",
                            (t, "command_ack_unmatched",
                             _json({"cmd_seq": seq, "ok": ok, "reason": reason}), sid))
        elif kind == "meter_reading":
            t, point, value, unit, conf, fused, state, error, jpeg = a
            snap = None
            if jpeg:
                snap = con.execute(
                    "INSERT INTO snapshot(t, reason, ref, size, jpeg, session) "
                    "VALUES (?,?,?,?,?,?)", (t, "meter", point, len(jpeg), jpeg, sid)).lastrowid
            con.execute("INSERT INTO meter_reading(t, point, value, unit, confidence, "
                        "fused, state, error, snapshot_id, session) "
                        "VALUES (?,?,?,?,?,?,?,?,?,?)",
                        (t, point, value, unit, conf, int(fused), state, error, snap, sid))
        elif kind == "snapshot":
            t, jpeg, reason, ref = a
            if jpeg:
                con.execute("INSERT INTO snapshot(t, reason, ref, size, jpeg, session) "
                            "VALUES (?,?,?,?,?,?)", (t, reason, ref, len(jpeg), jpeg, sid))
        elif kind == "map":
            con.execute("INSERT INTO map(t, png, session) VALUES (?,?,?)", (*a, sid))
        elif kind == "path":
            con.execute("INSERT INTO path(t, kind, points, session) VALUES (?,?,?,?)",
                        (*a, sid))
        elif kind == "session_robot":
            con.execute("UPDATE session SET robot=? WHERE id=?", (a[1], a[0]))
        elif kind == "session_end":
            con.execute("UPDATE session SET ended_t=? WHERE id=?", (a[1], a[0]))

    def _encode_image(self, kind: str, args: tuple) -> tuple[str, tuple]:
        """An RGB image given for a snapshot becomes a small JPEG here, in the writer
        thread, once (so the GUI thread never encodes)."""
        i = 1 if kind == "snapshot" else 8
        img = args[i]
        if img is None or isinstance(img, bytes):
            return kind, args
        jpeg = small_jpeg(img)
        if jpeg is None:
            with self._lock:
                self._dropped["bad_snapshot"] = self._dropped.get("bad_snapshot", 0) + 1
            log.warning("archive: a %s snapshot is not an RGB image; not stored", kind)
        return kind, (*args[:i], jpeg, *args[i + 1:])

    @staticmethod
    def _upsert_rollups(con: sqlite3.Connection, cids: list[int], t: np.ndarray,
                        v: np.ndarray) -> None:
        order = np.argsort(t, kind="stable")
        t, v = t[order], v[order]
        fin = np.isfinite(v)
        n_all = fin.astype(np.int64)
        s_all = np.where(fin, v, 0.0)
        lo_all = np.where(fin, v, np.inf)
        hi_all = np.where(fin, v, -np.inf)
        rows = []
        for level in ROLLUP_LEVELS_S:
            b = np.floor(t / level).astype(np.int64)
            starts = np.concatenate(([0], np.flatnonzero(np.diff(b)) + 1))
            buckets = b[starts]
            n = np.add.reduceat(n_all, starts, axis=0)
            s = np.add.reduceat(s_all, starts, axis=0)
            lo = np.minimum.reduceat(lo_all, starts, axis=0)
            hi = np.maximum.reduceat(hi_all, starts, axis=0)
            for j, cid in enumerate(cids):
                nz = n[:, j] > 0
                rows.extend(zip([level] * int(nz.sum()), [cid] * int(nz.sum()),
                                buckets[nz].tolist(), n[nz, j].tolist(), s[nz, j].tolist(),
                                lo[nz, j].tolist(), hi[nz, j].tolist(), strict=True))
        con.executemany(
            "INSERT INTO rollup(level, channel, bucket, n, sum, vmin, vmax) "
            "VALUES (?,?,?,?,?,?,?) ON CONFLICT(level, channel, bucket) DO UPDATE SET "
            "n = n + excluded.n, sum = sum + excluded.sum, "
            "vmin = min(vmin, excluded.vmin), vmax = max(vmax, excluded.vmax)", rows)

"""Reading the patrol archive: time ranges, down-sampled series (min of mins, max
of maxes, count-weighted means), journals, snapshots and CSV export.

:class:`ArchiveQueries` is the read half of :class:`app.core.records.Archive`; each
thread reads through its own connection (``query_only``), so the GUI can query while
the writer thread writes. Nothing here imports Qt.
"""

from __future__ import annotations

import csv
import json
import math
import sqlite3
from collections.abc import Iterable
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np

from app.core.i18n import translate
from app.core.records.schema import ROLLUP_LEVELS_S, TIMED_TABLES

__all__ = ["ArchiveQueries", "Series", "bin_series", "fmt_number"]


@dataclass
class Series:
    """One channel over a time range. Down-sampled: each point is a bin's mean, min, max."""

    channel: str
    t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    mean: np.ndarray = field(default_factory=lambda: np.zeros(0))
    vmin: np.ndarray = field(default_factory=lambda: np.zeros(0))
    vmax: np.ndarray = field(default_factory=lambda: np.zeros(0))
    source: str = "raw"  # "raw" or "rollup_<s>s"

    def __len__(self) -> int:
        return len(self.t)


def fmt_number(x: float) -> str:
    """The shortest text for a stored value; a value that is exactly a float32 (the
    wire's telemetry) prints at float32 precision: 18.1, not 18.100000381469727."""
    x = float(x)
    if math.isnan(x):
        return ""
    f32 = np.float32(x)
    if math.isfinite(x) and float(f32) == x:
        return str(f32)
    return repr(x)


def bin_series(t: np.ndarray, n: np.ndarray, s: np.ndarray, lo: np.ndarray, hi: np.ndarray,
               t0: float, t1: float, bins: int) -> tuple[np.ndarray, ...]:
    """Merge time-sorted samples (count, sum, min, max each) into ``bins`` equal bins.

    Returns (t, mean, vmin, vmax) of the non-empty bins; ``t`` is the count-weighted
    mean time of the bin's samples. Min and max are kept exactly (min of mins, max
    of maxes), so a one-sample spike survives any amount of down-sampling."""
    if len(t) == 0:
        z = np.zeros(0)
        return z, z, z, z
    span = max(t1 - t0, 1e-9)
    idx = np.clip(((t - t0) / span * bins).astype(np.int64), 0, bins - 1)
    starts = np.concatenate(([0], np.flatnonzero(np.diff(idx)) + 1))
    nn = np.add.reduceat(n, starts)
    keep = nn > 0
    tt = np.add.reduceat(t * n, starts)
    ss = np.add.reduceat(s, starts)
    mn = np.minimum.reduceat(lo, starts)
    mx = np.maximum.reduceat(hi, starts)
    nn = nn[keep]
    return tt[keep] / nn, ss[keep] / nn, mn[keep], mx[keep]


def _iso(t: float) -> str:
    return datetime.fromtimestamp(t, UTC).isoformat(timespec="milliseconds")


class ArchiveQueries:
    """Read methods of the archive (mixed into :class:`Archive`, which provides
    ``path``, ``_local`` and ``_readers``). On the archive they read every session;
    on a :class:`SessionView` (``archive.session_view(n)``) only session ``n``."""

    scope_session: int | None = None  # None: every session; 0: rows before sessions

    def _scope(self, table: str = "") -> tuple[str, tuple]:
        """SQL to add after a WHERE clause, and its parameters, for the session scope."""
        col = f"{table}.session" if table else "session"
        if self.scope_session is None:
            return "", ()
        if self.scope_session == 0:
            return f" AND {col} IS NULL", ()
        return f" AND {col} = ?", (self.scope_session,)

    # ------------------------------------------------------------ sessions
    def sessions(self) -> list[dict]:
        """Every session, oldest first: number, start and end (UTC s; end None while
        running or when the desk died), desk, robot, telemetry rows, and for rows
        written before sessions were recorded a session 0."""
        con = self._reader()
        out = [{"id": i, "started_t": a, "ended_t": b, "desk": d or "", "robot": r or ""}
               for i, a, b, d, r in con.execute(
                   "SELECT id, started_t, ended_t, desk, robot FROM session ORDER BY id")]
        counts = dict(con.execute("SELECT session, count(*) FROM telemetry GROUP BY session"))
        legacy = con.execute("SELECT min(t), max(t) FROM telemetry WHERE session IS NULL"
                             ).fetchone()
        for s in out:
            s["telemetry"] = int(counts.get(s["id"], 0))
        if legacy[0] is not None:
            out.insert(0, {"id": 0, "started_t": legacy[0], "ended_t": legacy[1],
                           "desk": "", "robot": "", "telemetry": int(counts.get(None, 0))})
        return out

    def session_info(self, session: int) -> dict | None:
        return next((s for s in self.sessions() if s["id"] == session), None)

    def latest_session(self, t0: float = -math.inf, t1: float = math.inf) -> int | None:
        """The newest session with telemetry in [t0, t1] (None: no telemetry there)."""
        r = self._reader().execute(
            "SELECT session FROM telemetry WHERE t >= ? AND t <= ? ORDER BY t DESC, id DESC "
            "LIMIT 1", (t0, t1)).fetchone()
        return None if r is None else (0 if r[0] is None else int(r[0]))

    def session_view(self, session: int) -> SessionView:
        """The same archive, read for ``session`` only (0: rows before sessions)."""
        return SessionView(self, int(session))

    def _reader(self) -> sqlite3.Connection:
        con = getattr(self._local, "con", None)
        if con is None:
            con = sqlite3.connect(self.path, timeout=5.0, check_same_thread=False)
            con.execute("PRAGMA query_only=1")
            self._local.con = con
            self._readers.append(con)
        return con

    def time_range(self) -> tuple[float, float] | None:
        con = self._reader()
        lo, hi = math.inf, -math.inf
        where, params = self._scope()
        where = " WHERE" + where[4:] if where else ""
        for table in TIMED_TABLES:
            a = con.execute(f"SELECT t FROM {table}{where} ORDER BY t LIMIT 1",
                            params).fetchone()
            if a is None:
                continue
            b = con.execute(f"SELECT t FROM {table}{where} ORDER BY t DESC LIMIT 1",
                            params).fetchone()
            lo, hi = min(lo, a[0]), max(hi, b[0])
        return None if lo == math.inf else (lo, hi)

    def channels(self) -> list[str]:
        return [r[0] for r in self._reader().execute("SELECT name FROM channel ORDER BY name")]

    def _raw_values(self, channels: list[str], t0: float, t1: float,
                    upper_open: bool = False, con: sqlite3.Connection | None = None
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(t, seq, values (N, len(channels))) of the raw telemetry rows in [t0, t1];
        NaN where a row has no such channel."""
        con = con or self._reader()
        layouts = {lid: json.loads(ch) for lid, ch in
                   con.execute("SELECT id, channels FROM telemetry_layout")}
        op = "<" if upper_open else "<="
        sw, sp = self._scope()
        rows = con.execute(f"SELECT t, seq, layout, data FROM telemetry WHERE t >= ? AND t {op} ?"
                           f"{sw} ORDER BY t", (t0, t1, *sp)).fetchall()
        n = len(rows)
        t = np.fromiter((r[0] for r in rows), np.float64, n)
        seq = np.fromiter((-1 if r[1] is None else r[1] for r in rows), np.int64, n)
        out = np.full((n, len(channels)), np.nan)
        lay = np.fromiter((r[2] for r in rows), np.int64, n)
        for lid in np.unique(lay):
            names = layouts.get(int(lid), [])
            sel = np.flatnonzero(lay == lid)
            block = np.frombuffer(b"".join(rows[i][3] for i in sel), np.float64) \
                .reshape(len(sel), len(names))
            for j, ch in enumerate(channels):
                if ch in names:
                    out[sel, j] = block[:, names.index(ch)]
        return t, seq, out

    def series(self, channel: str, t0: float, t1: float, max_points: int = 2000) -> Series:
        """``channel`` over [t0, t1]; at most ``max_points`` points, each the mean/min/max
        of its bin (from the roll-ups when the range is long)."""
        max_points = max(1, int(max_points))
        con = self._reader()
        row = con.execute("SELECT id FROM channel WHERE name=?", (channel,)).fetchone()
        if row is None or t1 < t0:
            return Series(channel)
        cid = row[0]
        width = (t1 - t0) / max_points
        level = max((lv for lv in ROLLUP_LEVELS_S if lv <= width), default=None)
        if level is None or self.scope_session is not None:  # roll-ups mix sessions
            t, _seq, v = self._raw_values([channel], t0, t1)
            v = v[:, 0]
            ok = np.isfinite(v)
            t, v = t[ok], v[ok]
            if len(t) <= max_points:
                return Series(channel, t, v.copy(), v.copy(), v.copy(), "raw")
            tt, mean, lo, hi = bin_series(t, np.ones(len(t)), v, v, v, t0, t1, max_points)
            return Series(channel, tt, mean, lo, hi, "raw")
        rows = con.execute(
            "SELECT bucket, n, sum, vmin, vmax FROM rollup WHERE level=? AND channel=? "
            "AND bucket >= ? AND bucket <= ? ORDER BY bucket",
            (level, cid, math.floor(t0 / level), math.floor(t1 / level))).fetchall()
        if not rows:
            return Series(channel, source=f"rollup_{level}s")
        a = np.array(rows, np.float64)
        tb = (a[:, 0] + 0.5) * level
        tt, mean, lo, hi = bin_series(tb, a[:, 1], a[:, 2], a[:, 3], a[:, 4], t0, t1,
                                      max_points)
        return Series(channel, tt, mean, lo, hi, f"rollup_{level}s")

    def telemetry_values(self, channels: list[str], t0: float = -math.inf,
                         t1: float = math.inf) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Raw rows in [t0, t1]: (t, seq (-1 when none), values (N, len(channels)),
        NaN where a row lacks a channel)."""
        return self._raw_values(list(channels), t0, t1)

    def telemetry_count(self, t0: float = -math.inf, t1: float = math.inf) -> int:
        sw, sp = self._scope()
        return self._reader().execute(f"SELECT count(*) FROM telemetry WHERE t >= ? AND t <= ?"
                                      f"{sw}", (t0, t1, *sp)).fetchone()[0]

    def telemetry_seqs(self, t0: float = -math.inf, t1: float = math.inf) -> np.ndarray:
        sw, sp = self._scope()
        rows = self._reader().execute(f"SELECT seq FROM telemetry WHERE t >= ? AND t <= ?{sw} "
                                      "ORDER BY id", (t0, t1, *sp)).fetchall()
        return np.array([-1 if r[0] is None else r[0] for r in rows], np.int64)

    def telemetry_rows(self, t0: float, t1: float, *, upper_open: bool = False
                       ) -> tuple[np.ndarray, np.ndarray, list[str], np.ndarray]:
        """The raw telemetry messages in [t0, t1] (or [t0, t1) with ``upper_open``),
        as received, for replay: (t, seq, channel names, values (N, channels)); NaN
        where a message lacked a channel, seq -1 where none was recorded."""
        channels = self.channels()
        t, seq, v = self._raw_values(channels, t0, t1, upper_open)
        return t, seq, channels, v

    def channel_stats(self, channel: str, t0: float, t1: float) -> dict | None:
        """Exact ``{n, min, max, mean}`` of ``channel`` over [t0, t1], or None when it
        has no samples there: whole seconds from the 1 s roll-ups, the part-seconds
        at both ends from the raw rows."""
        con = self._reader()
        row = con.execute("SELECT id FROM channel WHERE name=?", (channel,)).fetchone()
        if row is None or t1 < t0:
            return None
        lo_b, hi_b = math.ceil(t0), math.floor(t1)  # whole buckets [lo_b, hi_b)
        n, s, vmin, vmax = 0, 0.0, math.inf, -math.inf
        edges = [(t0, t1, False)]
        if hi_b > lo_b and self.scope_session is None:  # roll-ups mix sessions
            r = con.execute("SELECT sum(n), sum(sum), min(vmin), max(vmax) FROM rollup "
                            "WHERE level=1 AND channel=? AND bucket >= ? AND bucket < ?",
                            (row[0], lo_b, hi_b)).fetchone()
            if r[0]:
                n, s, vmin, vmax = int(r[0]), float(r[1]), float(r[2]), float(r[3])
            edges = [(t0, float(lo_b), True), (float(hi_b), t1, False)]
        for a, b, open_ in edges:
            _t, _seq, v = self._raw_values([channel], a, b, open_)
            v = v[:, 0][np.isfinite(v[:, 0])]
            if len(v):
                n += len(v)
                s += float(v.sum())
                vmin, vmax = min(vmin, float(v.min())), max(vmax, float(v.max()))
        if n == 0:
            return None
        return {"n": n, "min": vmin, "max": vmax, "mean": s / n}

    def events(self, t0: float, t1: float, kinds: Iterable[str] | None = None) -> list[dict]:
        sw, sp = self._scope()
        sql = f"SELECT id, t, kind, data FROM event WHERE t >= ? AND t <= ?{sw}"
        params: list[Any] = [t0, t1, *sp]
        if kinds is not None:
            kinds = list(kinds)
            sql += f" AND kind IN ({','.join('?' * len(kinds))})"
            params += kinds
        return [{"id": i, "t": t, "kind": k, "data": json.loads(d)}
                for i, t, k, d in self._reader().execute(sql + " ORDER BY t, id", params)]

    def _dicts(self, sql: str, params: tuple) -> list[dict]:
        cur = self._reader().execute(sql, params)
        cols = [d[0] for d in cur.description]
        return [dict(zip(cols, r, strict=True)) for r in cur]

    def alarm_transitions(self, t0: float, t1: float) -> list[dict]:
        out = self._dicts("SELECT id, t, alarm, source, priority, from_state, to_state, value, "
                          "limit_value, unit, text, user, reason FROM alarm_transition "
                          f"WHERE t >= ? AND t <= ?{self._scope()[0]} ORDER BY t, id",
                          (t0, t1, *self._scope()[1]))
        for d in out:
            d["limit"] = d.pop("limit_value")
        return out

    def meter_readings(self, t0: float, t1: float, fused_only: bool = True) -> list[dict]:
        sql = ("SELECT id, t, point, value, unit, confidence, fused, state, error, snapshot_id "
               "FROM meter_reading WHERE t >= ? AND t <= ?" + self._scope()[0])
        if fused_only:
            sql += " AND fused = 1"
        out = self._dicts(sql + " ORDER BY t, id", (t0, t1, *self._scope()[1]))
        for d in out:
            d["fused"] = bool(d["fused"])
        return out

    def commands(self, t0: float, t1: float) -> list[dict]:
        out = self._dicts("SELECT id, t, user, command, args, seq, acked, ack_reason, ack_t "
                          f"FROM command WHERE t >= ? AND t <= ?{self._scope()[0]} "
                          "ORDER BY t, id", (t0, t1, *self._scope()[1]))
        for d in out:
            d["args"] = json.loads(d["args"])
            d["acked"] = None if d["acked"] is None else bool(d["acked"])
        return out

    def poses(self, t0: float, t1: float, max_points: int | None = None) -> np.ndarray:
        sw, sp = self._scope()
        rows = self._reader().execute(f"SELECT t, x, y, theta FROM pose WHERE t >= ? AND t <= ?"
                                      f"{sw} ORDER BY t", (t0, t1, *sp)).fetchall()
        a = np.array(rows, np.float64).reshape(-1, 4)
        if max_points is not None and len(a) > max_points > 1:
            idx = np.unique(np.linspace(0, len(a) - 1, max_points).round().astype(np.int64))
            a = a[idx]
        return a

    def snapshots(self, t0: float, t1: float) -> list[dict]:
        return self._dicts("SELECT id, t, reason, ref, size FROM snapshot "
                           f"WHERE t >= ? AND t <= ?{self._scope()[0]} ORDER BY t, id",
                           (t0, t1, *self._scope()[1]))

    def snapshot(self, snapshot_id: int) -> bytes | None:
        r = self._reader().execute("SELECT jpeg FROM snapshot WHERE id=?",
                                   (int(snapshot_id),)).fetchone()
        return None if r is None else bytes(r[0])

    def latest_map(self, t: float | None = None) -> bytes | None:
        t = math.inf if t is None else t
        sw, sp = self._scope()
        r = self._reader().execute(f"SELECT png FROM map WHERE t <= ?{sw} "
                                   "ORDER BY t DESC, id DESC LIMIT 1", (t, *sp)).fetchone()
        return None if r is None else bytes(r[0])

    def paths(self, t0: float, t1: float) -> list[dict]:
        return [{"id": i, "t": t, "kind": k,
                 "points": np.frombuffer(p, np.float32).reshape(-1, 2).copy()}
                for i, t, k, p in self._reader().execute(
                    f"SELECT id, t, kind, points FROM path WHERE t >= ? AND t <= ?"
                    f"{self._scope()[0]} ORDER BY t, id", (t0, t1, *self._scope()[1]))]

    def export_csv(self, channels: list[str] | None, t0: float, t1: float,
                   path: str | Path) -> int:
        """Raw telemetry of ``channels`` (all when None) in [t0, t1] as CSV; returns rows."""
        return self._export_telemetry(self._reader(), channels, t0, t1, Path(path))

    def _export_telemetry(self, con: sqlite3.Connection, channels: list[str] | None,
                          t0: float, t1: float, out: Path, upper_open: bool = False) -> int:
        if channels is None:
            channels = [r[0] for r in con.execute("SELECT name FROM channel ORDER BY id")]
        t, seq, v = self._raw_values(list(channels), t0, t1, upper_open, con)
        out.parent.mkdir(parents=True, exist_ok=True)
        with open(out, "w", newline="", encoding="utf-8") as f:
            w = csv.writer(f)
            w.writerow(["time_utc", "t", "seq", *channels])
            for i in range(len(t)):
                w.writerow([_iso(t[i]), f"{t[i]:.3f}", "" if seq[i] < 0 else int(seq[i]),
                            *(fmt_number(x) for x in v[i])])
        return len(t)

    def integrity_check(self) -> str:
        return self._reader().execute("PRAGMA integrity_check").fetchone()[0]

    def counts(self) -> dict[str, int]:
        con = self._reader()
        return {t: con.execute(f"SELECT count(*) FROM {t}").fetchone()[0]
                for t in (*TIMED_TABLES, "rollup")}


class SessionView(ArchiveQueries):
    """One session of an archive, read through the archive's own connections: every
    query sees only that session's rows (``session 0``: rows written before the
    archive recorded sessions)."""

    def __init__(self, archive: ArchiveQueries, session: int) -> None:
        self.archive = archive
        self.scope_session = session
        self.path = archive.path
        self._local = archive._local
        self._readers = archive._readers

    def describe(self) -> str:
        """"session 7 — robot 127.0.0.1:35971, desk root@vm, 2026-12-01 15:46 UTC"."""
        return describe_session(self.archive.session_info(self.scope_session)
                                or {"id": self.scope_session})

    def close(self) -> None:
        close = getattr(self.archive, "close", None)
        if close is not None:
            close()


def describe_session(s: dict) -> str:
    """A session in one line, for titles and report headers."""
    if s.get("id") == 0:
        return translate("Session", "session 0 (recorded before sessions: desks and robots not "
                                   "told apart)")
    parts = []
    if s.get("robot"):
        parts.append(translate("Session", "robot {name}").format(name=s["robot"]))
    if s.get("desk"):
        parts.append(translate("Session", "desk {name}").format(name=s["desk"]))
    if s.get("started_t") is not None:
        parts.append(translate("Session", "from {time} UTC").format(
            time=_iso(s["started_t"])[:19].replace("T", " ")))
    return (translate("Session", "session {id}").format(id=s.get("id"))
            + (" — " + ", ".join(parts) if parts else ""))


def choose_session(archive: ArchiveQueries, which: str | int | None = "latest",
                   t0: float = -math.inf, t1: float = math.inf
                   ) -> tuple[ArchiveQueries, str]:
    """The rows a view, replay or report reads, and a line saying which:
    ``"latest"`` (or None): the newest session with telemetry in [t0, t1];
    a number: that session; ``"all"``: every session mixed (said so).
    Raises ValueError for a session the archive does not hold."""
    if which in (None, "latest"):
        sid = archive.latest_session(t0, t1)
        if sid is None:
            return archive, "no session has telemetry in this range"
        view = archive.session_view(sid)
        return view, view.describe()
    if which == "all":
        return archive, translate("Session",
                                  "all sessions mixed (desks and robots not told apart)")
    try:
        sid = int(which)
    except (TypeError, ValueError):
        raise ValueError(f"session must be a number, 'latest' or 'all', not {which!r}") from None
    info = archive.session_info(sid)
    if info is None:
        known = ", ".join(str(s["id"]) for s in archive.sessions()) or "none"
        raise ValueError(f"no session {sid} in the archive (sessions: {known})")
    return archive.session_view(sid), describe_session(info)

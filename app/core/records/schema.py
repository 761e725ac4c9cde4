"""The archive's tables. Times are UTC epoch seconds (REAL); every table has a time index.

Telemetry is stored one row per received message: the values packed as float64 in a
BLOB, with the channel names of that message kept once in ``telemetry_layout``. Roll-ups
per channel (1 s, 10 s and 60 s buckets: count, sum, min, max) are maintained in the
same transaction as the raw rows, so long-range plots read a few thousand rows.

Lidar scans (``scan``) are kept decimated and bounded (see :mod:`.scans`): at most
one per ``scan_every_s`` (1 s), at most 720 beams, ranges as unsigned 16-bit
millimetres (65535: no return) — 720 bytes a scan, about 62 MB a day at 1 Hz.

Sessions (schema 2): one row in ``session`` per desk run (its desk and the robot it
was connected to), and a ``session`` column on every timed table naming the run that
wrote the row; rows of a schema-1 archive keep NULL there (shown as session 0,
"recorded before sessions"). Roll-ups stay per channel over all sessions; a query
scoped to one session reads its raw rows.
"""

from __future__ import annotations

APP_ID = "station-patrol"
SCHEMA_VERSION = 2
ROLLUP_LEVELS_S = (1, 10, 60)

SCHEMA = """
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS channel (id INTEGER PRIMARY KEY, name TEXT NOT NULL UNIQUE);
CREATE TABLE IF NOT EXISTS telemetry_layout (
    id INTEGER PRIMARY KEY, channels TEXT NOT NULL UNIQUE);
CREATE TABLE IF NOT EXISTS telemetry (
    id INTEGER PRIMARY KEY, t REAL NOT NULL, seq INTEGER,
    layout INTEGER NOT NULL REFERENCES telemetry_layout(id), data BLOB NOT NULL);
CREATE INDEX IF NOT EXISTS telemetry_t ON telemetry(t);
CREATE TABLE IF NOT EXISTS rollup (
    level INTEGER NOT NULL, channel INTEGER NOT NULL, bucket INTEGER NOT NULL,
    n INTEGER NOT NULL, sum REAL NOT NULL, vmin REAL NOT NULL, vmax REAL NOT NULL,
    PRIMARY KEY (level, channel, bucket)) WITHOUT ROWID;
CREATE TABLE IF NOT EXISTS snapshot (
    id INTEGER PRIMARY KEY, t REAL NOT NULL, reason TEXT NOT NULL, ref TEXT,
    size INTEGER NOT NULL, jpeg BLOB NOT NULL);
CREATE INDEX IF NOT EXISTS snapshot_t ON snapshot(t);
CREATE TABLE IF NOT EXISTS meter_reading (
    id INTEGER PRIMARY KEY, t REAL NOT NULL, point TEXT NOT NULL, value REAL, unit TEXT,
    confidence REAL, fused INTEGER NOT NULL, state TEXT, error TEXT,
    snapshot_id INTEGER REFERENCES snapshot(id));
CREATE INDEX IF NOT EXISTS meter_reading_t ON meter_reading(t);
CREATE TABLE IF NOT EXISTS alarm_transition (
    id INTEGER PRIMARY KEY, t REAL NOT NULL, alarm TEXT NOT NULL, source TEXT,
    priority TEXT, from_state TEXT, to_state TEXT, value REAL, limit_value REAL,
    unit TEXT, text TEXT, user TEXT, reason TEXT, origin TEXT);
CREATE INDEX IF NOT EXISTS alarm_transition_t ON alarm_transition(t);
CREATE INDEX IF NOT EXISTS alarm_transition_alarm ON alarm_transition(alarm, t);
CREATE TABLE IF NOT EXISTS command (
    id INTEGER PRIMARY KEY, t REAL NOT NULL, user TEXT, command TEXT NOT NULL,
    args TEXT NOT NULL, seq INTEGER, acked INTEGER, ack_reason TEXT, ack_t REAL);
CREATE INDEX IF NOT EXISTS command_t ON command(t);
CREATE INDEX IF NOT EXISTS command_seq ON command(seq);
CREATE TABLE IF NOT EXISTS event (
    id INTEGER PRIMARY KEY, t REAL NOT NULL, kind TEXT NOT NULL, data TEXT NOT NULL);
CREATE INDEX IF NOT EXISTS event_t ON event(t);
CREATE INDEX IF NOT EXISTS event_kind ON event(kind, t);
CREATE TABLE IF NOT EXISTS pose (
    id INTEGER PRIMARY KEY, t REAL NOT NULL, x REAL NOT NULL, y REAL NOT NULL,
    theta REAL NOT NULL);
CREATE INDEX IF NOT EXISTS pose_t ON pose(t);
CREATE TABLE IF NOT EXISTS map (id INTEGER PRIMARY KEY, t REAL NOT NULL, png BLOB NOT NULL);
CREATE INDEX IF NOT EXISTS map_t ON map(t);
CREATE TABLE IF NOT EXISTS path (
    id INTEGER PRIMARY KEY, t REAL NOT NULL, kind TEXT NOT NULL, points BLOB NOT NULL);
CREATE INDEX IF NOT EXISTS path_t ON path(t);
CREATE TABLE IF NOT EXISTS scan (
    id INTEGER PRIMARY KEY, t REAL NOT NULL, angle_min REAL NOT NULL,
    angle_increment REAL NOT NULL, range_max REAL NOT NULL, ranges BLOB NOT NULL);
CREATE INDEX IF NOT EXISTS scan_t ON scan(t);
CREATE TABLE IF NOT EXISTS session (
    id INTEGER PRIMARY KEY, started_t REAL NOT NULL, ended_t REAL, desk TEXT, robot TEXT);
"""

def add_session_columns(con) -> None:
    """Schema 1 -> 2: a ``session`` column (and an index) on every timed table."""
    for table in TIMED_TABLES:
        cols = {r[1] for r in con.execute(f"PRAGMA table_info({table})")}
        if "session" not in cols:
            con.execute(f"ALTER TABLE {table} ADD COLUMN session INTEGER")
        con.execute(f"CREATE INDEX IF NOT EXISTS {table}_session ON {table}(session, t)")


def add_origin_column(con) -> None:
    """``alarm_transition.origin`` (where the user acted from: an OPC UA client's address
    and application), added to an archive made before it; NULL in older rows. Readers
    that do not know it are not affected, so the schema version stays."""
    cols = {r[1] for r in con.execute("PRAGMA table_info(alarm_transition)")}
    if "origin" not in cols:
        con.execute("ALTER TABLE alarm_transition ADD COLUMN origin TEXT")


# tables with a time column ``t``, in the order retention prunes them
TIMED_TABLES = ("telemetry", "meter_reading", "snapshot", "alarm_transition", "command",
                "event", "pose", "map", "path", "scan")

"""The desk's archive writer keeps a small SQLite page cache: writing on for hours
does not grow what SQLite holds past it (its default, 2000 KiB, filled over a
desk's first minutes)."""

from __future__ import annotations

import pytest

from app.session import WRITER_CACHE_KIB, open_archive
from bench.soak_probe import sqlite_kb

T0 = 1_800_000_000.0


def _write(archive, start: float, n: int) -> float:
    t = start
    for i in range(n):
        archive.add_telemetry(t, {"gas_lel_pct": 1.0 + i % 7, "temp_c": 20.0,
                                  "humidity_pct": 50.0})
        t += 0.1
    assert archive.flush(60)
    return t


def test_the_writer_cache_is_bounded(tmp_path):
    archive, error = open_archive(path=tmp_path / "archive.sqlite3")
    assert error is None
    try:
        size = archive.call_in_writer(lambda con: con.execute("PRAGMA cache_size").fetchone())
        assert size[0] == -WRITER_CACHE_KIB
        if sqlite_kb() < 0:
            pytest.skip("SQLite's memory counter is not reachable here (libsqlite3.so.0)")
        t = _write(archive, T0, 2000)
        filled = sqlite_kb()
        # 8x the rows again: a 2000 KiB default cache grows by well over a megabyte
        _write(archive, t, 16_000)
        grown = sqlite_kb() - filled
        assert grown < WRITER_CACHE_KIB, (filled, grown)
        assert archive.telemetry_count() == 18_000  # (a reader: its own cache, after)
    finally:
        archive.close()

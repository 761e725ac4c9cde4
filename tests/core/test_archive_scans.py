"""Lidar scans in the archive: decimated in time and beams, ranges packed to mm."""

from __future__ import annotations

import math
import sqlite3

import numpy as np

from app.core.records import Archive
from app.core.records.scans import NO_RETURN, ScanDecimator, pack_ranges, unpack_ranges


def test_ranges_pack_to_millimetres_with_no_return():
    r = np.array([0.0, 1.2345, 11.9996, np.inf, np.nan, -1.0, 99.0])
    back = unpack_ranges(pack_ranges(r))
    np.testing.assert_allclose(back[:3], [0.0, 1.2345, 11.9996], atol=5e-4)
    assert np.isinf(back[3:6]).all()  # inf, NaN and negative: no return
    assert back[6] == (NO_RETURN - 1) / 1000.0  # beyond 65.534 m: clipped, not lost


def test_decimator_keeps_one_a_second_and_at_most_max_beams():
    d = ScanDecimator(every_s=1.0, max_beams=720)
    kept = [d.take(10.0 + 0.2 * i, -math.pi, 2 * math.pi / 1440, np.ones(1440))
            for i in range(10)]
    assert [k is not None for k in kept] == [True, False, False, False, False] * 2
    amin, inc, blob = kept[0]
    assert len(blob) == 720 * 2 and inc == 2 * (2 * math.pi / 1440)
    assert (d.kept, d.skipped) == (2, 8)


def test_archive_stores_the_kept_scans(tmp_path):
    a = Archive(tmp_path / "a.sqlite3")
    ranges = np.linspace(0.2, 10.0, 360)
    stored = [a.add_scan(100.0 + 0.2 * i, -math.pi, math.pi / 180, 12.0, ranges)
              for i in range(25)]
    a.close()
    assert sum(stored) == 5
    con = sqlite3.connect(tmp_path / "a.sqlite3")
    try:
        rows = con.execute("SELECT t, range_max, length(ranges) FROM scan ORDER BY t").fetchall()
    finally:
        con.close()
    assert [r[0] for r in rows] == [100.0, 101.0, 102.0, 103.0, 104.0]
    assert all(r[1:] == (12.0, 720) for r in rows)  # 720 bytes a 360-beam scan

"""The archive's queries for replay and reports: raw telemetry rows, exact channel stats."""

import numpy as np
import pytest

from app.core.records import Archive


@pytest.fixture
def archive(tmp_path):
    a = Archive(tmp_path / "a.sqlite3")
    yield a
    a.close()


def test_telemetry_rows_come_back_as_received(archive):
    t0 = 1_700_000_000.25
    for k in range(25):
        vals = {"gas_lel_pct": float(k), "temp_c": 20.0 + k}
        if k == 3:
            vals = {"gas_lel_pct": 3.0}  # a message without temp_c
        archive.add_telemetry(t0 + 0.1 * k, vals, seq=100 + k)
    assert archive.flush()
    t, seq, names, v = archive.telemetry_rows(t0, t0 + 10)
    assert sorted(names) == ["gas_lel_pct", "temp_c"]
    g, tc = v[:, names.index("gas_lel_pct")], v[:, names.index("temp_c")]
    assert list(seq) == list(range(100, 125))
    assert np.allclose(g, np.arange(25.0))
    assert np.isnan(tc[3]) and tc[4] == 24.0
    t, *_ = archive.telemetry_rows(t0, t0 + 1.0, upper_open=True)
    assert len(t) == 10  # t0 + 1.0 itself left out


def test_channel_stats_are_exact_over_part_seconds(archive):
    rng = np.random.default_rng(3)
    t0 = 1_700_000_000.0
    ts = t0 + np.sort(rng.uniform(0, 50, 600))
    vs = rng.normal(5.0, 2.0, 600)
    for t, v in zip(ts, vs, strict=True):
        archive.add_telemetry(float(t), {"x": float(v)})
    assert archive.flush()
    a, b = t0 + 3.37, t0 + 41.72  # both ends inside a second
    sel = vs[(ts >= a) & (ts <= b)]
    st = archive.channel_stats("x", a, b)
    assert st["n"] == len(sel)
    assert st["min"] == pytest.approx(sel.min())
    assert st["max"] == pytest.approx(sel.max())
    assert st["mean"] == pytest.approx(sel.mean())
    short = vs[(ts >= t0 + 10.1) & (ts <= t0 + 10.9)]  # inside one second
    st = archive.channel_stats("x", t0 + 10.1, t0 + 10.9)
    assert st["n"] == len(short) and st["mean"] == pytest.approx(short.mean())
    assert archive.channel_stats("x", t0 + 100, t0 + 200) is None
    assert archive.channel_stats("nope", t0, t0 + 50) is None

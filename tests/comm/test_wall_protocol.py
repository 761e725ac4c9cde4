"""The wall climber's link messages: grids and plan round-trip; bad payloads are
refused and counted by the decoder, never raised."""

from __future__ import annotations

import json

import numpy as np
import pytest

from app.comm import protocol as P
from app.comm import wall_protocol as W


def _wall():
    rng = np.random.default_rng(1)
    blocked = rng.random((9, 17)) < 0.2
    labels = np.where(blocked, -1, rng.integers(0, 4, blocked.shape))
    free = np.argwhere(~blocked)
    return blocked, labels, [tuple(map(int, c)) for c in free]


def test_wall_info_round_trips_grids_and_plan():
    blocked, labels, path = _wall()
    msg = W.WallInfo.build("tank", 0.1, blocked, labels, [2, 0, 1, 3], path, 10.0, 8.0)
    got = P.FrameDecoder().feed(P.encode(msg))[0].message
    np.testing.assert_array_equal(got.blocked_grid(), blocked)
    np.testing.assert_array_equal(got.label_grid(), labels)
    np.testing.assert_array_equal(got.path_cells(), np.array(path))
    assert got.order == [2, 0, 1, 3] and (got.rows, got.cols) == (9, 17)


def test_coverage_figures_and_mask():
    blocked, _, _ = _wall()
    free = ~blocked
    mask = free.copy()
    mask[:3] = False
    msg = W.CoverageProgress.build(mask, int(free.sum()), int(mask.sum()) + 4, 7, 99, 1)
    got = P.FrameDecoder().feed(P.encode(msg))[0].message
    np.testing.assert_array_equal(got.mask(9, 17), mask)
    assert got.coverage_pct == pytest.approx(100 * mask.sum() / free.sum())
    assert got.repetition_pct == pytest.approx(100 * 4 / free.sum())
    with pytest.raises(P.ProtocolError):
        got.mask(10, 17)  # a mask for another wall


@pytest.mark.parametrize("msg_type,payload", [
    (P.MsgType.WALL_INFO, json.dumps({"rows": "9", "cols": 3}).encode()),
    (P.MsgType.WALL_INFO, json.dumps({"rows": 0, "cols": 3, "cell_m": 0.1}).encode()),
    (P.MsgType.COVERAGE, b"\x01\x02"),
    (P.MsgType.COVERAGE, (W.CoverageProgress._S.pack(5, 9, 0, 0, 0, 0))),  # covered > all
    (P.MsgType.PROBE, b"\x02\x00\x00\x00" + b"\x00" * 12),  # 2 readings, bytes for 1
    (P.MsgType.WALL_POSE, b"\x00" * 7),
])
def test_bad_payloads_are_counted_not_raised(msg_type, payload):
    dec = P.FrameDecoder()
    frames = dec.feed(P.FrameEncoder().encode_raw(int(msg_type), payload))
    assert frames == [] and dec.stats.bad_payload == 1


def test_packed_array_of_the_wrong_size_is_refused():
    text = W.pack_array(np.zeros(10, np.uint8), "<u1")
    with pytest.raises(P.ProtocolError):
        W.unpack_array(text, "<u1", 11)
    with pytest.raises(P.ProtocolError):
        W.unpack_array("not base64!", "<u1", 10)


def test_a_compressed_bomb_is_refused_without_inflating_it():
    import base64
    import zlib

    bomb = base64.b64encode(zlib.compress(b"\0" * 50_000_000)).decode()
    with pytest.raises(P.ProtocolError):
        W.unpack_array(bomb, "<u1", 100)
    cov = W.CoverageProgress(10, 0, 0, 0, 0, 0, zlib.compress(b"\0" * 50_000_000))
    with pytest.raises(P.ProtocolError):
        cov.mask(4, 4)

"""Seeded fuzz of both frame decoders: no exception escapes, and a good frame
after the damage still comes out (bench/fuzz.py runs >= 100 000 inputs)."""

import pytest

from app.comm import protocol as P
from bench.fuzz_cases import MUTATIONS, fuzz_link, fuzz_mcu


@pytest.mark.parametrize("seed", [11, 12])
def test_link_decoder_survives_hostile_input(seed):
    r = fuzz_link(3000, seed)
    assert r.raised == 0, r.first_errors
    assert r.sentinel_lost == 0
    assert set(r.by_mutation) == set(MUTATIONS)
    # the damage was seen and counted by reason, not silently passed through
    for reason in ("bad_header", "bad_checksum", "bad_length", "bad_payload", "garbage_bytes"):
        assert r.drops[reason] > 0, reason


@pytest.mark.parametrize("seed", [21, 22])
def test_mcu_decoder_survives_hostile_input(seed):
    r = fuzz_mcu(3000, seed)
    assert r.raised == 0, r.first_errors
    assert r.sentinel_lost == 0
    for reason in ("bad_crc", "bad_length", "unknown_type", "garbage_bytes"):
        assert r.drops[reason] > 0, reason


def test_json_messages_with_wrong_field_types_are_refused_not_passed_on():
    enc = P.FrameEncoder()
    dec = P.FrameDecoder()
    bad = [(P.MsgType.EVENT, b'{"level":[1],"code":"x","text":"t","data":3}'),
           (P.MsgType.COMMAND, b'{"name":5,"args":{}}'),
           (P.MsgType.COMMAND, b'{"name":"drive","args":[1]}'),
           (P.MsgType.COMMAND, b'{"name":"drive","args":{},"auth":"x"}'),
           (P.MsgType.PATROL_STATUS, b'{"state":"driving","points":7}')]
    data = b"".join(enc.encode_raw(int(t), p) for t, p in bad)
    good = P.Event("info", "ok", "fine", {"n": 1})
    out = dec.feed(data + enc.encode(good))
    assert [f.message for f in out] == [good]
    assert dec.stats.bad_payload == len(bad)


def test_a_lying_length_holds_the_next_frame_only_until_its_bytes_arrive():
    enc = P.FrameEncoder()
    from bench.fuzz_cases import _relength

    liar = _relength(enc.encode(P.Pose(1, 2, 3, 0, 0)), 1000)
    dec = P.FrameDecoder()
    ev = enc.encode(P.Event("info", "after", "x", {}))
    assert dec.feed(liar + ev) == []
    assert dec.pending_bytes > 0
    out = dec.feed(b"\x00" * dec.pending_bytes + ev)
    assert [f.message.code for f in out] == ["after", "after"]  # the held one and the new one
    assert dec.stats.bad_checksum >= 1

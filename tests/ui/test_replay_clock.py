"""The replay clock and cursor (Qt-free), driven step by step."""

import pytest

from app.core.replay import MAX_SPEED, MIN_SPEED, ReplayClock, ReplayCursor


def test_clock_starts_paused_and_plays_at_its_speed():
    c = ReplayClock(100.0, 200.0)
    assert c.paused and c.position == 100.0
    assert c.advance(5.0) == 100.0  # paused: no movement
    c.play()
    assert c.advance(5.0) == pytest.approx(105.0)
    c.set_speed(4.0)
    assert c.advance(2.5) == pytest.approx(115.0)


def test_speed_is_clamped_to_half_and_ten():
    c = ReplayClock(0.0, 10.0)
    assert c.set_speed(0.1) == MIN_SPEED == 0.5
    assert c.set_speed(50.0) == MAX_SPEED == 10.0
    with pytest.raises(ValueError):
        c.set_speed(float("nan"))


def test_clock_stops_and_pauses_at_the_end_and_replays_from_the_start():
    c = ReplayClock(0.0, 10.0, speed=10.0)
    c.play()
    assert c.advance(5.0) == 10.0
    assert c.finished and c.paused
    c.play()
    assert c.position == 0.0 and not c.paused


def test_seek_clamps_to_the_range():
    c = ReplayClock(10.0, 20.0)
    assert c.seek(15.0) == 15.0
    assert c.seek(-5.0) == 10.0
    assert c.seek(99.0) == 20.0
    assert c.seek_fraction(0.25) == pytest.approx(12.5)
    with pytest.raises(ValueError):
        c.seek(float("inf"))


def test_bad_range_is_refused():
    with pytest.raises(ValueError):
        ReplayClock(10.0, 5.0)


def test_cursor_hands_out_each_stretch_once():
    c = ReplayClock(0.0, 10.0)
    cur = ReplayCursor(c)
    c.play()
    w1 = cur.advance(1.0)
    w2 = cur.advance(1.0)
    assert (w1.start, w1.end, w1.inclusive) == (0.0, 1.0, True)
    assert (w2.start, w2.end, w2.inclusive) == (1.0, 2.0, False)
    samples = [0.0, 0.5, 1.0, 1.5, 2.0, 2.5]
    due = [t for t in samples if w1.contains(t)] + [t for t in samples if w2.contains(t)]
    assert due == [0.0, 0.5, 1.0, 1.5, 2.0]  # every sample once, none twice
    c.pause()
    assert cur.advance(1.0) is None


def test_cursor_after_seek_starts_at_the_target():
    c = ReplayClock(0.0, 10.0)
    cur = ReplayCursor(c)
    c.play()
    cur.advance(3.0)
    cur.seek(7.0)
    w = cur.advance(1.0)
    assert (w.start, w.end, w.inclusive) == (7.0, 8.0, True)
    cur.seek(2.0)  # backwards too
    w = cur.advance(0.5)
    assert (w.start, w.end) == (2.0, 2.5)


def test_cursor_seek_can_leave_the_target_out():
    c = ReplayClock(0.0, 10.0)
    cur = ReplayCursor(c)
    c.play()
    cur.seek(4.0, inclusive=False)
    w = cur.advance(1.0)
    assert not w.contains(4.0) and w.contains(4.1) and w.contains(5.0)

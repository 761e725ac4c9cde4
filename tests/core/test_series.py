import numpy as np
import pytest

from app.core.series import RingBuffer, SeriesSet


def test_window_before_wrap_returns_views():
    rb = RingBuffer(10)
    for i in range(5):
        rb.append(100.0 + i, i * 2.0)
    t, y = rb.window(2.0)
    assert t.tolist() == [102.0, 103.0, 104.0]
    assert y.tolist() == [4.0, 6.0, 8.0]
    assert np.shares_memory(t, rb._t)  # no copy while contiguous


def test_wraps_and_keeps_last_capacity():
    rb = RingBuffer(4)
    for i in range(10):
        rb.append(float(i), float(i))
    assert len(rb) == 4
    t, y = rb.data()
    assert t.tolist() == [6.0, 7.0, 8.0, 9.0]
    assert rb.latest() == (9.0, 9.0)
    # window across the wrap point copies only what is inside
    t, y = rb.window(1.5)
    assert t.tolist() == [8.0, 9.0]


def test_window_spanning_both_segments():
    rb = RingBuffer(5)
    for i in range(7):  # head at 2: segments [2..5) then [0..2)
        rb.append(float(i), float(-i))
    t, y = rb.window(10.0)
    assert t.tolist() == [2.0, 3.0, 4.0, 5.0, 6.0]
    assert y.tolist() == [-2.0, -3.0, -4.0, -5.0, -6.0]


def test_window_with_explicit_end():
    rb = RingBuffer(100)
    for i in range(50):
        rb.append(float(i), 1.0)
    t, _ = rb.window(5.0, end_t=20.0)
    assert t[0] == 15.0 and t[-1] == 20.0
    t, _ = rb.window(5.0, end_t=1000.0)
    assert t.size == 0


def test_empty_and_bounded_memory():
    rb = RingBuffer(1000)
    t, y = rb.window(60.0)
    assert t.size == 0 and y.size == 0
    assert rb.latest() is None
    before = rb.nbytes
    for i in range(5000):
        rb.append(float(i), 0.0)
    assert rb.nbytes == before == 16 * 1000


def test_time_going_backwards_is_clamped_and_counted():
    rb = RingBuffer(10)
    rb.append(10.0, 1.0)
    rb.append(9.0, 2.0)
    assert rb.out_of_order == 1
    t, y = rb.data()
    assert t.tolist() == [10.0, 10.0] and y.tolist() == [1.0, 2.0]


def test_bad_capacity():
    with pytest.raises(ValueError):
        RingBuffer(0)


def test_series_set_skips_missing_and_nan():
    s = SeriesSet(["a", "b"], 8)
    s.append(1.0, {"a": 1.0, "b": float("nan")})
    s.append(2.0, {"a": 2.0, "b": 5.0})
    assert len(s["a"]) == 2 and len(s["b"]) == 1
    t, y = s.window("b", 10.0)
    assert t.tolist() == [2.0] and y.tolist() == [5.0]
    assert "a" in s and s.channels == ["a", "b"]

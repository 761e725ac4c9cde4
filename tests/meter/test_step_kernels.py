"""Rewritten step helpers against the plain forms they replace, on random inputs: the
same values, bit for bit (a reading depends on every one of them)."""

import numpy as np

from app.core.meter.arc_fit import _window_sums
from app.core.meter.end_marks import lit_run as _lit_run
from app.core.meter.needle import _extent


def _lit_run_cumprod(rows: np.ndarray) -> np.ndarray:
    return np.cumprod(rows.astype(np.int8), axis=0).sum(axis=0)


def test_lit_run_counts_unbroken_lit_rows_from_the_first():
    rng = np.random.default_rng(1)
    for _ in range(200):
        rows = rng.random((int(rng.integers(1, 30)), int(rng.integers(1, 40)))) < rng.random()
        assert np.array_equal(_lit_run(rows), _lit_run_cumprod(rows))
    rows = np.array([[1, 0, 1], [1, 1, 1], [0, 1, 1]], bool)
    assert _lit_run(rows).tolist() == [2, 0, 3]


def _extent_loop(ray, rs, thr, gap_px, late=0.0):
    on = ray > thr
    last = None
    for j in range(len(rs)):
        if on[j]:
            if last is not None and rs[j] - rs[last] > gap_px:
                break
            if last is None and rs[j] - rs[0] > gap_px + late:
                break
            last = j
    return float(rs[last]) if last is not None else 0.0


def test_extent_bridges_gaps_as_the_ray_walk_does():
    rng = np.random.default_rng(2)
    for _ in range(500):
        n = int(rng.integers(2, 96))
        r0 = float(rng.uniform(5, 30))
        rs = np.linspace(r0, r0 + float(rng.uniform(20, 150)), n).astype(np.float32)
        ray = (rng.random(n) * 10).astype(np.float32)
        thr = float(rng.uniform(0, 10))
        gap, late = float(rng.uniform(0.5, 12)), float(rng.choice([0.0, rng.uniform(0, 20)]))
        assert _extent(ray, rs, thr, gap, late) == _extent_loop(ray, rs, thr, gap, late)
    rs = np.arange(10, 20, dtype=np.float32)
    ray = np.array([0, 5, 5, 0, 0, 5, 0, 0, 0, 5], np.float32)
    assert _extent(ray, rs, 1.0, 3.0) == 15.0  # the 3-px step bridged, the 4-px one not
    assert _extent(ray, rs, 1.0, 0.5) == 0.0  # the first lit radius too far out


def _window_sums_two_calls(e, span_cols, starts):
    n = len(e)
    c = np.concatenate([[0.0], np.cumsum(np.tile(e, 3))])
    x = np.arange(3 * n + 1, dtype=float)
    s = starts % n + n
    return np.interp(s + span_cols, x, c) - np.interp(s, x, c)


def test_window_sums_equal_two_interpolations():
    rng = np.random.default_rng(3)
    for _ in range(100):
        n = int(rng.integers(8, 720))
        e = rng.random(n) * (rng.random(n) < 0.4)
        starts = rng.uniform(-2 * n, 2 * n, int(rng.integers(1, 600)))
        span = float(rng.uniform(1, n))
        assert np.array_equal(_window_sums(e, span, starts), _window_sums_two_calls(e, span,
                                                                                    starts))

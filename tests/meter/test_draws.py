"""The rim search's RANSAC samples (:mod:`app.core.meter.draws`) are the numpy calls' own."""

import numpy as np
import pytest

from app.core.meter.draws import _sample_by_calls, ransac_samples


@pytest.mark.parametrize("seed", range(6))
def test_ransac_samples_are_the_generator_calls_and_leave_it_alike(seed):
    pick = np.random.default_rng(100 + seed)
    for _ in range(20):
        n = int(pick.integers(40, 5000))
        iters = int(pick.integers(1, 40))
        a = np.random.default_rng([seed, n])
        if pick.random() < 0.5:
            a.integers(0, 7)  # a 32-bit draw: the generator keeps the other half
        b = np.random.default_rng([seed, n])
        b.bit_generator.state = a.bit_generator.state
        got = ransac_samples(a, n, iters)
        want = [_sample_by_calls(b, n) for _ in range(iters)]
        assert all(np.array_equal(g, w) for g, w in zip(got, want, strict=True))
        assert a.bit_generator.state == b.bit_generator.state
        assert a.integers(0, 1000, 5).tolist() == b.integers(0, 1000, 5).tolist()

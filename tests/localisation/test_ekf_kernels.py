"""The EKF's compiled kernels against the textbook forms of seed 003's eqs. 9–13."""

import math

import numpy as np
import pytest

from app.core.localisation import _ekf_kernels as kernels


def _spd(rng, n):
    a = rng.normal(size=(n, n))
    return a @ a.T + 0.1 * np.eye(n)


@pytest.mark.parametrize("n,m", [(6, 1), (7, 3), (11, 1), (11, 2)])
def test_the_update_is_the_joseph_form_of_eqs_10_to_13(n, m):
    rng = np.random.default_rng(n * 10 + m)
    for _ in range(20):
        p, x = _spd(rng, n), rng.normal(size=n)
        h, r, z = rng.normal(size=(m, n)), _spd(rng, m), rng.normal(size=m)
        k = p @ h.T @ np.linalg.inv(h @ p @ h.T + r)  # eq. 10
        want_x = x + k @ (z - h @ x)  # eq. 11
        want_x[2] = (want_x[2] + math.pi) % (2 * math.pi) - math.pi
        i_kh = np.eye(n) - k @ h
        want_p = i_kh @ p @ i_kh.T + k @ r @ k.T  # eq. 13, Joseph form
        got_x, got_p = x.copy(), p.copy()
        innov = kernels.update(got_x, got_p, z, h, r, 2)
        assert np.allclose(innov, z - h @ x, atol=1e-12)
        assert np.allclose(got_x, want_x, atol=1e-10)
        assert np.allclose(got_p, want_p, atol=1e-10)
        assert np.allclose(got_p, got_p.T, atol=1e-12)


def test_the_propagation_is_eq_9():
    rng = np.random.default_rng(3)
    p, a, q = _spd(rng, 11), rng.normal(size=(11, 11)), _spd(rng, 11)
    a[a < 0] = 0.0  # zeros, as the Jacobian's, are skipped
    assert np.allclose(kernels.propagate(p, a, q), a @ p @ a.T + q, atol=1e-10)

"""Compiled kernels of the odometry EKF (:mod:`.ekf`): the covariance
propagation of eq. 9 and the linear update of eqs. 10–13, in place.

The filter's matrices are 6 × 6 to 12 × 12 and its measurements one to three
rows: numpy's per-call overhead, not the arithmetic, was the cost (the wall
climber's inspection spends about half its time in these updates, ≈ 60 µs
each). Plain loops, compiled with ``njit(cache=True)`` so that later
processes load the machine code.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def _add_abt(out, a, b, sign):
    """out[i, j] += sign · Σ_k a[i, k] b[j, k] (A Bᵀ; pass ``x.T`` for B to add A X)."""
    for i in range(out.shape[0]):
        for j in range(out.shape[1]):
            acc = 0.0
            for k in range(a.shape[1]):
                acc += a[i, k] * b[j, k]
            out[i, j] += sign * acc


@njit(cache=True)
def _add_abt_termwise(out, a, b):
    """out[i, j] += a[i, k] b[j, k] for each k in turn (A Bᵀ added term by term, the
    zeros of A skipped: a Jacobian's many)."""
    for i in range(out.shape[0]):
        for k in range(a.shape[1]):
            aik = a[i, k]
            if aik != 0.0:
                for j in range(out.shape[1]):
                    out[i, j] += aik * b[j, k]


@njit(cache=True)
def propagate(p, a, q):
    """P⁻ = A P Aᵀ + Q (eq. 9); returns a new matrix."""
    n = p.shape[0]
    ap = np.zeros((n, n))
    _add_abt_termwise(ap, a, p.T)
    out = q.copy()
    _add_abt(out, ap, a, 1.0)
    return out


@njit(cache=True)
def _inverse(s):
    """The inverse of a small symmetric positive-definite matrix (Gauss–Jordan
    with partial pivoting; S = H P Hᵀ + R of at most a few rows)."""
    m = s.shape[0]
    w = s.copy()
    inv = np.eye(m)
    for c in range(m):
        piv = c
        for r in range(c + 1, m):
            if abs(w[r, c]) > abs(w[piv, c]):
                piv = r
        if piv != c:
            for j in range(m):
                w[c, j], w[piv, j] = w[piv, j], w[c, j]
                inv[c, j], inv[piv, j] = inv[piv, j], inv[c, j]
        d = w[c, c]
        for j in range(m):
            w[c, j] /= d
            inv[c, j] /= d
        for r in range(m):
            if r != c:
                f = w[r, c]
                if f != 0.0:
                    for j in range(m):
                        w[r, j] -= f * w[c, j]
                        inv[r, j] -= f * inv[c, j]
    return inv


@njit(cache=True)
def update(x, p, z, h, r, angle):
    """The linear update Z = H X + V, V ~ N(0, R), applied to ``x`` and ``p`` in
    place; state ``angle`` is wrapped to [−π, π) after it. Returns the
    innovation (a new array).

    K = P Hᵀ S⁻¹, S = H P Hᵀ + R (eq. 10); X = X + K (Z − H X) (eq. 11); eq. 13
    in Joseph form, (I − KH) P (I − KH)ᵀ + K R Kᵀ, multiplied out: with
    A = P − K (HP), (I − KH) P (I − KH)ᵀ = A − (A Hᵀ) Kᵀ (P symmetric).
    """
    n = x.shape[0]
    m = z.shape[0]
    innov = z.copy()
    for i in range(m):
        for j in range(n):
            innov[i] -= h[i, j] * x[j]
    ph = np.zeros((n, m))  # P Hᵀ
    _add_abt_termwise(ph, p, h)
    s = r.copy()  # H P Hᵀ + R
    _add_abt(s, h, ph.T, 1.0)
    k_gain = np.zeros((n, m))  # eq. 10
    if m == 1:
        for i in range(n):
            k_gain[i, 0] = ph[i, 0] / s[0, 0]
    else:
        _add_abt(k_gain, ph, _inverse(s).T, 1.0)
    for i in range(n):  # eq. 11
        acc = 0.0
        for j in range(m):
            acc += k_gain[i, j] * innov[j]
        x[i] += acc
    x[angle] = (x[angle] + math.pi) % (2 * math.pi) - math.pi
    a = p.copy()  # A = P − K (HP) = P − K (P Hᵀ)ᵀ
    _add_abt(a, k_gain, ph, -1.0)
    ah = np.zeros((n, m))  # A Hᵀ
    _add_abt_termwise(ah, a, h)
    kr = np.zeros((n, m))  # K R
    _add_abt(kr, k_gain, r.T, 1.0)
    p[:, :] = a  # P = A − (A Hᵀ) Kᵀ + K R Kᵀ
    _add_abt(p, kr - ah, k_gain, 1.0)
    return innov


@njit(cache=True)
def positive_definite(p):
    """True when the symmetric ``p`` is positive definite: its Cholesky
    factorisation P = L Lᵀ runs with every pivot positive (on a copy)."""
    n = p.shape[0]
    lo = np.zeros((n, n))
    for j in range(n):
        d = p[j, j]
        for k in range(j):
            d -= lo[j, k] * lo[j, k]
        if not d > 0.0:  # also refuses NaN
            return False
        lo[j, j] = math.sqrt(d)
        for i in range(j + 1, n):
            acc = p[i, j]
            for k in range(j):
                acc -= lo[i, k] * lo[j, k]
            lo[i, j] = acc / lo[j, j]
    return True


@njit(cache=True)
def symmetrise_positive_definite(p):
    """``p`` made symmetric in place, each pair of off-diagonal entries set to their
    mean (the same numbers as ``0.5 * (p + p.T)``), then :func:`positive_definite`
    of it. One compiled call where the wall EKF, after every step and update, paid
    numpy's overhead for the mean and a second call for the test."""
    n = p.shape[0]
    for i in range(n):
        for j in range(i + 1, n):
            m = 0.5 * (p[i, j] + p[j, i])
            p[i, j] = m
            p[j, i] = m
    return positive_definite(p)

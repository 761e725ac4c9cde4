"""Entries of the inverse of a sparse symmetric positive definite matrix on
the pattern of its factor (the "selected" or "sparse" inverse), and the
trace tr(A⁻¹ B) of a product with a sparse B inside that pattern.

Takahashi, Fagan & Chen's recurrence ("Formation of a sparse bus impedance
matrix and its application to short circuit study", PICA 1973; in the form
of Erisman & Tinney, "On computing certain elements of the inverse of a
sparse matrix", CACM 18(3), 1975): with the factorisation P A Pᵀ = L D Lᵀ
(L unit lower triangular) and Z = (P A Pᵀ)⁻¹,

    Z = D⁻¹ L⁻¹ + (I − Lᵀ) Z,                                            (1)

so for i ≤ j, with S_i the rows below the diagonal in L's column i,

    Z_ij = δ_ij / d_i − Σ_{k ∈ S_i} L_ki Z_kj.                             (2)

Taken column by column from the last, (2) needs Z only at pairs of S_i,
which lie in L's pattern (S_i is a clique of the filled graph), so Z on
that pattern costs about as much as the factorisation, where the inverse's
columns solved one by one cost n solves. The variance components'
redundancies (variance_components.py) need only tr(N⁻¹ N_g), N_g inside
N's pattern.

The factor comes from SuperLU (scipy.sparse.linalg.splu) on a symmetric
order with diagonal pivots (pose_graph.normal_factor): then U = D Lᵀ and the
row and column permutations are one.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from scipy.sparse import coo_matrix


class SelectedInverse:
    """Z = A⁻¹ on the pattern of A's factor (``lu``: a SuperLU object of A
    factored with a symmetric permutation and diagonal pivots)."""

    def __init__(self, lu) -> None:
        if not np.array_equal(lu.perm_r, lu.perm_c):
            raise ValueError("the factor's row and column orders differ: not a symmetric "
                             "factorisation (pose_graph.normal_factor makes one)")
        low = lu.L.tocsc()
        low.sort_indices()
        self.lu = lu
        self.n = low.shape[0]
        self.perm = np.asarray(lu.perm_c)  # A[a, b] is (P A Pᵀ)[perm[a], perm[b]]
        self.indptr, self.indices = low.indptr, low.indices
        self.z, self.zd = _takahashi(self.n, low.indptr, low.indices, low.data,
                                     np.asarray(lu.U.diagonal(), float))

    def trace_product(self, b) -> float:
        """tr(A⁻¹ B) for a symmetric sparse B whose nonzeros lie in A's pattern."""
        b = coo_matrix(b)
        pr, pc = self.perm[b.row], self.perm[b.col]
        hi, lo = np.maximum(pr, pc), np.minimum(pr, pc)
        order = np.argsort(lo, kind="stable")
        vals = b.data[order].astype(float)
        tot, missing = _trace(self.n, self.indptr, self.indices, self.z, self.zd, hi[order],
                              lo[order], vals)
        # an entry of B where A's own entry cancelled to zero lies outside the factor's
        # pattern: that element of A⁻¹ solved for
        for e in np.flatnonzero(missing):
            unit = np.zeros(self.n)
            unit[b.col[order[e]]] = 1.0
            tot += vals[e] * float(self.lu.solve(unit)[b.row[order[e]]])
        return tot


@njit(cache=True)
def _takahashi(n, indptr, indices, lval, d):
    """Z below the diagonal on L's pattern (aligned with ``lval``) and Z's
    diagonal, by (2) from the last column to the first."""
    z = np.zeros(lval.shape[0])
    zd = np.zeros(n)
    w = np.zeros(n)  # a column of Z scattered
    acc = np.zeros(n)  # Z_ij being summed, j ∈ S_i
    for i in range(n - 1, -1, -1):
        a, b = indptr[i], indptr[i + 1]
        for p in range(a, b):
            acc[indices[p]] = 0.0
        for p in range(a, b):
            k = indices[p]
            if k <= i:
                continue
            lki = lval[p]
            acc[k] -= lki * zd[k]  # the term of (2) with k = j
            for r in range(indptr[k], indptr[k + 1]):
                if indices[r] > k:
                    w[indices[r]] = z[r]
            for p2 in range(a, b):  # the pairs k < j of S_i, each once, both ways
                j = indices[p2]
                if j > k:
                    zkj = w[j]
                    acc[j] -= lki * zkj
                    acc[k] -= lval[p2] * zkj
            for r in range(indptr[k], indptr[k + 1]):
                w[indices[r]] = 0.0
        s = 0.0
        for p in range(a, b):
            k = indices[p]
            if k > i:
                z[p] = acc[k]
                s += lval[p] * acc[k]
        zd[i] = 1.0 / d[i] - s  # (2) with i = j
    return z, zd


@njit(cache=True)
def _trace(n, indptr, indices, z, zd, hi, lo, vals):
    """Σ B_ab Z_ab over B's entries (hi ≥ lo: Z's row and column in the
    permuted order, sorted by column) within L's pattern, and which entries
    lie outside it (left out of the sum)."""
    w = np.zeros(n)
    seen = np.zeros(n, np.bool_)
    missing = np.zeros(hi.shape[0], np.bool_)
    tot = 0.0
    col = -1
    for e in range(hi.shape[0]):
        c, r = lo[e], hi[e]
        if c != col:
            if col >= 0:
                for q in range(indptr[col], indptr[col + 1]):
                    w[indices[q]] = 0.0
                    seen[indices[q]] = False
            col = c
            for q in range(indptr[c], indptr[c + 1]):
                if indices[q] > c:
                    w[indices[q]] = z[q]
                    seen[indices[q]] = True
        if r == c:
            tot += vals[e] * zd[c]
        elif seen[r]:
            tot += vals[e] * w[r]
        else:
            missing[e] = True
    return tot, missing

"""The inverse's entries on the factor's pattern and tr(A⁻¹ B) (selected_inverse.py)."""

import numpy as np
from scipy.sparse import csc_matrix, diags, lil_matrix

from app.core.localisation.pose_graph import normal_factor
from app.core.localisation.selected_inverse import SelectedInverse


def _pose_graph_like(n: int, loops: int, seed: int):
    """A sparse SPD matrix shaped as a pose graph's normal matrix: a chain of
    3 × 3 blocks with some long-range couplings (loop closures)."""
    rng = np.random.default_rng(seed)
    rows, cols, vals = [], [], []
    pairs = [(i, i + 1) for i in range(n - 1)]
    pairs += [tuple(sorted(rng.choice(n, 2, replace=False))) for _ in range(loops)]
    for a, b in pairs:
        j = rng.normal(size=(3, 6))  # one edge's whitened Jacobian on nodes a, b
        idx = np.r_[3 * a:3 * a + 3, 3 * b:3 * b + 3]
        blk = j.T @ j
        for r in range(6):
            for c in range(6):
                rows.append(idx[r])
                cols.append(idx[c])
                vals.append(blk[r, c])
    m = csc_matrix((vals, (rows, cols)), shape=(3 * n, 3 * n))
    return m + diags(np.full(3 * n, 1e-3)), pairs


def test_entries_on_the_pattern_and_traces_equal_the_dense_inverse():
    a, pairs = _pose_graph_like(60, 25, seed=1)
    inv = SelectedInverse(normal_factor(a - diags(np.full(a.shape[0], 1e-9))))
    dense = np.linalg.inv(a.toarray())
    # the diagonal, and each edge's blocks, where the redundancies need them
    assert np.allclose(inv.zd[inv.perm], np.diag(dense), rtol=1e-9, atol=0)
    for b in (a, diags(np.arange(1.0, a.shape[0] + 1))):
        assert np.isclose(inv.trace_product(b), np.trace(dense @ b.toarray()), rtol=1e-9)
    # one class of edges: the loop edges' share of the normal matrix
    rng = np.random.default_rng(4)
    j = lil_matrix((30, a.shape[0]))
    for k, (p, q) in enumerate(pairs[-10:]):
        for r in range(3):
            j[3 * k + r, 3 * p:3 * p + 3] = rng.normal(size=3)
            j[3 * k + r, 3 * q:3 * q + 3] = rng.normal(size=3)
    ng = (j.T @ j).tocsc()
    assert np.isclose(inv.trace_product(ng), np.trace(dense @ ng.toarray()), rtol=1e-9)


def test_an_entry_outside_the_factors_pattern_is_solved_for():
    """A chain alone fills nothing: an entry coupling its two ends lies outside
    the factor's pattern, and its element of the inverse is solved for."""
    a, _ = _pose_graph_like(30, 0, seed=2)
    inv = SelectedInverse(normal_factor(a - diags(np.full(a.shape[0], 1e-9))))
    n = a.shape[0]
    b = csc_matrix(([2.0, 2.0, 1.0], ([0, n - 1, 5], [n - 1, 0, 5])), shape=(n, n))
    dense = np.linalg.inv(a.toarray())
    assert np.isclose(inv.trace_product(b), np.trace(dense @ b.toarray()), rtol=1e-9)

"""Pose graph: nodes (x, y, θ), relative-pose edges, a robust sparse solve.

An edge k from node i to node j holds the measured pose z_k of j seen from i
and the square root S_k of its information (SᵀS = Σ⁻¹). The solve minimises
Σ_k ρ(‖r_k‖²) with r_k = S_k ((x_i ⊖ x_j) − z_k) by Gauss-Newton on sparse
normal equations (the g2o / "graph SLAM" formulation: Grisetti et al. 2010,
"A tutorial on graph-based SLAM", eqs. 13–24, here in 2-D with a Cauchy
loss by iteratively re-weighted least squares).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import csr_matrix, identity
from scipy.sparse.linalg import splu, spsolve

from .se2 import relative, wrap


@dataclass
class Edge:
    i: int
    j: int
    z: np.ndarray  # relative pose of node j seen from node i
    sqrt_info: np.ndarray  # 3×3, whitening
    loop: bool = False


def _whitened(e: Edge, x: np.ndarray) -> float:
    """‖S (x_i ⊖ x_j − z)‖ of an edge at poses x."""
    err = relative(x[e.i], x[e.j]) - e.z
    err[2] = float(wrap(err[2]))
    return float(np.linalg.norm(e.sqrt_info @ err))


def _sqrt_info(cov: np.ndarray) -> np.ndarray:
    """Upper-triangular S with SᵀS = cov⁻¹ (whitening of a residual)."""
    info = np.linalg.inv(cov)
    info = (info + info.T) / 2
    return np.linalg.cholesky(info).T


def normal_factor(h):
    """The sparse LU factor of a pose graph's normal matrix h (+ 1e-9 I):
    symmetric positive definite, so factored with diagonal pivots on a
    symmetric fill-reducing order (minimum degree on h + hᵀ, SuperLU's
    symmetric mode), which keeps the factor's fill a half to a third of
    the default column order's on the logs' graphs."""
    return splu(h.tocsc() + identity(h.shape[0], format="csc") * 1e-9,
                permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                options={"SymmetricMode": True})


def solve_pose_graph(x0: np.ndarray, edges: list[Edge], cauchy_c: float = 3.0,
                     iterations: int = 15, tol: float = 1e-6) -> np.ndarray:
    """The solved poses (``gauss_newton`` until it converges or has run
    ``iterations`` steps)."""
    return gauss_newton(x0, edges, iterations, cauchy_c, tol)[0]


def gauss_newton(x0: np.ndarray, edges: list[Edge], iterations: int, cauchy_c: float = 3.0,
                 tol: float = 1e-6) -> tuple[np.ndarray, bool]:
    """At most ``iterations`` Gauss-Newton steps of the pose graph from x0, on
    scipy.sparse normal equations; (poses, converged). A solve can be spread
    over several calls, each starting where the last one stopped.

    Minimises Σ_k ρ(‖r_k‖²), r_k = S_k ((x_i ⊖ x_j) − z_k) (angle wrapped), with
    the Cauchy loss ρ(s) = c² log(1 + s/c²) applied by iteratively re-weighted
    least squares (edge weight 1 / (1 + ‖r_k‖²/c²)), so that a wrong loop
    closure that slipped through the test pulls little. Each step solves
    (Jᵀ W J) δ = −Jᵀ W r with node 0 held fixed (its columns dropped), by
    sparse LU (scipy.sparse.linalg.spsolve)."""
    n = len(x0)
    if n < 2 or not edges:
        return np.array(x0, float), True
    lin = Linearisation(edges, n)
    x = np.array(x0, float)
    for _ in range(iterations):
        jac, rw, _ = lin.at(x, cauchy_c)
        h = (jac.T @ jac).tocsc()
        g = jac.T @ rw
        delta = spsolve(h + identity(h.shape[0], format="csc") * 1e-9, -g)
        x[1:] += delta.reshape(n - 1, 3)
        x[:, 2] = wrap(x[:, 2])
        if np.max(np.abs(delta)) < tol:
            return x, True
    return x, False


class Linearisation:
    """The whitened, re-weighted residuals of a pose graph's edges and their
    sparse Jacobian (node 0's columns dropped) at poses x: what one
    Gauss-Newton step of ``gauss_newton`` solves with."""

    def __init__(self, edges: list[Edge], n: int) -> None:
        self.n = n
        self.ii = np.array([e.i for e in edges])
        self.jj = np.array([e.j for e in edges])
        self.z = np.array([e.z for e in edges])
        self.S = np.array([e.sqrt_info for e in edges])
        ne = len(edges)
        self.rows = np.repeat((3 * np.arange(ne)[:, None] + np.arange(3))[:, :, None], 6,
                              axis=2)
        cols = np.concatenate((3 * self.ii[:, None] + np.arange(3),
                               3 * self.jj[:, None] + np.arange(3)), axis=1)
        self.cols = np.repeat(cols[:, None, :], 3, axis=1)

    def at(self, x: np.ndarray, cauchy_c: float) -> tuple[csr_matrix, np.ndarray, np.ndarray]:
        """(J, r) whitened and weighted by the Cauchy loss's IRLS weights, both
        flattened edge by edge (3 rows each), and the weights w (one per edge)."""
        ii, jj, S = self.ii, self.jj, self.S
        xi, xj = x[ii], x[jj]
        c, s = np.cos(xi[:, 2]), np.sin(xi[:, 2])
        dx, dy = xj[:, 0] - xi[:, 0], xj[:, 1] - xi[:, 1]
        err = np.column_stack((c * dx + s * dy, -s * dx + c * dy, xj[:, 2] - xi[:, 2])) - self.z
        err[:, 2] = wrap(err[:, 2])
        r = np.einsum("kij,kj->ki", S, err)  # whitened residuals (E, 3)
        w = 1.0 / (1.0 + np.sum(r * r, axis=1) / cauchy_c ** 2)
        jp = np.zeros((len(ii), 3, 6))  # ∂(x_i ⊖ x_j) / ∂(x_i, y_i, θ_i, x_j, y_j, θ_j)
        jp[:, 0, 0], jp[:, 0, 1], jp[:, 0, 2] = -c, -s, -s * dx + c * dy
        jp[:, 1, 0], jp[:, 1, 1], jp[:, 1, 2] = s, -c, -c * dx - s * dy
        jp[:, 2, 2] = -1.0
        jp[:, 0, 3], jp[:, 0, 4] = c, s
        jp[:, 1, 3], jp[:, 1, 4] = -s, c
        jp[:, 2, 5] = 1.0
        blocks = np.einsum("kij,kjl->kil", S, jp) * np.sqrt(w)[:, None, None]
        jac = csr_matrix((blocks.ravel(), (self.rows.ravel(), self.cols.ravel())),
                         shape=(3 * len(ii), 3 * self.n))
        return jac[:, 3:], (r * np.sqrt(w)[:, None]).ravel(), w

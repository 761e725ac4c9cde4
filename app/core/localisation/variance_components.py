"""Variance component estimation for the pose graph's edge classes.

The graph's edges come in classes whose stated covariances were set by
different rules: the fused odometry-and-match steps between consecutive
scans, the online loop closures, the final pass's matches and the
long-range ties (mapping.py). Each rule's scale may be off — a floor, a
fixed factor on a Hessian covariance — and when one class claims too much
or too little against the others, the solve bends the trajectory the
wrong way: too loose steps let the loop edges' errors into each step.

Helmert's variance component estimation (in Förstner's form, 1979: "Ein
Verfahren zur Schätzung von Varianz- und Kovarianzkomponenten", AVN 86;
Koch, "Parameter Estimation and Hypothesis Testing in Linear Models", §3.6)
estimates one factor per class from the residuals of the solve itself:

    σ̂²_g = v_gᵀ P_g v_g / r_g,   r_g = n_g − tr(N⁻¹ N_g)                   (VCE-1)

with v_g the class's residuals, P_g its weights, n_g its observations,
N = Σ_g N_g the normal matrix and N_g = J_gᵀ P_g J_g the class's share of it;
r_g is the class's redundancy (the part of its observations the others
check). Each class's covariance is multiplied by σ̂²_g and the graph solved
again, until the factors settle (VCE-2: iterated, as the estimator is
exact only at the solution). No reference is used: the edges' own
disagreement is the measurement. Robust weights (the solve's Cauchy loss)
enter P_g, so an edge the loss has set aside does not inflate its class.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .pose_graph import Edge, Linearisation, normal_factor, solve_pose_graph
from .selected_inverse import SelectedInverse


@dataclass(frozen=True)
class VarianceComponentConfig:
    iterations: int = 4  # re-estimations (each one solve); stops earlier when settled
    tol: float = 0.05  # ...settled: every factor changed by less than this share
    min_redundancy: float = 3.0  # a class checked less than this keeps its factor
    # factors are clipped to [1 / limit, limit] of the stated covariances
    limit: float = 25.0
    cauchy_c: float = 3.0  # as the solve's (pose_graph.gauss_newton)
    # the factors are relative to the most numerous class other than class 0
    # (the loop edges'; kept at 1): the scale against which the loss weighs
    # the whitened residuals stays as stated. False: absolute factors
    relative: bool = True


def class_factors(x: np.ndarray, edges: list[Edge], classes: np.ndarray,
                  cauchy_c: float = 3.0, min_redundancy: float = 3.0
                  ) -> tuple[np.ndarray, np.ndarray]:
    """(σ̂²_g, r_g) per class (VCE-1) at solved poses x; ``classes``: one
    integer per edge, 0..G−1. A class with redundancy below
    ``min_redundancy`` gets the factor 1."""
    n = len(x)
    lin = Linearisation(edges, n)
    jac, rw, _ = lin.at(x, cauchy_c)
    cls3 = np.repeat(np.asarray(classes), 3)
    # tr(N⁻¹ N_g) needs N⁻¹ only where N_g has entries, inside N's pattern: the selected
    # inverse on the factor's pattern (selected_inverse.py), not n solves
    inv = SelectedInverse(normal_factor((jac.T @ jac).tocsc()))
    g_count = int(np.max(classes)) + 1
    s2, red = np.ones(g_count), np.zeros(g_count)
    for g in range(g_count):
        rows = np.flatnonzero(cls3 == g)
        if rows.size == 0:
            continue
        jg = jac[rows]
        red[g] = rows.size - inv.trace_product(jg.T @ jg)  # r_g = n_g − tr(N⁻¹ N_g)
        if red[g] >= min_redundancy:
            s2[g] = float(rw[rows] @ rw[rows]) / red[g]
    return s2, red


def reweighted_solve(x0: np.ndarray, edges: list[Edge], classes,
                     cfg: VarianceComponentConfig = VarianceComponentConfig()
                     ) -> tuple[np.ndarray, list[Edge], np.ndarray]:
    """Solve, estimate each class's factor, rescale its edges' covariance by
    it and solve again (VCE-2); (poses, rescaled edges, factors)."""
    classes = np.asarray(classes, int)
    factors = np.ones(int(classes.max()) + 1)
    counts = np.bincount(classes, minlength=len(factors))
    counts[0] = 0
    ref = int(np.argmax(counts)) if counts.max() > 0 else -1
    x = solve_pose_graph(np.array(x0, float), edges, cfg.cauchy_c)
    cur = list(edges)
    for _ in range(cfg.iterations):
        s2, _ = class_factors(x, cur, classes, cfg.cauchy_c, cfg.min_redundancy)
        new = factors * s2
        if cfg.relative and ref >= 0:
            new = new / new[ref]
        new = np.clip(new, 1.0 / cfg.limit, cfg.limit)
        done = np.all(np.abs(new / factors - 1.0) < cfg.tol)
        factors = new
        cur = [Edge(e.i, e.j, e.z, e.sqrt_info / np.sqrt(factors[c]), e.loop)
               for e, c in zip(edges, classes, strict=True)]
        x = solve_pose_graph(x, cur, cfg.cauchy_c)
        if done:
            break
    return x, cur, factors


def edge_classes(edges: list[Edge]) -> np.ndarray:
    """The mapper's two edge classes: consecutive-scan steps (0) and loop
    edges (1: online closures, the final pass's and the long-range ties)."""
    return np.array([1 if e.loop else 0 for e in edges], int)

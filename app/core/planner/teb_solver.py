"""Levenberg–Marquardt on banded normal equations, for the timed elastic band.

Minimise F(z) = ½ ‖r(z)‖² over z ∈ Rⁿ, where every residual touches a few
neighbouring unknowns, so that, with the unknowns in a suitable order, JᵀJ is
a band matrix of half-bandwidth u ≪ n. Each iteration, in the trust-region
form of Moré (1978, "The Levenberg–Marquardt algorithm: implementation and
theory"):

1. the step h solves the damped normal equations of Levenberg (1944) and
   Marquardt (1963),

       (JᵀJ + μ I) h = −g,        g = Jᵀr,                        (LM)

   with μ ≥ 0 chosen so that ‖h‖ ≈ Δ, the trust radius (μ = 0, the
   Gauss–Newton step, when that lies inside); μ by Newton's method on
   ‖h(μ)‖ − Δ (Moré eq. 5.5). JᵀJ + μI is symmetric positive definite, stored
   in LAPACK's upper band form and factored by a banded Cholesky
   (``scipy.linalg.cholesky_banded``) in O(n u²) — a few per iteration;
2. the gain ratio compares the actual with the predicted decrease,

       ϱ = (F(z) − F(z + h)) / (L(0) − L(h)),
       L(0) − L(h) = ½ hᵀ(μ h − g);                                (gain)

3. the radius: Δ ← ‖h‖/4 if ϱ < ¼, Δ ← 2Δ if ϱ > ¾ and the step reached
   the boundary; the step is kept whenever F decreased. Δ0 = ‖z0‖ and no
   scaling of the unknowns, as SciPy's ``least_squares`` (trf) defaults.

It stops on a small gradient ‖g‖∞ ≤ gtol, a small step
‖h‖ ≤ xtol (‖z‖ + xtol), a small relative decrease ≤ ftol, or when
``max_nfev`` residual evaluations have been spent (the first one included,
as in ``scipy.optimize.least_squares``).

The Jacobian comes as the values of a fixed sparsity pattern (rows, cols);
its normal matrix is assembled straight into band form with one
``np.bincount`` over the precomputed pairs of entries that share a row.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.linalg import LinAlgError, cho_solve_banded, cholesky_banded

__all__ = ["BandedPattern", "LmResult", "levenberg_marquardt"]


class BandedPattern:
    """A Jacobian's sparsity pattern, with the unknowns re-ordered by
    ``order`` (``order[j]`` = position of unknown j) so that JᵀJ is banded.

    Precomputes, for every pair of entries (a, b) in one row, where the
    product J_a J_b lands in the upper band storage ``ab[u + i − j, j]``
    (i ≤ j the positions of their columns)."""

    def __init__(self, rows: np.ndarray, cols: np.ndarray, n_rows: int, n_vars: int,
                 order: np.ndarray | None = None):
        self.rows = np.asarray(rows, dtype=np.int64)
        self.n_rows, self.n_vars = int(n_rows), int(n_vars)
        self.order = (np.arange(n_vars) if order is None
                      else np.asarray(order, dtype=np.int64))
        self.pcols = self.order[np.asarray(cols, dtype=np.int64)]
        by_row = np.argsort(self.rows, kind="stable")
        starts = np.searchsorted(self.rows[by_row], np.arange(self.n_rows + 1))
        ia, ib = [], []
        for k in range(self.n_rows):
            e = by_row[starts[k]:starts[k + 1]]
            a, b = np.triu_indices(len(e))
            ia.append(e[a])
            ib.append(e[b])
        self.ia = np.concatenate(ia)
        self.ib = np.concatenate(ib)
        i = np.minimum(self.pcols[self.ia], self.pcols[self.ib])
        j = np.maximum(self.pcols[self.ia], self.pcols[self.ib])
        self.u = int(np.max(j - i)) if len(i) else 0
        self.slot = (self.u + i - j) * self.n_vars + j

    def normal(self, vals: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """JᵀJ in upper band form ((u + 1) × n) and g = Jᵀr, both in the
        banded order of the unknowns."""
        n = self.n_vars
        ab = np.bincount(self.slot, weights=vals[self.ia] * vals[self.ib],
                         minlength=(self.u + 1) * n).reshape(self.u + 1, n)
        g = np.bincount(self.pcols, weights=vals * r[self.rows], minlength=n)
        return ab, g


@dataclass
class LmResult:
    x: np.ndarray
    cost: float  # F = ½‖r‖², as least_squares reports it
    nfev: int
    njev: int
    status: str


def _damped_step(ab, u, g, mu):
    """(LM) for one μ: the step h and, through the banded Cholesky factor
    U (A + μI = UᵀU), ‖U⁻ᵀh‖² for Moré's Newton update of μ."""
    damped = ab.copy()
    damped[u] += mu
    U = cholesky_banded(damped, lower=False, check_finite=False)
    h = cho_solve_banded((U, False), -g, check_finite=False)
    w = cho_solve_banded((U, False), h, check_finite=False)
    return h, float(h @ w)


def _trust_step(ab, u, g, delta, mu):
    """Moré (1978) §3–5: the μ ≥ 0 whose step has ‖h(μ)‖ ≈ Δ (within 10 %),
    by Newton's method on φ(μ) = ‖h(μ)‖ − Δ safeguarded in [l, u]:

        μ⁺ = μ + (‖h‖ − Δ)/Δ · ‖h‖² / ‖U⁻ᵀh‖²                      (Moré 5.5)

    The Gauss–Newton step (μ = 0) is taken when it lies inside the region."""
    tiny = 1e-12 * max(float(np.max(ab[u])), 1e-12)
    try:
        h, _ = _damped_step(ab, u, g, tiny)
        if np.linalg.norm(h) <= delta:
            return h, 0.0
    except LinAlgError:
        pass
    lo, hi = 0.0, float(np.linalg.norm(g)) / delta
    if not lo < mu < hi:
        mu = max(1e-3 * hi, math.sqrt(lo * hi))
    for _ in range(10):
        h, q = _damped_step(ab, u, g, mu + tiny)
        nh = float(np.linalg.norm(h))
        phi = nh - delta
        if abs(phi) <= 0.1 * delta:
            break
        if phi < 0:
            hi = mu
        else:
            lo = mu
        mu = mu + phi / delta * nh * nh / max(q, 1e-300)
        if not lo < mu < hi:
            mu = max(1e-3 * hi, math.sqrt(lo * hi))
    return h, mu


def levenberg_marquardt(fun: Callable[[np.ndarray], np.ndarray],
                        jac: Callable[[np.ndarray, np.ndarray], np.ndarray],
                        x0: np.ndarray, pattern: BandedPattern, *, max_nfev: int = 12,
                        gtol: float = 1e-8, xtol: float = 1e-8,
                        ftol: float = 1e-8) -> LmResult:
    """Minimise ½‖fun(x)‖². ``jac(x, r)`` returns the Jacobian's values on
    ``pattern`` at x, where r = fun(x) is passed in to be reused."""
    order, u = pattern.order, pattern.u
    x = np.asarray(x0, dtype=float).copy()
    r = fun(x)
    F = 0.5 * float(r @ r)
    nfev, njev = 1, 0
    delta = float(np.linalg.norm(x)) or 1.0  # Δ0 = ‖x0‖, as least_squares
    mu = 0.0
    status = "max_nfev"
    need_jac = True
    while nfev < max_nfev:
        if need_jac:
            vals = jac(x, r)
            njev += 1
            ab, g = pattern.normal(vals, r)
            if np.max(np.abs(g)) <= gtol:
                status = "gtol"
                break
            need_jac = False
        hp, mu = _trust_step(ab, u, g, delta, mu)  # (LM) inside the region
        nh = float(np.linalg.norm(hp))
        if nh <= xtol * (np.linalg.norm(x) + xtol):
            status = "xtol"
            break
        x_new = x + hp[order]
        r_new = fun(x_new)
        nfev += 1
        F_new = 0.5 * float(r_new @ r_new)
        predicted = 0.5 * float(hp @ (mu * hp - g))  # (gain)
        rho = (F - F_new) / predicted if predicted > 0 else -1.0
        # Moré's radius update (the rule least_squares' trf also uses).
        if rho < 0.25:
            delta = 0.25 * nh
        elif rho > 0.75 and nh >= 0.95 * delta:
            delta = 2.0 * delta
        if F_new < F:
            small = F - F_new <= ftol * F
            x, r, F = x_new, r_new, F_new
            need_jac = True
            if small:
                status = "ftol"
                break
    return LmResult(x, F, nfev, njev, status)

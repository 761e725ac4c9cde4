"""One measurement from two scan matches of which one may be wrong: the ICP
fit and the grid fit (submap_match.py) of the same scan on the same
keyframes (MappingConfig.match_disagreement "mixture", the default).

The two fits usually agree to a few tenths of a degree; where they part by
d (grid fit ⊖ ICP's), one has slid into a rival minimum or both have been
pulled by wrongly paired points, and nothing in either fit says which. The
former rule ("fusion") kept the grid fit and added k² d dᵀ to its
covariance, so the step leaned on odometry along d; that holds a grid fit
in a rival minimum (edmonton-every2's step 48: the grid fit 4–6° off, ICP
1–2.5°), but it also hands odometry the heading of every step whose fits
merely part, and odometry's turn error is a random walk (seed 002 eqs. 2–5):
on edmonton's draw 8 its calibrated turns are 0.35° per step off, one way,
for 50 steps (a 3 σ run of the drawn white noise; no bias estimate could
have foreseen it), and that run became the map's.

**Which fit** — as the probabilistic data association filter weighs the
candidate measurements in its gate (Y. Bar-Shalom, F. Daum, J. Huang, "The
probabilistic data association filter", IEEE Control Systems 29(6), 2009,
the association probabilities β_i and the combined innovation
ν = Σ β_i ν_i; here P_D = 1 and no clutter: one of the two is the scan's
pose), with the odometry prediction x̂ (covariance Q), both fits measuring
the pose with the match's covariance R (the scan's geometry constrains
either fit alike; ICP's own Hessian covariance is 3–5 times too sure on the
logs), S = Q + R, ν_j = z_j − x̂ and equal priors:

    β_j = N(ν_j; 0, S) / Σ_l N(ν_l; 0, S),      z = Σ_j β_j z_j = z_grid − β_icp d.

Odometry only arbitrates: two fits as far from its guess weigh alike, and a
fit in a rival minimum far from it weighs nothing.

**How sure** — the two fits' errors e_g, e_i are correlated (the same scan
on the same keyframes, ρ); with equal variances σ² the midpoint's error
(e_g + e_i)/2 is independent of d = e_g − e_i, E[d²] = 2σ²(1 − ρ), so one
disagreement estimates σ² and the error of z = m + (½ − β_icp) d given d
has the variance (c_mid + (β_g − β_i)²/4) d², c_mid = (1 + ρ)/(4(1 − ρ)).
The former rule's k² (about the grid fit, β = (1, 0)) is c_mid + ¼; kept,
the covariance about the mixture is

    R_z = R + (k² − β_g β_i) d dᵀ,

the former rule where one fit weighs all, ¼ d dᵀ less where both weigh
alike. The step is then fused with odometry as before (seed 002 eqs. 11–14).

Measured (bench/localisation_bench.py --part logs --methods full): see
mapping_config.py's ``match_disagreement``. The pure PDAF update (the step
from the β-weighted innovations with the fits' own R, the disagreement only
as the two-point spread β_g β_i d dᵀ) mended edmonton (12 draws, worst
0.264 → 0.203 m) but let edmonton-every2's step 48 through (8 draws, worst
0.229 → 0.355 m): there both fits are off, and only the disagreement's size
says so.
"""

from __future__ import annotations

import math

import numpy as np


def association_weights(nu_grid: np.ndarray, nu_icp: np.ndarray, s: np.ndarray) -> np.ndarray:
    """(β_grid, β_icp): the PDAF's association probabilities of two
    innovations with the same innovation covariance ``s`` and equal priors."""
    m = np.array([float(nu_grid @ np.linalg.solve(s, nu_grid)),
                  float(nu_icp @ np.linalg.solve(s, nu_icp))])
    w = np.exp(-0.5 * (m - m.min()))
    return w / w.sum()


def mixture_measurement(grid_pose: np.ndarray, r: np.ndarray, d: np.ndarray,
                        beta: np.ndarray, k2: float) -> tuple[np.ndarray, np.ndarray]:
    """The two fits as one measurement (module docstring): z = z_grid − β_icp d
    and R + (k² − β_g β_i) d dᵀ; ``d`` = grid fit ⊖ ICP's (heading wrapped),
    ``r`` the match's covariance, ``k2`` the disagreement's factor about the
    grid fit (MappingConfig.match_disagreement_k²)."""
    z = np.asarray(grid_pose, float) - beta[1] * d
    z[2] = math.remainder(float(z[2]), 2 * math.pi)
    return z, r + max(k2 - beta[0] * beta[1], 0.0) * np.outer(d, d)

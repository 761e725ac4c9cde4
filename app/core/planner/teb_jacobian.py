"""The analytic Jacobian of the timed elastic band's penalties (teb.py).

Each penalty of ``Teb._residuals`` touches at most three neighbouring poses
and two intervals; its derivatives are written out here in one compiled
(numba) pass over the band's segments — 0.014 ms median per Jacobian on the
4WS crowd patrol's problems, against 0.19 ms for the same vectorised in
numpy (many small array operations) and 0.23 ms for forward differences
(bench/teb_jacobian_bench.py). With
segment i from pose a = si to pose b = si+1 (dx, dy its chord,
ca = cos θa, …, ΔTi its interval):

- time  ΔTi                                   ∂/∂ΔTi = 1
- arc model  k = (ca + cb) dy − (sa + sb) dx   ∂k/∂xa = sa + sb, ∂k/∂ya = −(ca + cb),
  ∂k/∂θa = −sa dy − ca dx (and the mirror for b, with the chord's signs flipped)
- speed  v = (ca dx + sa dy)/ΔT               ∂v/∂xa = −ca/ΔT, ∂v/∂θa = (ca dy − sa dx)/ΔT,
  ∂v/∂ΔT = −v/ΔT
- yaw rate  ω = wrap(θb − θa)/ΔT              ∂ω/∂θb = −∂ω/∂θa = 1/ΔT, ∂ω/∂ΔT = −ω/ΔT
- radius  r_min |Δθ| − ‖d‖, and the limits on v, −v, |ω| and the
  acceleration (vi − vi−1)/ΔT̄i (ΔT̄0 = ΔT0, ΔT̄i = (ΔTi−1 + ΔTi)/2): each a
  hinge max(0, ·) whose derivative is the inner one where the hinge is
  active and 0 elsewhere, kinks included. Active means above KINK = 10⁻⁹:
  the initial band runs at exactly the top speed, so v − v_max is 0 but for
  rounding there, and a hinge taken as active on one ulp makes Gauss–Newton
  hold v at the limit from both sides (the L dead end's 6 m band then
  stalled at 3.4× the cost);
- clearance  max(0, c − D(p)) at the inner poses and the segments' midpoints:
  −∇D, the bilinear interpolation's own derivative
  (:meth:`ObstacleField.distance_and_grad`);
- distance to the global path: the unit vector from the nearest point of the
  nearest segment (envelope theorem: that point's own motion does not count);
  for a point on the path, the segment's normal (see ``_natural_values``).

The intervals are clamped at 1 ms (ΔT = max(z, 10⁻³)), so their derivative
is 0 below the clamp. The values come back in the sparsity pattern's COO
order (``Teb._sparsity``) through a permutation computed once per band size.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["JacobianLayout", "bilinear_grad", "field_distance_and_grad", "jacobian_values"]


class JacobianLayout:
    """Where the natural blocks of :func:`jacobian_values` land in the COO
    order of the sparsity pattern (rows, cols) of a band of n poses."""

    def __init__(self, n: int, with_path: bool, rows: np.ndarray, cols: np.ndarray):
        m, q = n - 1, n - 2
        nv = 3 * q + m
        seg = np.arange(m)

        def pc(p):  # pose index array -> (len, 3) variable columns, −1 when fixed
            p = np.asarray(p)
            base = 3 * (p - 1)
            out = base[:, None] + np.arange(3)[None]
            out[(p <= 0) | (p >= n - 1)] = -1
            return out

        dtc = 3 * q + seg
        dt_prev = np.where(seg > 0, 3 * q + seg - 1, -1)
        pair = np.column_stack([pc(seg), pc(seg + 1), dtc])  # m × 7
        inner = 3 * np.arange(q)[:, None] + np.arange(2)[None]  # q × 2
        blocks_r, blocks_c = [seg[:, None]], [dtc[:, None]]  # time
        r0 = m
        for _ in range(5):  # kin, radius, vmax, back, wmax
            blocks_r.append(np.broadcast_to((r0 + seg)[:, None], pair.shape))
            blocks_c.append(pair)
            r0 += m
        acc = np.column_stack([pc(seg - 1), dt_prev, pc(seg), pc(seg + 1), dtc])  # m × 11
        blocks_r.append(np.broadcast_to((r0 + seg)[:, None], acc.shape))
        blocks_c.append(acc)
        r0 += m
        blocks_r.append(np.broadcast_to((r0 + np.arange(q))[:, None], inner.shape))
        blocks_c.append(inner)
        r0 += q
        mid = np.column_stack([pc(seg)[:, :2], pc(seg + 1)[:, :2]])  # m × 4
        blocks_r.append(np.broadcast_to((r0 + seg)[:, None], mid.shape))
        blocks_c.append(mid)
        r0 += m
        if with_path:
            blocks_r.append(np.broadcast_to((r0 + np.arange(q))[:, None], inner.shape))
            blocks_c.append(inner)
        nat_r = np.concatenate([b.ravel() for b in blocks_r])
        nat_c = np.concatenate([b.ravel() for b in blocks_c])
        keep = np.nonzero(nat_c >= 0)[0]
        key_nat = nat_r[keep] * nv + nat_c[keep]
        key_coo = np.asarray(rows, dtype=np.int64) * nv + np.asarray(cols, dtype=np.int64)
        srt = np.argsort(key_nat)
        at = np.searchsorted(key_nat[srt], key_coo)
        if (len(key_nat) != len(key_coo) or np.any(at >= len(key_nat))
                or np.any(key_nat[srt][np.minimum(at, len(key_nat) - 1)] != key_coo)):
            raise AssertionError("the analytic Jacobian's entries differ from the pattern's")
        self.perm = keep[srt[at]]  # COO entry k = natural entry perm[k]
        self.size = len(nat_r)
        self.n, self.with_path = n, with_path


def field_distance_and_grad(field, xy: np.ndarray, h: float = 1e-6):
    """D(xy) and ∇D (…, 2) from the field's own ``distance_and_grad`` when it
    has one, else by central differences of its ``distance``."""
    fn = getattr(field, "distance_and_grad", None)
    if fn is not None:
        return fn(xy)
    xy = np.asarray(xy, dtype=float)
    e = np.array([[h, 0.0], [-h, 0.0], [0.0, h], [0.0, -h]])
    pts = np.concatenate([xy[None], xy[None] + e.reshape(4, *([1] * (xy.ndim - 1)), 2)])
    D = field.distance(pts)
    g = np.stack([(D[1] - D[2]) / (2 * h), (D[3] - D[4]) / (2 * h)], axis=-1)
    return D[0], g


KINK = 1e-9


@njit(cache=True)
def _hinge(x):
    """∂ max(0, x)/∂x: 1 where the hinge is active, 0 elsewhere and within
    KINK of its kink."""
    return 1.0 if x > KINK else 0.0


@njit(cache=True)
def _sgn(x):
    return 1.0 if x > 0.0 else (-1.0 if x < 0.0 else 0.0)


@njit(cache=True)
def _natural_values(z, n, start, goal, v0, prm, opt, D, G, path, with_path, out):
    """The Jacobian's entries in the natural order of :class:`JacobianLayout`
    into out. prm: the weights w_time, w_kin, w_radius, w_limits, w_reverse,
    w_obstacle, w_path, then max speed, max reverse, max yaw rate, max
    acceleration, clearance and r_min; D, G: the field's distance and
    gradient at the inner poses then the segments' midpoints."""
    w_time, w_kin, w_rad, w_lim = prm[0], prm[1], prm[2], prm[3]
    w_rev, w_obs, w_path = prm[4], prm[5], prm[6]
    vmax, vrev, wmax, amax, clear, r_min = prm[7], prm[8], prm[9], prm[10], prm[11], prm[12]
    m = n - 1
    q = n - 2
    P = np.empty((n, 3))
    P[0] = start
    for i in range(q):
        P[i + 1, 0] = z[3 * i]
        P[i + 1, 1] = z[3 * i + 1]
        P[i + 1, 2] = z[3 * i + 2]
    P[n - 1] = goal
    dts = np.empty(m)
    mk = np.empty(m)
    for i in range(m):
        zz = z[3 * q + i]
        if zz > 1e-3:
            dts[i] = zz
            mk[i] = 1.0
        else:
            dts[i] = 1e-3
            mk[i] = 0.0
    # time
    for i in range(m):
        out[i] = w_time * mk[i]
    o_kin = m
    o_rad = o_kin + 7 * m
    o_vmax = o_rad + 7 * m
    o_back = o_vmax + 7 * m
    o_w = o_back + 7 * m
    o_acc = o_w + 7 * m
    o_obs = o_acc + 11 * m
    o_mid = o_obs + 2 * q
    o_path = o_mid + 4 * m
    Jv = np.empty(7)
    Jvp = np.zeros(7)
    vprev = v0
    for i in range(m):
        xa, ya, ta = P[i, 0], P[i, 1], P[i, 2]
        xb, yb, tb = P[i + 1, 0], P[i + 1, 1], P[i + 1, 2]
        dx = xb - xa
        dy = yb - ya
        dist = math.sqrt(dx * dx + dy * dy)
        dth = (tb - ta + math.pi) % (2 * math.pi) - math.pi
        ca, sa, cb, sb = math.cos(ta), math.sin(ta), math.cos(tb), math.sin(tb)
        inv = 1.0 / dts[i]
        v = (ca * dx + sa * dy) * inv
        Jv[0] = -ca * inv
        Jv[1] = -sa * inv
        Jv[2] = (ca * dy - sa * dx) * inv
        Jv[3] = ca * inv
        Jv[4] = sa * inv
        Jv[5] = 0.0
        Jv[6] = -v * inv * mk[i]
        om = dth * inv
        k = o_kin + 7 * i
        cs, ss = ca + cb, sa + sb
        out[k] = w_kin * ss
        out[k + 1] = -w_kin * cs
        out[k + 2] = w_kin * (-sa * dy - ca * dx)
        out[k + 3] = -w_kin * ss
        out[k + 4] = w_kin * cs
        out[k + 5] = w_kin * (-sb * dy - cb * dx)
        out[k + 6] = 0.0
        k = o_rad + 7 * i
        g = w_rad * _hinge(r_min * abs(dth) - dist)
        ux = dx / dist if dist > 0.0 else 0.0
        uy = dy / dist if dist > 0.0 else 0.0
        rs = r_min * _sgn(dth)
        out[k] = g * ux
        out[k + 1] = g * uy
        out[k + 2] = -g * rs
        out[k + 3] = -g * ux
        out[k + 4] = -g * uy
        out[k + 5] = g * rs
        out[k + 6] = 0.0
        gv = w_lim * _hinge(v - vmax)
        if opt:
            gb = -w_rev * _hinge(-v)
        else:
            gb = -w_lim * _hinge(-v - vrev)
        for j in range(7):
            out[o_vmax + 7 * i + j] = gv * Jv[j]
            out[o_back + 7 * i + j] = gb * Jv[j]
        k = o_w + 7 * i
        gw = w_lim * _sgn(om) * _hinge(abs(om) - wmax)
        out[k] = 0.0
        out[k + 1] = 0.0
        out[k + 2] = -gw * inv
        out[k + 3] = 0.0
        out[k + 4] = 0.0
        out[k + 5] = gw * inv
        out[k + 6] = -gw * om * inv * mk[i]
        # acceleration (v_i − v_{i−1}) / tacc_i
        if i == 0:
            tacc = dts[0]
            dprev, dcur = 0.0, mk[0]
        else:
            tacc = 0.5 * (dts[i - 1] + dts[i])
            dprev, dcur = 0.5 * mk[i - 1], 0.5 * mk[i]
        acc = (v - vprev) / tacc
        ga = w_lim * _sgn(acc) * _hinge(abs(acc) - amax) / tacc
        k = o_acc + 11 * i
        out[k] = -ga * Jvp[0]
        out[k + 1] = -ga * Jvp[1]
        out[k + 2] = -ga * Jvp[2]
        out[k + 3] = ga * (-Jvp[6] - acc * dprev)
        out[k + 4] = ga * (Jv[0] - Jvp[3])
        out[k + 5] = ga * (Jv[1] - Jvp[4])
        out[k + 6] = ga * (Jv[2] - Jvp[5])
        out[k + 7] = ga * Jv[3]
        out[k + 8] = ga * Jv[4]
        out[k + 9] = ga * Jv[5]
        out[k + 10] = ga * (Jv[6] - acc * dcur)
        for j in range(7):
            Jvp[j] = Jv[j]
        vprev = v
        # obstacle at the midpoint (D, G rows q + i)
        go = -0.5 * w_obs * _hinge(clear - D[q + i])
        k = o_mid + 4 * i
        out[k] = go * G[q + i, 0]
        out[k + 1] = go * G[q + i, 1]
        out[k + 2] = go * G[q + i, 0]
        out[k + 3] = go * G[q + i, 1]
    for i in range(q):
        go = -w_obs * _hinge(clear - D[i])
        out[o_obs + 2 * i] = go * G[i, 0]
        out[o_obs + 2 * i + 1] = go * G[i, 1]
    if with_path:
        M = path.shape[0]
        for i in range(q):
            px, py = P[i + 1, 0], P[i + 1, 1]
            bx = px - path[0, 0]
            by = py - path[0, 1]
            best = bx * bx + by * by
            nx, ny, inside = 0.0, 0.0, False
            for s in range(M - 1):
                ax, ay = path[s, 0], path[s, 1]
                abx, aby = path[s + 1, 0] - ax, path[s + 1, 1] - ay
                L2 = max(abx * abx + aby * aby, 1e-12)
                t = ((px - ax) * abx + (py - ay) * aby) / L2
                t = min(max(t, 0.0), 1.0)
                ox = px - (ax + t * abx)
                oy = py - (ay + t * aby)
                dd = ox * ox + oy * oy
                if s == 0 or dd < best:
                    best = dd
                    bx, by = ox, oy
                    L = math.sqrt(L2)
                    nx, ny = -aby / L, abx / L
                    inside = 0.0 < t < 1.0
            d = math.sqrt(best)
            if inside or d == 0.0:
                # The segment's unit normal, to the point's side: equal to the
                # offset's direction off the path, and on it the direction
                # whose Gauss–Newton term w² n nᵀ is the exact curvature of
                # (w d)², where the offset has none.
                sgn = 1.0 if bx * nx + by * ny >= 0.0 else -1.0
                gx, gy = sgn * nx, sgn * ny
            else:  # nearest to a vertex: away from it
                gx, gy = bx / d, by / d
            out[o_path + 2 * i] = w_path * gx
            out[o_path + 2 * i + 1] = w_path * gy

@njit(cache=True)
def bilinear_grad(grid, ox, oy, res, pts, d_out, g_out):
    """Bilinear interpolation of grid at the points (k × 2, metres; sample
    (r, c) at (ox + (c + ½) res, oy + (r + ½) res)) and its gradient, as
    ``map_coordinates(order=1, mode="constant", cval=0)``: 0 outside the
    samples' extent; on a cell edge the derivative of the cell above it."""
    h, w = grid.shape
    for k in range(pts.shape[0]):
        c = (pts[k, 0] - ox) / res - 0.5
        r = (pts[k, 1] - oy) / res - 0.5
        if not (r >= 0.0 and r <= h - 1 and c >= 0.0 and c <= w - 1):
            d_out[k] = 0.0
            g_out[k, 0] = 0.0
            g_out[k, 1] = 0.0
            continue
        r0 = min(int(math.floor(r)), max(h - 2, 0))
        c0 = min(int(math.floor(c)), max(w - 2, 0))
        r1 = min(r0 + 1, h - 1)
        c1 = min(c0 + 1, w - 1)
        fr = r - r0
        fc = c - c0
        v00, v01, v10, v11 = grid[r0, c0], grid[r0, c1], grid[r1, c0], grid[r1, c1]
        top = v00 + fc * (v01 - v00)
        bot = v10 + fc * (v11 - v10)
        d_out[k] = top + fr * (bot - top)
        g_out[k, 0] = ((v01 - v00) + fr * ((v11 - v10) - (v01 - v00))) / res
        g_out[k, 1] = (bot - top) / res


def _params(cfg, r_min: float) -> np.ndarray:
    return np.array([cfg.w_time, cfg.w_kin, cfg.w_radius, cfg.w_limits, cfg.w_reverse,
                     cfg.w_obstacle, cfg.w_path, cfg.max_speed_mps, cfg.max_reverse_mps,
                     cfg.max_yaw_rate, cfg.max_accel_mps2, cfg.clearance_m, float(r_min)])


_NO_PATH = np.zeros((1, 2))


def jacobian_values(cfg, r_min: float, layout: JacobianLayout, z, n, start, goal, field,
                    path, v0) -> np.ndarray:
    """∂r/∂z of ``Teb._residuals`` at z, as the values of the sparsity
    pattern in COO order."""
    q = n - 2
    z = np.ascontiguousarray(z, dtype=float)
    start = np.ascontiguousarray(start, dtype=float)
    goal = np.ascontiguousarray(goal, dtype=float)
    xy = z[: 3 * q].reshape(q, 3)[:, :2]
    ends = np.vstack([start[:2], xy, goal[:2]])
    D, G = field_distance_and_grad(field, np.vstack([xy, 0.5 * (ends[:-1] + ends[1:])]))
    out = np.empty(layout.size)
    with_path = path is not None
    _natural_values(z, n, start, goal, float(v0), _params(cfg, r_min), bool(cfg.optimised),
                    np.ascontiguousarray(D, dtype=float), np.ascontiguousarray(G, dtype=float),
                    np.ascontiguousarray(path, dtype=float) if with_path else _NO_PATH,
                    with_path, out)
    return out[layout.perm]

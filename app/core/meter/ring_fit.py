"""The scale ring's circle fits (:mod:`.ring_centre`), compiled (numba).

:func:`trimmed_kernel` is :func:`.ring_centre._trimmed_circle_np`'s trimmed circle fit and
:func:`fits_kernel` the loop over the candidate rings' mark ends that calls it
(:func:`.ring_centre._best_fit_np`), with the same arithmetic: numpy's pairwise sums
(:func:`pairwise_sum`), the same BLAS dot products and the same elementwise steps, so the
same values to the last digit.  Where a fit's points lie on a line they answer COLLINEAR
and the caller runs the numpy form.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

NONE, FITTED, COLLINEAR = 0, 1, 2  # no circle, a circle, left to the numpy form


@njit(cache=True)
def fits_kernel(b, short, hid, has_hid, r0, kinds, los, his, rs, sin64, cos64, c0, c1,
                clamp_band, step, min_arc_deg, clamped_share):
    """:func:`.ring_centre._best_fit_np`'s loop over the candidate rings and their two
    ends: (status, m, n, rms, r) of the closest fit (status as :func:`trimmed_kernel`'s)."""
    n_col = b.shape[1]
    best_status, bm, bn, brms, br = NONE, 0.0, 0.0, 0.0, 0.0
    cols = np.empty(n_col, np.int64)
    edge = np.empty(n_col, np.int64)
    for q in range(len(los)):
        img = b if kinds[q] == 0 else short
        lo, hi = los[q], his[q]
        nc = 0  # the columns lit in the ring's rows, where the needle does not lie
        for x in range(n_col):
            if has_hid:
                hidden = False
                for y in range(lo, hi + 1):
                    if hid[y - r0, x]:
                        hidden = True
                        break
                if hidden:
                    continue
            for y in range(lo, hi + 1):
                if img[y, x]:
                    cols[nc] = x
                    nc += 1
                    break
        if nc < 20:
            continue
        if kinds[q] != 0:  # a short arc of strokes fixes no centre
            gap = cols[0] + n_col - cols[nc - 1]
            for i in range(1, nc):
                gap = max(gap, cols[i] - cols[i - 1])
            if 360.0 - float(gap) * step < min_arc_deg:
                continue
        for side in range(2):  # the outer end first, then the inner
            clamped = 0
            for i in range(nc):
                x = cols[i]
                if side == 0:
                    e = hi
                    while not img[e, x]:
                        e -= 1
                else:
                    e = lo
                    while not img[e, x]:
                        e += 1
                edge[i] = e - lo
                if e == lo or e == hi:
                    clamped += 1
            if (kinds[q] != 0 or clamp_band) and clamped / nc > clamped_share:
                continue
            px = np.empty(nc)
            py = np.empty(nc)
            for i in range(nc):
                r_e = np.float64(rs[lo + edge[i]])
                px[i] = c0 + r_e * sin64[cols[i]]
                py[i] = c1 - r_e * cos64[cols[i]]
            st, m, n, rms, r = trimmed_kernel(px, py)
            if st == COLLINEAR:
                return COLLINEAR, 0.0, 0.0, 0.0, 0.0
            if st == FITTED and (best_status != FITTED or rms < brms):
                best_status, bm, bn, brms, br = FITTED, m, n, rms, r
    return best_status, bm, bn, brms, br


@njit(cache=True)
def trimmed_kernel(px, py):
    """:func:`.ring_centre._trimmed_circle_np`'s rounds: (status, m, n, rms, r), status
    one of NONE, FITTED, COLLINEAR (a round's points on a line: not decided here)."""
    n_all = len(px)
    keep = np.ones(n_all, np.bool_)
    new = np.empty(n_all, np.bool_)
    n_keep = n_all
    m = nn = r = rms = 0.0
    for _ in range(4):
        if n_keep < 20:
            return NONE, 0.0, 0.0, 0.0, 0.0
        sx = np.empty(n_keep)
        sy = np.empty(n_keep)
        j = 0
        for i in range(n_all):
            if keep[i]:
                sx[j] = px[i]
                sy[j] = py[i]
                j += 1
        ox = pairwise_sum(sx, n_keep) / n_keep
        oy = pairwise_sum(sy, n_keep) / n_keep
        x = sx - ox
        y = sy - oy
        z = np.empty(n_keep)
        for i in range(n_keep):
            z[i] = x[i] * x[i] + y[i] * y[i]
        sxx, sxy, syy = np.dot(x, x), np.dot(x, y), np.dot(y, y)
        sxz, syz = 0.5 * np.dot(x, z), 0.5 * np.dot(y, z)
        det = sxx * syy - sxy * sxy
        if det <= 1e-12 * max(sxx * syy, 1e-300):
            return COLLINEAR, 0.0, 0.0, 0.0, 0.0
        m0 = (sxz * syy - syz * sxy) / det
        n0 = (syz * sxx - sxz * sxy) / det
        cz = pairwise_sum(z, n_keep) / n_keep
        m, nn = m0 + ox, n0 + oy
        r = math.sqrt(max(cz + m0 * m0 + n0 * n0, 0.0))
        d = np.empty(n_all)
        for i in range(n_all):
            d[i] = np.hypot(px[i] - m, py[i] - nn) - r
        dk2 = np.empty(n_keep)
        j = 0
        for i in range(n_all):
            if keep[i]:
                dk2[j] = d[i] * d[i]
                j += 1
        rms = math.sqrt(pairwise_sum(dk2, n_keep) / n_keep)
        tol = max(1.0, 2.0 * rms)
        n_new = 0
        same = True
        for i in range(n_all):
            v = abs(d[i]) < tol
            new[i] = v
            n_new += v
            same = same and v == keep[i]
        if same:
            break
        keep[:] = new
        n_keep = n_new
    if n_keep < max(20, 0.4 * n_all):
        return NONE, 0.0, 0.0, 0.0, 0.0
    return FITTED, m, nn, rms, r


# numpy's pairwise summation, written out level by level (a compiled function that calls
# itself is not safely cached): a level sums up to its PW_MAX, halving (in multiples of 8)
# down to the blocks of up to 128 that eight running sums add up
PW_MAX = (128, 240, 464, 912, 1808, 3600)


@njit(cache=True)
def _pw0(a, lo, n):
    """``np.add.reduce(a[lo:lo + n])`` (float64, contiguous), n <= 128, as numpy sums it."""
    if n < 8:
        res = 0.0
        for i in range(lo, lo + n):
            res += a[i]
        return res
    r0, r1, r2, r3 = a[lo], a[lo + 1], a[lo + 2], a[lo + 3]
    r4, r5, r6, r7 = a[lo + 4], a[lo + 5], a[lo + 6], a[lo + 7]
    i = 8
    while i < n - (n % 8):
        r0 += a[lo + i]
        r1 += a[lo + i + 1]
        r2 += a[lo + i + 2]
        r3 += a[lo + i + 3]
        r4 += a[lo + i + 4]
        r5 += a[lo + i + 5]
        r6 += a[lo + i + 6]
        r7 += a[lo + i + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += a[lo + i]
        i += 1
    return res


@njit(cache=True)
def _pw1(a, lo, n):
    if n <= 128:
        return _pw0(a, lo, n)
    n2 = n // 2 - (n // 2) % 8
    return _pw0(a, lo, n2) + _pw0(a, lo + n2, n - n2)


@njit(cache=True)
def _pw2(a, lo, n):
    if n <= 128:
        return _pw0(a, lo, n)
    n2 = n // 2 - (n // 2) % 8
    return _pw1(a, lo, n2) + _pw1(a, lo + n2, n - n2)


@njit(cache=True)
def _pw3(a, lo, n):
    if n <= 128:
        return _pw0(a, lo, n)
    n2 = n // 2 - (n // 2) % 8
    return _pw2(a, lo, n2) + _pw2(a, lo + n2, n - n2)


@njit(cache=True)
def _pw4(a, lo, n):
    if n <= 128:
        return _pw0(a, lo, n)
    n2 = n // 2 - (n // 2) % 8
    return _pw3(a, lo, n2) + _pw3(a, lo + n2, n - n2)


@njit(cache=True)
def pairwise_sum(a, n):
    """``np.add.reduce(a[:n])`` of a contiguous float64 array, summed as numpy sums it (its
    pairwise summation), so the same value; n <= PW_MAX[-1]."""
    if n <= 128:
        return _pw0(a, 0, n)
    n2 = n // 2 - (n // 2) % 8
    return _pw4(a, 0, n2) + _pw4(a, n2, n - n2)

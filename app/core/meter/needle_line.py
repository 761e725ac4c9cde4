"""Step 4 of :mod:`.needle`: the needle's axis to a fraction of a degree.

Per radius, the response-weighted centroid across the needle in the polar unwrap gives a
point (:func:`_centroids`); points where print touches the needle are dropped and the
rest capped (:func:`_needle_points`); the line most of the points of both ends agree with
(a consensus over lines through pairs of them) is refitted by weighted total least squares
through its inliers (:func:`_fit_needle`).  See :mod:`.needle`'s docstring.
"""

from __future__ import annotations

import numpy as np

from .dial import _median

N_TH = 720  # 0.5 deg per ray of the polar unwrap
R_IN = 0.2  # the hub skipped, in units of the scale's radius R
WIDE_RUN = 1.8  # a centre whose run across the needle is this much wider is print beside it
CAP_SUM = 1.5  # no centre weighs more than this x the median response across the needle
CONSENSUS_PTS = 24  # lines through pairs of this many centres (evenly spaced) are tried
INLIER_PX = 1.2  # a centre this near a line agrees with it


def _centroids(p: np.ndarray, th0: int, rs: np.ndarray, r_max: float, half_px: float,
               pivot) -> tuple[np.ndarray, np.ndarray]:
    """Per radius up to ``r_max``: the response-weighted centre across the needle near ray
    ``th0``, as image points, with the response summed across, the radius and the run's
    width in px.  Only the run of rays around the local peak counts, so a numeral or a tick
    beside the needle does not pull the centre."""
    js = np.flatnonzero(rs <= r_max)
    if len(js) == 0:
        return np.zeros((0, 2)), np.zeros(0), np.zeros(0), np.zeros(0)
    r = rs[js]
    hw = np.clip(np.ceil(np.degrees(half_px / r) * N_TH / 360.0), 3, 40).astype(int)
    hmax = int(hw.max())
    offs = np.arange(-hmax, hmax + 1)
    v = p[(th0 + offs[:, None]) % N_TH, js[None, :]]  # window x radii
    inwin = np.abs(offs)[:, None] <= hw[None, :]
    v = np.where(inwin, v, 0.0)
    k = np.argmax(v, axis=0)
    peak = v[k, np.arange(len(js))]
    above = v > 0.3 * peak[None, :]
    idx = np.arange(len(offs))[:, None]
    lo = np.where(~above & (idx < k), idx, -1).max(axis=0) + 1
    hi = np.where(~above & (idx > k), idx, len(offs)).min(axis=0) - 1
    # the run must close inside the window: a thin line here, not a blob
    ok = (peak > 0) & (lo > hmax - hw) & (hi < hmax + hw)
    run = (idx >= lo) & (idx <= hi) & ok[None, :]
    w = np.where(run, v - 0.3 * peak[None, :], 0.0)
    sw = w.sum(axis=0)
    ok &= sw > 0
    ok &= ~_widened(np.where(ok, (hi - lo + 1) * (2 * np.pi / N_TH) * r, np.nan), r)
    t = (th0 + (offs[:, None] * w).sum(axis=0)[ok] / sw[ok]) * (2 * np.pi / N_TH)
    pts = np.column_stack([pivot[0] + r[ok] * np.sin(t), pivot[1] - r[ok] * np.cos(t)])
    width = (hi - lo + 1)[ok] * (2 * np.pi / N_TH) * r[ok]
    return pts, sw[ok], r[ok], width


def _needle_points(pieces) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The centre points of both ends (``_centroids``' results), their weights for the line
    fit and their shares in the consensus.  A needle's cross-section changes slowly along
    it; where a numeral, a tick or the hub's ring touches it, the run across it is wider
    and its response sum larger.  Such points are dropped (run wider than ``WIDE_RUN`` x
    the median) and every point's response is capped at ``CAP_SUM`` x the median, so that
    thick print cannot outweigh the needle; in the fit far points fix the direction better
    (weight x radius)."""
    pts = np.vstack([p[0] for p in pieces])
    sw = np.concatenate([p[1] for p in pieces])
    r = np.concatenate([p[2] for p in pieces])
    width = np.concatenate([p[3] for p in pieces])
    if len(pts) == 0:
        return pts, sw, sw
    keep = width <= WIDE_RUN * _median(width) + 2.0
    capped = np.minimum(sw[keep], CAP_SUM * _median(sw[keep]))
    return pts[keep], capped * r[keep], capped


def _fit_needle(pts: np.ndarray, w: np.ndarray, cover: np.ndarray):
    """The needle's axis as the line that most centres agree with (a consensus over lines
    through pairs of centres, Fischler & Bolles 1981), then a robust fit through its
    inliers: (centroid, unit direction, spread, the inliers' share of the centres).

    The centres near the hub (its ring, a set-point's hub) or where the needle runs into a
    numeral or a tick leave the line, and only the needle's own straight run counts.
    ``cover`` (each centre's capped response) breaks ties."""
    n = len(pts)
    if n < 4:
        return (*_fit_line(pts, w), 1.0)
    sub, ii, jj = _pairs(n)
    a, b = pts[sub[ii]], pts[sub[jj]]
    d = b - a
    ln = np.hypot(d[:, 0], d[:, 1])
    use = ln > 8.0  # far enough apart to fix a direction
    if not use.any():
        return (*_fit_line(pts, w), 1.0)
    a, nrm = a[use], np.column_stack([-d[use, 1], d[use, 0]]) / ln[use, None]
    res = np.abs((pts[None, :, 0] - a[:, None, 0]) * nrm[:, None, 0]
                 + (pts[None, :, 1] - a[:, None, 1]) * nrm[:, None, 1])
    # the longest straight run: the most centres (one per radius), each counted by how
    # near it lies (MSAC's truncated quadratic cost, Torr & Zisserman 2000: a line turned
    # a little still passes within the band of a short run, not near its centres); the
    # response only breaks ties (a pin or a numeral beside the needle responds more than
    # its thin tip)
    votes = res <= INLIER_PX
    near = np.maximum(0.0, 1.0 - (res / INLIER_PX) ** 2)
    best = int(np.argmax(near.sum(axis=1) + (votes * cover[None, :]).sum(axis=1)
                         / max(float(cover.sum()), 1e-9)))
    inl = votes[best]
    if inl.sum() < 4:
        return (*_fit_line(pts, w), float(inl.mean()))
    for _ in range(2):  # refined through its inliers, which are then taken again
        c, u, spread = _fit_line(pts[inl], w[inl])
        near = np.abs((pts - c) @ np.array([-u[1], u[0]])) <= INLIER_PX
        if near.sum() < 4 or (near == inl).all():
            break
        inl = near
    return c, u, spread, float(inl.mean())


def _pairs(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The centres of :func:`_fit_needle`'s consensus (up to :data:`CONSENSUS_PTS` of ``n``,
    evenly spaced) and every pair of them (i < j, as ``np.triu_indices``): made once per
    ``n`` (read-only), as a needle has a few dozen centres."""
    got = _PAIRS.get(n)
    if got is None:
        sub = np.unique(np.linspace(0, n - 1, min(n, CONSENSUS_PTS)).round().astype(int))
        got = (sub, *np.triu_indices(len(sub), 1))
        for a in got:
            a.flags.writeable = False
        _PAIRS[n] = got
    return got


_PAIRS: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}


def _widened(width: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Radii where the needle's cross-section is much wider than its shape's trend along
    it (a robust straight line of width against radius): a numeral or a tick touches the
    needle there and would pull its centre off the axis.  NaN widths are not judged."""
    ok = np.isfinite(width)
    keep = ok.copy()
    out = np.zeros(len(width), bool)
    for _ in range(3):
        if keep.sum() < 6:
            return out
        a, b = _lsq_line(r[keep], width[keep])
        trend = a + b * r
        new = ok & (width <= 1.3 * trend + 1.5)
        if (new == keep).all():
            break
        keep = new
    out[ok] = ~keep[ok]
    return out


def _lsq_line(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """Least squares ``y = a + b x`` (``np.polyfit(x, y, 1)`` reversed, to its last digits
    or so) in closed form about the means, without polyfit's scaled solver; x not all
    equal."""
    xm = float(np.add.reduce(x)) / len(x)
    ym = float(np.add.reduce(y)) / len(y)
    dx = x - xm
    b = float(dx @ (y - ym)) / float(dx @ dx)
    return ym - b * xm, b


def _fit_line(pts: np.ndarray, w: np.ndarray):
    """Weighted total-least-squares line, (centroid, unit direction, spread), made robust by
    three Cauchy reweightings: centres pulled off the needle by a numeral count less."""
    wt = w.copy()
    for it in range(4):
        c = (pts * wt[:, None]).sum(0) / wt.sum()
        d = pts - c
        s = (d * wt[:, None]).T @ d / wt.sum()
        evals, evecs = np.linalg.eigh(s)
        u = evecs[:, 1]
        res = np.abs(d @ np.array([-u[1], u[0]]))
        if it < 3:
            sigma = max(0.5, 1.5 * _median(res))
            wt = w / (1.0 + (res / sigma) ** 2)
    return c, u, 1.4826 * _median(res)  # robust spread about the line

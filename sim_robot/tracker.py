"""Moving obstacles from the lidar: scan points not in the static map, clustered
and tracked with velocity.

1. Each return is turned into a map point with the robot's estimated pose;
   points within ``static_gap_m`` (+ a little per metre of range, for heading
   noise) of the static map are the map itself and dropped.
2. The rest are grouped in beam order: a gap over ``cluster_gap_m`` between
   neighbouring returns starts a new cluster (the first and last beams join up).
3. A cluster seen as an arc of a disc: radius = half its extent, centre = the
   centroid pushed away from the sensor by π/4 · radius (the mean of an arc
   sampled uniformly across its width lies π/4 · r in front of the centre).
4. Tracks: greedy nearest-neighbour association within a gate around each
   track's prediction, then an alpha-beta filter for position and velocity
   (x ← x̂ + α r, v ← v + β r / Δt, r the innovation). A track is published
   after ``confirm_hits`` hits and dropped after ``drop_after_s`` unseen.
5. Manoeuvres: the filter's small β keeps a standing person's velocity
   quiet but lags a person setting off (0.15 → 0.74 m/s over 0.5 s for one
   starting at 0.8 m/s). So each track also keeps its detections of the last
   ``fit_window_s``; once they span ``fit_min_span_s``, a least-squares line
   through them gives a second velocity, and when the two differ by more than
   ``manoeuvre_mps`` the filter's velocity is replaced by the fitted one
   (a start, a stop or a turn is followed within ≈ 0.2 s).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np


@dataclass
class TrackerConfig:
    range_max_m: float = 8.0
    static_gap_m: float = 0.25
    static_gap_per_m: float = 0.012
    cluster_gap_m: float = 0.45
    min_points: int = 2
    max_radius_m: float = 1.5
    gate_m: float = 1.2
    alpha: float = 0.5
    beta: float = 0.15
    max_speed_mps: float = 4.0
    confirm_hits: int = 3
    drop_after_s: float = 1.0
    radius_margin_m: float = 0.05
    fit_window_s: float = 0.3
    fit_min_span_s: float = 0.2
    manoeuvre_mps: float = 0.3


@dataclass
class Track:
    id: int
    x: float
    y: float
    vx: float
    vy: float
    r: float
    hits: int = 1
    last_t: float = 0.0
    seen: list[tuple[float, float, float]] = field(default_factory=list)  # (t, x, y)


class ObstacleTracker:
    def __init__(self, clearance_m: np.ndarray, resolution_m: float,
                 origin_xy: tuple[float, float] = (0.0, 0.0),
                 config: TrackerConfig | None = None) -> None:
        """``clearance_m``: metres from each cell to the static map (row = y)."""
        self.clear = clearance_m
        self.res = resolution_m
        self.origin = origin_xy
        self.cfg = config or TrackerConfig()
        self.tracks: list[Track] = []
        self._next_id = 1
        self.t: float | None = None

    # -------------------------------------------------------------- detection
    def _static_clearance(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        c = np.floor((x - self.origin[0]) / self.res).astype(int)
        r = np.floor((y - self.origin[1]) / self.res).astype(int)
        h, w = self.clear.shape
        inside = (r >= 0) & (r < h) & (c >= 0) & (c < w)
        out = np.zeros(len(x))
        out[inside] = self.clear[r[inside], c[inside]]
        return out

    def detect(self, ranges: np.ndarray, angle_min: float, angle_inc: float,
               pose: tuple[float, float, float]) -> list[tuple[float, float, float]]:
        """Clusters of non-map returns as discs (x, y, radius) in the map frame."""
        cfg = self.cfg
        rng = np.asarray(ranges, float)
        n = len(rng)
        ang = pose[2] + angle_min + angle_inc * np.arange(n)
        ok = np.isfinite(rng) & (rng <= cfg.range_max_m)
        rr = np.where(ok, rng, 0.0)
        px = pose[0] + rr * np.cos(ang)
        py = pose[1] + rr * np.sin(ang)
        idx = np.flatnonzero(ok)
        if len(idx) == 0:
            return []
        gap = cfg.static_gap_m + cfg.static_gap_per_m * rng[idx]
        idx = idx[self._static_clearance(px[idx], py[idx]) > gap]
        if len(idx) == 0:
            return []
        # clusters in beam order
        groups: list[list[int]] = [[int(idx[0])]]
        for a, b in zip(idx[:-1], idx[1:], strict=False):
            if math.hypot(px[b] - px[a], py[b] - py[a]) > cfg.cluster_gap_m:
                groups.append([])
            groups[-1].append(int(b))
        if len(groups) > 1:  # the scan is a full turn: the last cluster may wrap to the first
            a, b = groups[-1][-1], groups[0][0]
            if math.hypot(px[b] - px[a], py[b] - py[a]) <= cfg.cluster_gap_m:
                groups[0] = groups.pop() + groups[0]
        out = []
        for g in groups:
            if len(g) < cfg.min_points:
                continue
            gx, gy = px[g], py[g]
            ext = max(np.hypot(gx[i] - gx[j], gy[i] - gy[j])
                      for i, j in ((0, -1), (0, len(g) // 2), (len(g) // 2, -1)))
            r = float(np.clip(ext / 2, 0.1, cfg.max_radius_m))
            cx, cy = float(gx.mean()), float(gy.mean())
            dx, dy = cx - pose[0], cy - pose[1]
            d = math.hypot(dx, dy) or 1.0
            out.append((cx + dx / d * math.pi / 4 * r, cy + dy / d * math.pi / 4 * r, r))
        return out

    # -------------------------------------------------------------- tracking
    def update(self, t_s: float, detections: list[tuple[float, float, float]]) -> None:
        cfg = self.cfg
        dt = 0.0 if self.t is None else max(t_s - self.t, 0.0)
        self.t = t_s
        for tr in self.tracks:  # predict
            tr.x += tr.vx * dt
            tr.y += tr.vy * dt
        pairs = []
        for ti, tr in enumerate(self.tracks):
            for di, (x, y, _r) in enumerate(detections):
                d = math.hypot(x - tr.x, y - tr.y)
                if d <= cfg.gate_m + tr.r:
                    pairs.append((d, ti, di))
        pairs.sort()
        used_t: set[int] = set()
        used_d: set[int] = set()
        for _d, ti, di in pairs:
            if ti in used_t or di in used_d:
                continue
            used_t.add(ti)
            used_d.add(di)
            tr = self.tracks[ti]
            x, y, r = detections[di]
            rx, ry = x - tr.x, y - tr.y
            tr.x += cfg.alpha * rx
            tr.y += cfg.alpha * ry
            if dt > 1e-6:
                tr.vx += cfg.beta * rx / dt
                tr.vy += cfg.beta * ry / dt
                sp = math.hypot(tr.vx, tr.vy)
                if sp > cfg.max_speed_mps:
                    tr.vx *= cfg.max_speed_mps / sp
                    tr.vy *= cfg.max_speed_mps / sp
            self._refit(tr, t_s, x, y)
            tr.r = 0.7 * tr.r + 0.3 * r if tr.hits > 1 else r
            tr.hits += 1
            tr.last_t = t_s
        for di, (x, y, r) in enumerate(detections):
            if di not in used_d:
                self.tracks.append(Track(self._next_id, x, y, 0.0, 0.0, r, 1, t_s,
                                         [(t_s, x, y)]))
                self._next_id += 1
        self.tracks = [tr for tr in self.tracks if t_s - tr.last_t <= cfg.drop_after_s]

    def _refit(self, tr: Track, t_s: float, x: float, y: float) -> None:
        """Keep the track's recent detections; when their least-squares
        velocity and the filter's disagree by more than ``manoeuvre_mps``,
        take the fitted one (the person started, stopped or turned)."""
        cfg = self.cfg
        tr.seen.append((t_s, x, y))
        while tr.seen and t_s - tr.seen[0][0] > cfg.fit_window_s + 1e-9:
            tr.seen.pop(0)
        if len(tr.seen) < 3 or t_s - tr.seen[0][0] < cfg.fit_min_span_s - 1e-9:
            return
        a = np.asarray(tr.seen)
        tt = a[:, 0] - a[:, 0].mean()
        den = float(tt @ tt)
        if den <= 1e-9:
            return
        vx = float(tt @ (a[:, 1] - a[:, 1].mean())) / den
        vy = float(tt @ (a[:, 2] - a[:, 2].mean())) / den
        sp = math.hypot(vx, vy)
        if sp > cfg.max_speed_mps:
            vx, vy = vx * cfg.max_speed_mps / sp, vy * cfg.max_speed_mps / sp
        if math.hypot(vx - tr.vx, vy - tr.vy) > cfg.manoeuvre_mps:
            tr.vx, tr.vy = vx, vy

    def obstacles(self) -> np.ndarray:
        """Confirmed tracks as rows (x, y, vx, vy, radius) for the planner / the desk."""
        rows = [(t.x, t.y, t.vx, t.vy, t.r + self.cfg.radius_margin_m)
                for t in self.tracks if t.hits >= self.cfg.confirm_hits]
        return np.array(rows, float).reshape(-1, 5)

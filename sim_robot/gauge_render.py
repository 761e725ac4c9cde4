"""Synthetic pointer-gauge images for the simulator's camera and the meter benchmark.

Qt-free: numpy + OpenCV only.  Angles are degrees clockwise from 12 o'clock as seen
on the upright dial (the convention of the gauge profiles in ``app/resources/gauges``).

* :class:`GaugeSpec` describes one gauge face (range, span, ticks, colours, pointer).
* :func:`render_dial` draws the upright dial as a square crop (the paper's 300 x 300 input).
* :func:`render_view` places that dial in a cluttered camera frame, seen from a tilted and
  rolled pose, with glare, blur, noise and JPEG artefacts, and returns ground truth.
* :data:`STOCK_SPECS` are the gauges matching the profiles in ``app/resources/gauges``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import lru_cache

import cv2
import numpy as np

from .gauge_draw import SC as _SC
from .gauge_draw import SH as _SH
from .gauge_draw import direction as _dir
from .gauge_draw import p as _p
from .gauge_draw import project as _proj

__all__ = [
    "GaugeSpec",
    "PAPER_TABLE1",
    "STOCK_SPECS",
    "random_spec",
    "render_dial",
    "render_view",
    "stock_spec",
]

# Table 1 of seed 000 (value, x, y) on the paper's 300 x 300 template dial.
PAPER_TABLE1: tuple[tuple[float, float, float], ...] = (
    (0.0, 75.69, 215.91), (0.1, 72.29, 211.93), (0.2, 66.13, 203.46), (0.3, 60.12, 192.84),
    (0.4, 55.45, 181.56), (0.5, 52.56, 171.50), (0.6, 50.55, 159.45), (0.7, 50.02, 147.25),
    (0.8, 50.97, 135.08), (0.9, 53.41, 123.12), (1.0, 56.64, 113.16), (1.1, 61.71, 102.05),
    (1.2, 68.08, 91.64), (1.3, 75.69, 82.09), (1.4, 83.09, 74.69), (1.5, 92.04, 67.08),
    (1.6, 103.05, 60.71), (1.7, 114.16, 55.64), (1.8, 125.81, 51.97), (1.9, 136.08, 49.97),
    (2.0, 148.25, 49.02), (2.1, 160.45, 49.55), (2.2, 170.79, 51.19), (2.3, 182.56, 54.45),
    (2.4, 193.84, 59.12), (2.5, 204.46, 65.13), (2.6, 214.28, 72.40), (2.7, 223.14, 80.80),
    (2.8, 230.90, 90.22), (2.9, 236.60, 99.00), (3.0, 242.72, 111.54), (3.1, 246.13, 121.44),
    (3.2, 248.77, 133.36), (3.3, 249.94, 145.51), (3.4, 249.62, 157.72), (3.5, 248.16, 168.08),
    (3.6, 245.11, 179.90), (3.7, 240.63, 191.26), (3.8, 234.80, 201.99), (3.9, 227.71, 211.93),
    (4.0, 220.71, 219.71),
)


def _table_geometry(table) -> tuple[float, float, float, list[tuple[float, float]]]:
    """Least-squares circle through the table's tick points; returns (m, n, r, [(v, angle)])."""
    pts = np.array([(x, y) for _, x, y in table], dtype=float)
    a = np.column_stack([2 * pts[:, 0], 2 * pts[:, 1], np.ones(len(pts))])
    b = (pts**2).sum(axis=1)
    (m, n, c), *_ = np.linalg.lstsq(a, b, rcond=None)
    r = math.sqrt(c + m * m + n * n)
    ticks = []
    for v, x, y in table:
        ang = math.degrees(math.atan2(x - m, -(y - n)))
        ticks.append((float(v), ang))
    return m, n, r, ticks


@dataclass(frozen=True)
class GaugeSpec:
    """One gauge face.  Radii are fractions of the crop size (the dial spans 0.49)."""

    name: str = "gauge"
    unit: str = "MPa"
    min_value: float = 0.0
    max_value: float = 4.0
    min_angle_deg: float = -135.0
    max_angle_deg: float = 135.0
    major_step: float = 0.5
    minor_per_major: int = 5
    label_every: int = 1  # numeral on every n-th major tick
    face_bgr: tuple[int, int, int] = (240, 242, 244)
    bezel_bgr: tuple[int, int, int] = (40, 40, 40)
    ink_bgr: tuple[int, int, int] = (25, 25, 25)
    pointer_bgr: tuple[int, int, int] = (20, 20, 20)
    pointer_style: str = "needle"  # needle | arrow | lance
    pointer_len: float = 0.38
    pointer_width: float = 0.028
    tail_len: float = 0.08
    hub_radius: float = 0.05
    face_radius: float = 0.45
    tick_outer: float = 0.40
    major_inner: float = 0.34
    minor_inner: float = 0.37
    numeral_radius: float = 0.28
    numerals: bool = True
    normal_band: tuple[float, float] | None = None  # drawn as a green arc
    table: tuple[tuple[float, float], ...] | None = field(default=None)  # (value, angle)
    table_xy: tuple[tuple[float, float, float], ...] | None = None  # (value, x, y) template
    profile_file: str | None = None

    def angle_of(self, value: float) -> float:
        """Pointer angle (deg, clockwise from 12 o'clock) for ``value`` on the upright dial."""
        if self.table:
            vals = np.array([t[0] for t in self.table])
            angs = np.array([t[1] for t in self.table])
            return float(np.interp(value, vals, angs))
        f = (value - self.min_value) / (self.max_value - self.min_value)
        return self.min_angle_deg + f * (self.max_angle_deg - self.min_angle_deg)

    def tick_list(self) -> list[tuple[float, float, bool]]:
        """(value, angle, is_major) for every tick."""
        if self.table:
            out = []
            for v, a in self.table:
                k = round((v - self.min_value) / self.major_step, 6)
                out.append((v, a, abs(k - round(k)) < 1e-6))
            return out
        n_major = round((self.max_value - self.min_value) / self.major_step)
        n = n_major * self.minor_per_major
        out = []
        for i in range(n + 1):
            v = self.min_value + i * self.major_step / self.minor_per_major
            out.append((v, self.angle_of(v), i % self.minor_per_major == 0))
        return out

    def profile(self) -> dict:
        """The angle-form gauge profile that describes this face."""
        p = {
            "name": self.name,
            "unit": self.unit,
            "min_value": self.min_value,
            "max_value": self.max_value,
            "min_angle_deg": round(self.angle_of(self.min_value), 3),
            "max_angle_deg": round(self.angle_of(self.max_value), 3),
        }
        if self.normal_band:
            p["normal_min"], p["normal_max"] = self.normal_band
        if self.table_xy:
            p["dial_size"] = 300
            p["ticks"] = [{"value": v, "x": x, "y": y} for v, x, y in self.table_xy]
        return p


def _paper_spec() -> GaugeSpec:
    m, n, r, ticks = _table_geometry(PAPER_TABLE1)
    s = r / 300.0  # tick ring radius as fraction of crop size
    return GaugeSpec(
        name="paper_0_4mpa", unit="MPa", min_value=0.0, max_value=4.0,
        min_angle_deg=ticks[0][1], max_angle_deg=ticks[-1][1], major_step=0.5,
        minor_per_major=5, tick_outer=s + 0.035, major_inner=s - 0.035, minor_inner=s - 0.01,
        numeral_radius=s - 0.085, pointer_len=s + 0.03, table=tuple(ticks), table_xy=PAPER_TABLE1,
        profile_file="paper_0_4mpa.json", normal_band=(0.5, 3.0),
    )


STOCK_SPECS: tuple[GaugeSpec, ...] = (
    _paper_spec(),
    GaugeSpec(name="pressure_0_1p6mpa", unit="MPa", min_value=0.0, max_value=1.6,
              major_step=0.2, minor_per_major=4, pointer_style="arrow",
              pointer_bgr=(30, 30, 170), bezel_bgr=(150, 150, 155),
              profile_file="pressure_0_1p6mpa.json", normal_band=(0.2, 1.2)),
    GaugeSpec(name="pressure_0_10bar", unit="bar", min_value=0.0, max_value=10.0,
              min_angle_deg=-120.0, max_angle_deg=120.0, major_step=1.0, minor_per_major=5,
              pointer_style="lance", face_bgr=(225, 238, 245),
              profile_file="pressure_0_10bar.json", normal_band=(2.0, 8.0)),
    GaugeSpec(name="compound_m0p1_0p9mpa", unit="MPa", min_value=-0.1, max_value=0.9,
              major_step=0.1, minor_per_major=5, pointer_bgr=(20, 20, 120),
              profile_file="compound_m0p1_0p9mpa.json", normal_band=(0.0, 0.6)),
)


def stock_spec(name: str) -> GaugeSpec:
    for s in STOCK_SPECS:
        if s.name == name:
            return s
    raise KeyError(name)


def random_spec(rng: np.random.Generator) -> GaugeSpec:
    """A randomly styled gauge: one of the stock ranges, span 180-270 deg, varied look."""
    base = STOCK_SPECS[int(rng.integers(1, len(STOCK_SPECS)))]
    span = float(rng.choice([180.0, 220.0, 240.0, 270.0]))
    face = tuple(int(v) for v in rng.integers(215, 252, 3))
    bezel = tuple(int(v) for v in (rng.integers(20, 60, 3) if rng.random() < 0.5
                                   else rng.integers(120, 180, 3)))
    ptr = [(20, 20, 20), (25, 25, 160), (110, 40, 20), (30, 30, 30)][int(rng.integers(0, 4))]
    return replace(
        base, min_angle_deg=-span / 2, max_angle_deg=span / 2, face_bgr=face,
        bezel_bgr=bezel, pointer_bgr=ptr,
        pointer_style=["needle", "arrow", "lance"][int(rng.integers(0, 3))],
        pointer_width=float(rng.uniform(0.022, 0.034)), hub_radius=float(rng.uniform(0.04, 0.06)),
        tail_len=float(rng.uniform(0.0, 0.1)), numerals=bool(rng.random() < 0.85),
        label_every=int(rng.choice([1, 2])) if base.name != "pressure_0_1p6mpa" else 1,
        profile_file=None,
    )


def _fmt(v: float) -> str:
    s = f"{v:.2f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


@lru_cache(maxsize=8)
def _radius2(size: int) -> np.ndarray:
    """Squared distance of every pixel from the crop centre (cached per size)."""
    c = size / 2.0
    yy, xx = np.mgrid[0:size, 0:size].astype(np.float32)
    out = (xx - c) ** 2 + (yy - c) ** 2
    out.flags.writeable = False
    return out


def render_dial(spec: GaugeSpec, value: float, size: int = 300) -> np.ndarray:
    """Upright dial showing ``value`` as a ``size`` x ``size`` BGR uint8 crop."""
    img = np.full((size, size, 3), 255, np.uint8)
    c = size / 2.0
    lw = max(1, round(size / 150))
    # bezel and face (slight radial shading on the face)
    cv2.circle(img, _p(c, c), int(0.49 * size * _SC), spec.bezel_bgr, -1, cv2.LINE_AA, _SH)
    rr2 = _radius2(size) / (spec.face_radius * size) ** 2
    face = np.array(spec.face_bgr, np.float32)[None, None, :] * (1.0 - 0.06 * rr2[..., None])
    fmask = np.zeros((size, size), np.uint8)
    cv2.circle(fmask, _p(c, c), int(spec.face_radius * size * _SC), 255, -1, cv2.LINE_AA, _SH)
    a = fmask.astype(np.float32)[..., None] / 255.0
    img = (img * (1 - a) + face * a).astype(np.uint8)
    # bezel highlight ring for chrome bezels
    if sum(spec.bezel_bgr) > 300:
        cv2.circle(img, _p(c, c), int(0.47 * size * _SC), (225, 225, 230), lw, cv2.LINE_AA, _SH)
    # normal band arc
    if spec.normal_band:
        a0 = spec.angle_of(spec.normal_band[0]) - 90
        a1 = spec.angle_of(spec.normal_band[1]) - 90
        rad = int(spec.tick_outer * size + 5 * lw)
        cv2.ellipse(img, (int(c), int(c)), (rad, rad), 0, a0, a1, (60, 170, 60), 2 * lw,
                    cv2.LINE_AA)
    # ticks and numerals
    for _v, ang, major in spec.tick_list():
        dx, dy = _dir(ang)
        r0 = (spec.major_inner if major else spec.minor_inner) * size
        r1 = spec.tick_outer * size
        th = (2 if major else 1) * lw
        cv2.line(img, _p(c + dx * r0, c + dy * r0), _p(c + dx * r1, c + dy * r1), spec.ink_bgr,
                 th, cv2.LINE_AA, _SH)
    if spec.numerals:
        fs = size / 600.0
        majors = [t for t in spec.tick_list() if t[2]]
        for i, (v, ang, _) in enumerate(majors):
            if i % spec.label_every:
                continue
            dx, dy = _dir(ang)
            txt = _fmt(v)
            (tw, th_), _ = cv2.getTextSize(txt, cv2.FONT_HERSHEY_SIMPLEX, fs, lw)
            x = c + dx * spec.numeral_radius * size - tw / 2
            y = c + dy * spec.numeral_radius * size + th_ / 2
            cv2.putText(img, txt, (int(x), int(y)), cv2.FONT_HERSHEY_SIMPLEX, fs, spec.ink_bgr,
                        lw, cv2.LINE_AA)
    (tw, _), _ = cv2.getTextSize(spec.unit, cv2.FONT_HERSHEY_SIMPLEX, size / 500, lw)
    cv2.putText(img, spec.unit, (int(c - tw / 2), int(c + 0.2 * size)),
                cv2.FONT_HERSHEY_SIMPLEX, size / 500, spec.ink_bgr, lw, cv2.LINE_AA)
    _draw_pointer(img, spec, spec.angle_of(value), size)
    return img


def _draw_pointer(img: np.ndarray, spec: GaugeSpec, angle: float, size: int) -> None:
    c = size / 2.0
    dx, dy = _dir(angle)
    nx, ny = -dy, dx
    L = spec.pointer_len * size
    w = spec.pointer_width * size / 2
    T = spec.tail_len * size
    if spec.pointer_style == "arrow":
        pts = [(0, -w * 0.8), (L - 4 * w, -w * 0.5), (L - 4 * w, -w * 1.8), (L, 0),
               (L - 4 * w, w * 1.8), (L - 4 * w, w * 0.5), (0, w * 0.8), (-T, w), (-T, -w)]
    elif spec.pointer_style == "lance":
        pts = [(0, -w * 1.3), (0.55 * L, -w * 1.1), (L, 0), (0.55 * L, w * 1.1), (0, w * 1.3),
               (-T, w * 1.3), (-T, -w * 1.3)]
    else:  # needle
        pts = [(0, -w), (L, -0.12 * w), (L, 0.12 * w), (0, w), (-T, w * 1.1), (-T, -w * 1.1)]
    poly = np.array([_p(c + dx * s + nx * t, c + dy * s + ny * t) for s, t in pts], np.int32)
    cv2.fillPoly(img, [poly], spec.pointer_bgr, cv2.LINE_AA, _SH)
    cv2.circle(img, _p(c, c), int(spec.hub_radius * size * _SC), spec.pointer_bgr, -1,
               cv2.LINE_AA, _SH)


# ----------------------------------------------------------------------------- frames


def _clutter(rng: np.random.Generator, w: int, h: int, kind: str) -> np.ndarray:
    if kind == "plain":
        return np.full((h, w, 3), 128, np.uint8)
    base = rng.uniform(60, 190, 3)
    grad = np.linspace(0.75, 1.15, h, dtype=np.float32)[:, None, None]
    img = np.broadcast_to(base[None, None, :] * grad, (h, w, 3)).astype(np.float32).copy()
    for _ in range(int(rng.integers(1, 4))):  # cabinets / panels
        x0, y0 = int(rng.integers(0, w)), int(rng.integers(0, h))
        x1, y1 = x0 + int(rng.integers(40, 250)), y0 + int(rng.integers(40, 250))
        col = rng.uniform(40, 220, 3)
        cv2.rectangle(img, (x0, y0), (x1, y1), col.tolist(), -1)
        cv2.rectangle(img, (x0, y0), (x1, y1), (col * 0.6).tolist(), 2)
    for _ in range(int(rng.integers(2, 6))):  # pipes with cylindrical shading
        t = int(rng.integers(20, 80))
        col = rng.uniform(50, 230, 3)
        prof = (0.45 + 0.75 * np.cos(np.linspace(-1.3, 1.3, t)) ** 2)[:, None] * col[None, :]
        prof = np.clip(prof, 0, 255)
        if rng.random() < 0.5:
            y0 = int(rng.integers(-t // 2, h - t // 2))
            ys = np.arange(y0, y0 + t)
            ok = (ys >= 0) & (ys < h)
            img[ys[ok], :, :] = prof[ok][:, None, :]
            for _ in range(int(rng.integers(0, 3))):  # flanges
                fx = int(rng.integers(0, w))
                cv2.rectangle(img, (fx, y0 - 8), (fx + 14, y0 + t + 8), (col * 0.7).tolist(), -1)
        else:
            x0 = int(rng.integers(-t // 2, w - t // 2))
            xs = np.arange(x0, x0 + t)
            ok = (xs >= 0) & (xs < w)
            img[:, xs[ok], :] = prof[ok][None, :, :]
    for _ in range(int(rng.integers(0, 2))):  # hand-wheel valve: a circular distractor
        cx, cy, r = int(rng.integers(0, w)), int(rng.integers(0, h)), int(rng.integers(25, 70))
        cv2.circle(img, (cx, cy), r, (30, 30, 170), 7, cv2.LINE_AA)
        for k in range(3):
            a = k * math.pi / 3 + rng.uniform(0, 1)
            cv2.line(img, (int(cx - r * math.cos(a)), int(cy - r * math.sin(a))),
                     (int(cx + r * math.cos(a)), int(cy + r * math.sin(a))), (30, 30, 150), 5)
    img += rng.normal(0, 4, img.shape).astype(np.float32)
    img = np.clip(img, 0, 255).astype(np.uint8)
    for _ in range(int(rng.integers(0, 3))):  # labels
        x0, y0 = int(rng.integers(0, w - 60)), int(rng.integers(10, h))
        cv2.rectangle(img, (x0, y0 - 18), (x0 + 70, y0 + 4), (235, 235, 235), -1)
        cv2.putText(img, f"V-{int(rng.integers(0, 99)):02d}", (x0 + 4, y0),
                    cv2.FONT_HERSHEY_SIMPLEX,
                    0.6, (20, 20, 20), 2)
    return img


def _rotation(tilt_deg: float, tilt_axis_deg: float, roll_deg: float) -> np.ndarray:
    ax = math.radians(tilt_axis_deg)
    rv = np.array([math.cos(ax), math.sin(ax), 0.0]) * math.radians(tilt_deg)
    r_tilt, _ = cv2.Rodrigues(rv)
    r_roll, _ = cv2.Rodrigues(np.array([0.0, 0.0, math.radians(roll_deg)]))
    return r_roll @ r_tilt


def render_view(
    spec: GaugeSpec,
    value: float,
    *,
    frame_size: tuple[int, int] = (640, 480),
    fill: float = 0.6,
    tilt_deg: float = 0.0,
    tilt_axis_deg: float = 0.0,
    roll_deg: float = 0.0,
    glare: float = 0.0,
    noise_sigma: float = 0.0,
    blur_px: float = 0.0,
    motion_blur_px: float = 0.0,
    jpeg_quality: int | None = None,
    rng: np.random.Generator | None = None,
    background: str = "clutter",
    glare_on_pointer: bool = False,
    focal_px: float = 1400.0,
    offset_frac: tuple[float, float] | None = None,
) -> tuple[np.ndarray, dict]:
    """The dial seen by a camera: ``(BGR frame, ground truth)``.

    ``fill`` is the dial's outer diameter as a fraction of the frame's shorter side.  The
    dial plane is tilted by ``tilt_deg`` about an in-plane axis at ``tilt_axis_deg`` and the
    camera rolled by ``roll_deg``; a pinhole camera of focal length ``focal_px`` gives the
    homography.  ``glare`` (0..1) is the peak opacity of a white highlight on the glass.
    """
    rng = rng if rng is not None else np.random.default_rng()
    w, h = frame_size
    short = min(w, h)
    size = int(round(fill * short / 0.98))
    size += size % 2
    dial = render_dial(spec, value, size).astype(np.float32)
    c = size / 2.0
    if glare > 0:
        if glare_on_pointer:
            dx, dy = _dir(spec.angle_of(value))
            d = rng.uniform(0.12, 0.3) * size
            gx, gy = c + dx * d, c + dy * d
        else:
            ga = rng.uniform(0, 2 * math.pi)
            d = rng.uniform(0.05, 0.35) * size
            gx, gy = c + d * math.cos(ga), c + d * math.sin(ga)
        sx, sy = rng.uniform(0.06, 0.16, 2) * size
        th = rng.uniform(0, math.pi)
        yy, xx = np.mgrid[0:size, 0:size].astype(np.float32)
        u = (xx - gx) * math.cos(th) + (yy - gy) * math.sin(th)
        v = -(xx - gx) * math.sin(th) + (yy - gy) * math.cos(th)
        alpha = glare * np.exp(-0.5 * ((u / sx) ** 2 + (v / sy) ** 2))
        inside = (np.hypot(xx - c, yy - c) < 0.47 * size).astype(np.float32)
        alpha = (alpha * inside)[..., None]
        dial = dial * (1 - alpha) + 255.0 * alpha
    dial = np.clip(dial, 0, 255).astype(np.uint8)

    # homography: dial pixel -> frame pixel
    if offset_frac is None:
        slack = max(0.0, (short - size * 1.02) / 2)
        off = rng.uniform(-1, 1, 2) * slack * 0.9
    else:
        off = np.array(offset_frac) * short
    cxf, cyf = w / 2 + off[0], h / 2 + off[1]
    rot = _rotation(tilt_deg, tilt_axis_deg, roll_deg)
    k = np.array([[focal_px, 0, cxf], [0, focal_px, cyf], [0, 0, 1.0]])
    t = np.array([0.0, 0.0, focal_px])
    hmat = k @ np.column_stack([rot[:, 0], rot[:, 1], t]) @ np.array(
        [[1, 0, -c], [0, 1, -c], [0, 0, 1.0]])
    frame = _clutter(rng, w, h, background)
    # the gauge's stem below the dial
    stem_w = max(6, int(0.12 * size))
    bot = _proj(hmat, c, size * 0.97)
    cv2.rectangle(frame, (int(bot[0] - stem_w / 2), int(bot[1] - 5)),
                  (int(bot[0] + stem_w / 2), h), (90, 110, 140), -1)
    warped = cv2.warpPerspective(dial, hmat, (w, h), flags=cv2.INTER_LINEAR)
    mask = np.zeros((size, size), np.uint8)
    cv2.circle(mask, _p(c, c), int(0.49 * size * _SC), 255, -1, cv2.LINE_AA, _SH)
    wm = cv2.warpPerspective(mask, hmat, (w, h), flags=cv2.INTER_LINEAR)
    a = wm.astype(np.float32)[..., None] / 255.0
    out = frame.astype(np.float32) * (1 - a) + warped.astype(np.float32) * a
    if motion_blur_px > 0:
        n = max(2, int(round(motion_blur_px)))
        kern = np.zeros((n, n), np.float32)
        ang = rng.uniform(0, math.pi)
        cv2.line(kern, (int(n / 2 - math.cos(ang) * n / 2), int(n / 2 - math.sin(ang) * n / 2)),
                 (int(n / 2 + math.cos(ang) * n / 2), int(n / 2 + math.sin(ang) * n / 2)), 1.0, 1)
        kern /= max(kern.sum(), 1e-6)
        out = cv2.filter2D(out, -1, kern)
    if blur_px > 0:
        out = cv2.GaussianBlur(out, (0, 0), blur_px)
    if noise_sigma > 0:
        out = out + rng.normal(0, noise_sigma, out.shape).astype(np.float32)
    img = np.clip(out, 0, 255).astype(np.uint8)
    if jpeg_quality is not None:
        ok, buf = cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, int(jpeg_quality)])
        img = cv2.imdecode(buf, cv2.IMREAD_COLOR)
    rim = np.array([_proj(hmat, c + spec.face_radius * size * math.cos(q),
                          c + spec.face_radius * size * math.sin(q))
                    for q in np.linspace(0, 2 * math.pi, 72, endpoint=False)], np.float32)
    (ex, ey), (ea, eb), eang = cv2.fitEllipse(rim)
    dx, dy = _dir(spec.angle_of(value))
    tip = _proj(hmat, c + dx * spec.pointer_len * size, c + dy * spec.pointer_len * size)
    truth = {
        "value": float(value),
        "angle_deg": spec.angle_of(value),
        "centre_xy": list(_proj(hmat, c, c)),
        "tip_xy": list(tip),
        "face_ellipse": [float(ex), float(ey), float(ea), float(eb), float(eang)],
        "homography": hmat.tolist(),
        "fill": fill, "tilt_deg": tilt_deg, "tilt_axis_deg": tilt_axis_deg,
        "roll_deg": roll_deg, "glare": glare,
        "full_scale": spec.max_value - spec.min_value,
    }
    return img, truth

"""Camera frames of styled gauges (:mod:`sim_robot.gauge_styles`) with full ground truth.

Qt-free: numpy + OpenCV only.  The gauge hangs on a planar wall (the *plane*); a pinhole
camera at :class:`Pose` sees the plane through a homography, then the frame gets what a
real camera adds (:class:`Look`): barrel lens distortion, a lighting gradient, vignetting,
a shadow, glare spots and streaks on the glass (one may be laid across the needle), blur,
noise and JPEG.

:func:`render_sample` draws one benchmark image at a level (``clean``: upright 300 x 300
crops; ``field``: 320 x 320 crops, mild pose and optics; ``hard``: whole 640 x 480 frames
with clutter, other gauges, strong pose, lens and glare).  :func:`compose` is the general
form, used for re-visited inspection points with a fixed background.

Ground truth (a dict): ``value``; ``profile`` (the angle-form profile dict, with
``"needle": "two-ended"`` and ``"ignore_colour": "red"`` where the face has them);
``pivot_xy``, ``min_mark_xy``, ``max_mark_xy`` in image pixels (after lens distortion);
``homography`` (3 x 3, upright dial crop pixels -> image pixels before lens distortion) and
``lens_k`` (the distortion, see :func:`distort_point`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import cv2
import numpy as np

from . import gauge_atlas, gauge_foundry, gauge_foundry_glass
from .gauge_dial import draw_dial, outline_mask
from .gauge_draw import project as _proj
from .gauge_render import _clutter
from .gauge_styles import DialStyle, random_style, random_value

__all__ = ["LEVELS", "Look", "Pose", "background", "compose", "distort_point", "own_backdrops",
           "render_sample"]

LEVELS = ("clean", "field", "hard")


@dataclass(frozen=True)
class Pose:
    """Camera pose relative to the gauge: ``fill`` is the dial's diameter over the frame's
    shorter side at zoom 1; ``offset`` moves the dial's centre (fractions of the shorter
    side); the dial plane is tilted about an in-plane axis and the camera rolled."""

    fill: float = 0.6
    offset: tuple[float, float] = (0.0, 0.0)
    tilt_deg: float = 0.0
    tilt_axis_deg: float = 0.0
    roll_deg: float = 0.0
    zoom: float = 1.0
    focal_px: float = 1400.0


@dataclass(frozen=True)
class Look:
    """What the optics and the light add.  ``lens_k`` > 0 is barrel distortion."""

    lens_k: float = 0.0
    light: float = 0.0  # depth of a linear lighting gradient (0..1)
    light_angle_deg: float = 0.0
    shadow: float = 0.0  # darkness of a soft shadow edge across the gauge (0..1)
    glare: float = 0.0  # peak opacity of a glare spot on the glass
    glare_on_needle: bool = False
    streaks: int = 0  # thin glare streaks across the glass
    streak_on_needle: bool = False  # one more streak, laid across the needle
    vignette: float = 0.0  # darkening toward the frame's corners (0..1)
    blur_px: float = 0.0
    motion_blur_px: float = 0.0
    noise_sigma: float = 0.0
    jpeg_quality: int | None = None


# ----------------------------------------------------------------------------- lens


def distort_point(x: float, y: float, k: float, w: int, h: int) -> tuple[float, float]:
    """Where an undistorted image point lands in the distorted image.

    The model: an undistorted point p_u = c + (p_d - c)(1 + k r_d^2), r_d the distorted
    distance from the frame centre c over the half-diagonal; solved for p_d by fixed point.
    """
    if k == 0:
        return float(x), float(y)
    cx, cy, s = w / 2.0, h / 2.0, math.hypot(w, h) / 2.0
    ux, uy = (x - cx) / s, (y - cy) / s
    ru = math.hypot(ux, uy)
    rd = ru
    for _ in range(30):
        rd = ru / (1 + k * rd * rd)
    f = rd / ru if ru > 0 else 1.0
    return float(cx + ux * f * s), float(cy + uy * f * s)


def _distort(img: np.ndarray, k: float) -> np.ndarray:
    if k == 0:
        return img
    h, w = img.shape[:2]
    cx, cy, s = w / 2.0, h / 2.0, math.hypot(w, h) / 2.0
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    dx, dy = (xx - cx) / s, (yy - cy) / s
    f = 1 + k * (dx * dx + dy * dy)
    return cv2.remap(img, cx + dx * f * s, cy + dy * f * s, cv2.INTER_LINEAR,
                     borderMode=cv2.BORDER_REFLECT)


# ----------------------------------------------------------------------------- backgrounds


def background(rng: np.random.Generator, w: int, h: int, kind: str,
               family: str = "plant") -> np.ndarray:
    """A backdrop: ``plain``, ``wall`` (painted concrete with bolts and a conduit),
    ``pipes`` (cabinets, pipes, valves, labels), ``gauges`` (pipes and other gauges), the
    ``marine`` family's own: ``tiles`` (a glazed tile wall with grout lines) and ``panel`` (a
    control panel with lamps, switches and a cable duct), the ``nordic`` family's own:
    ``brick`` (a brick wall in running bond) and ``cladding`` (corrugated metal sheet with
    rivets), or the held-out family's own (:func:`sim_robot.gauge_atlas.backdrop`): ``rack``
    (an instrument rack with tubing, valves, tags and other gauges of ``family``) and
    ``grating`` (steel grating behind beams), or the ``foundry`` family's own
    (:func:`sim_robot.gauge_foundry_glass.backdrop`): ``skid`` (pipework, flanges and a
    hazard-striped rail, with other gauges of ``family``) and ``bokeh`` (a plant out of
    focus)."""
    if kind in ("skid", "bokeh"):
        img = gauge_foundry_glass.backdrop(rng, w, h, kind)
        return _other_gauges(img, rng, family, 1, 3) if kind == "skid" else img
    if kind in ("rack", "grating"):
        img = gauge_atlas.backdrop(rng, w, h, kind)
        return _other_gauges(img, rng, family, 1, 3) if kind == "rack" else img
    if kind == "brick":
        return _brick(rng, w, h)
    if kind == "cladding":
        return _cladding(rng, w, h)
    if kind == "tiles":
        return _tiles(rng, w, h)
    if kind == "panel":
        return _panel(rng, w, h)
    if kind == "plain":
        return np.full((h, w, 3), int(rng.integers(90, 170)), np.uint8)
    if kind == "wall":
        base = rng.uniform(90, 210, 3)
        small = rng.normal(0, 1, (h // 16 + 1, w // 16 + 1)).astype(np.float32)
        tex = cv2.resize(small, (w, h), interpolation=cv2.INTER_CUBIC) * 6
        img = base[None, None, :] + tex[..., None] + rng.normal(0, 5, (h, w, 1))
        img = img.astype(np.float32)
        y0 = int(rng.integers(0, h))
        cv2.rectangle(img, (0, y0), (w, y0 + int(rng.integers(8, 20))), (base * 0.7).tolist(), -1)
        for _ in range(int(rng.integers(2, 8))):
            cv2.circle(img, (int(rng.integers(0, w)), int(rng.integers(0, h))), 4,
                       (base * 0.5).tolist(), -1, cv2.LINE_AA)
        return np.clip(img, 0, 255).astype(np.uint8)
    img = _clutter(rng, w, h, "clutter")
    return _other_gauges(img, rng, family, 1, 4) if kind == "gauges" else img


def _other_gauges(img: np.ndarray, rng: np.random.Generator, family: str, lo: int,
                  hi: int) -> np.ndarray:
    """``lo`` to ``hi - 1`` other gauges of ``family`` drawn onto the backdrop ``img``."""
    h, w = img.shape[:2]
    for _ in range(int(rng.integers(lo, hi))):
        st = random_style(family, rng)
        s = int(rng.integers(60, max(61, min(w, h) // 3)))
        dial, _ = draw_dial(st, random_value(st, rng), s)
        x, y = int(rng.integers(0, w - s)), int(rng.integers(0, h - s))
        a = outline_mask(st, s)[..., None].astype(np.float32) / 255
        roi = img[y:y + s, x:x + s].astype(np.float32)
        img[y:y + s, x:x + s] = (roi * (1 - a) + dial * a).astype(np.uint8)
    return img


def _tiles(rng: np.random.Generator, w: int, h: int) -> np.ndarray:
    tile = rng.uniform(150, 235, 3)
    grout = tile * rng.uniform(0.45, 0.7)
    img = np.empty((h, w, 3), np.float32)
    img[:] = grout
    side = int(rng.integers(40, 90))
    for y in range(0, h, side):
        for x in range(0, w, side):
            shade = tile * rng.uniform(0.93, 1.05)
            cv2.rectangle(img, (x + 2, y + 2), (x + side - 3, y + side - 3), shade.tolist(), -1)
    img += rng.normal(0, 3, img.shape).astype(np.float32)
    return np.clip(img, 0, 255).astype(np.uint8)


def _brick(rng: np.random.Generator, w: int, h: int) -> np.ndarray:
    mortar = rng.uniform(150, 200) * np.array([0.95, 1.0, 1.02])
    brick = np.array([rng.uniform(40, 70), rng.uniform(60, 90), rng.uniform(130, 175)])
    img = np.empty((h, w, 3), np.float32)
    img[:] = mortar
    bh = int(rng.integers(18, 34))
    bw = int(bh * rng.uniform(2.2, 2.8))
    for row, y in enumerate(range(0, h, bh)):
        for x in range(-(bw // 2) * (row % 2), w, bw):
            shade = brick * rng.uniform(0.8, 1.15)
            cv2.rectangle(img, (x + 2, y + 2), (x + bw - 2, y + bh - 2), shade.tolist(), -1)
    img += rng.normal(0, 6, img.shape).astype(np.float32)
    return np.clip(img, 0, 255).astype(np.uint8)


def _cladding(rng: np.random.Generator, w: int, h: int) -> np.ndarray:
    base = rng.uniform(120, 190) * np.array([1.0, 1.0, 0.97])
    period = float(rng.uniform(18, 36))
    xx = np.arange(w, dtype=np.float32)
    ridge = 1.0 + 0.18 * np.sin(2 * np.pi * xx / period)
    img = np.empty((h, w, 3), np.float32)
    img[:] = base[None, None, :] * ridge[None, :, None]
    for y in range(int(rng.integers(20, 60)), h, int(rng.integers(120, 200))):  # rivet rows
        for x in range(int(period / 4), w, int(2 * period)):
            cv2.circle(img, (x, y), 3, (base * 0.55).tolist(), -1, cv2.LINE_AA)
    img += rng.normal(0, 4, img.shape).astype(np.float32)
    return np.clip(img, 0, 255).astype(np.uint8)


def _panel(rng: np.random.Generator, w: int, h: int) -> np.ndarray:
    base = rng.uniform(70, 130, 3)
    img = np.empty((h, w, 3), np.float32)
    img[:] = base
    lamps = ((40, 40, 200), (40, 180, 40), (30, 190, 230), (220, 220, 220))
    for _ in range(int(rng.integers(6, 16))):  # lamps with bezels, and toggle switches
        x, y = int(rng.integers(0, w)), int(rng.integers(0, h))
        if rng.random() < 0.6:
            cv2.circle(img, (x, y), int(rng.integers(8, 16)), (base * 0.5).tolist(), -1)
            cv2.circle(img, (x, y), int(rng.integers(4, 7)),
                       lamps[int(rng.integers(0, 4))], -1, cv2.LINE_AA)
        else:
            cv2.rectangle(img, (x - 9, y - 14), (x + 9, y + 14), (base * 0.6).tolist(), -1)
            cv2.line(img, (x, y), (x + int(rng.integers(-6, 7)), y - 12), (200, 200, 200), 4)
    y0 = int(rng.integers(0, h))  # a slotted cable duct
    cv2.rectangle(img, (0, y0), (w, y0 + 30), (160, 160, 150), -1)
    for x in range(0, w, 24):
        cv2.rectangle(img, (x, y0 + 4), (x + 8, y0 + 26), (110, 110, 105), -1)
    img += rng.normal(0, 3, img.shape).astype(np.float32)
    return np.clip(img, 0, 255).astype(np.uint8)


# ----------------------------------------------------------------------------- compose


def _rotation(tilt_deg: float, tilt_axis_deg: float, roll_deg: float) -> np.ndarray:
    ax = math.radians(tilt_axis_deg)
    rv = np.array([math.cos(ax), math.sin(ax), 0.0]) * math.radians(tilt_deg)
    r_tilt, _ = cv2.Rodrigues(rv)
    r_roll, _ = cv2.Rodrigues(np.array([0.0, 0.0, math.radians(roll_deg)]))
    return r_roll @ r_tilt


def _glare(dial: np.ndarray, look: Look, angle_deg: float, rng,
           needle_len_px: float = 0.0) -> np.ndarray:
    size = dial.shape[0]
    c = size / 2.0
    out = dial.astype(np.float32)
    yy, xx = np.mgrid[0:size, 0:size].astype(np.float32)
    alpha = np.zeros((size, size), np.float32)
    if look.glare > 0:
        if look.glare_on_needle:
            a = math.radians(angle_deg)
            d = rng.uniform(0.12, 0.3) * size
            gx, gy = c + math.sin(a) * d, c - math.cos(a) * d
        else:
            q, d = rng.uniform(0, 2 * math.pi), rng.uniform(0.05, 0.35) * size
            gx, gy = c + d * math.cos(q), c + d * math.sin(q)
        sx, sy = rng.uniform(0.06, 0.16, 2) * size
        th = rng.uniform(0, math.pi)
        u = (xx - gx) * math.cos(th) + (yy - gy) * math.sin(th)
        v = -(xx - gx) * math.sin(th) + (yy - gy) * math.cos(th)
        alpha = np.maximum(alpha, look.glare * np.exp(-0.5 * ((u / sx) ** 2 + (v / sy) ** 2)))
    for _ in range(look.streaks):  # a thin bright band across the glass
        th = rng.uniform(0, math.pi)
        off = rng.uniform(-0.3, 0.3) * size
        wd = rng.uniform(0.01, 0.03) * size
        dist = (xx - c) * math.cos(th) + (yy - c) * math.sin(th) - off
        alpha = np.maximum(alpha, rng.uniform(0.4, 0.8) * np.exp(-0.5 * (dist / wd) ** 2))
    if look.streak_on_needle:  # a streak through a point of the needle, across it
        a = math.radians(angle_deg)
        d = rng.uniform(0.3, 0.8) * needle_len_px
        px, py = c + math.sin(a) * d, c - math.cos(a) * d
        th = a + rng.uniform(-0.6, 0.6)  # the streak's normal: near the needle's direction
        wd = rng.uniform(0.01, 0.025) * size
        dist = (xx - px) * math.sin(th) - (yy - py) * math.cos(th)
        alpha = np.maximum(alpha, rng.uniform(0.4, 0.75) * np.exp(-0.5 * (dist / wd) ** 2))
    inside = (np.hypot(xx - c, yy - c) < 0.47 * size).astype(np.float32)
    alpha = (alpha * inside)[..., None]
    return out * (1 - alpha) + 255.0 * alpha


def compose(style: DialStyle, value: float, rng: np.random.Generator, *,
            frame_size: tuple[int, int] = (640, 480), pose: Pose = Pose(), look: Look = Look(),
            backdrop: np.ndarray | str = "pipes") -> tuple[np.ndarray, dict]:
    """The gauge on its wall seen by the camera: ``(BGR frame, ground truth)``.

    ``backdrop`` is a kind for :func:`background` or a fixed plane image (twice the frame's
    size, the gauge at its centre) so that re-visits of one point see the same wall.
    """
    w, h = frame_size
    short = min(w, h)
    size = int(round(pose.fill * short / 0.98))
    size += size % 2
    c = size / 2.0
    dial, dt = draw_dial(style, value, size)
    dial = _glare(dial, look, dt["needle_angle_deg"], rng, dt["needle_len_px"])
    plane = (background(rng, 2 * w, 2 * h, backdrop, style.family)
             if isinstance(backdrop, str) else backdrop.copy())
    ph, pw = plane.shape[:2]
    pcx, pcy = pw / 2.0, ph / 2.0
    plane = plane.astype(np.float32)
    # drop shadow, stem, then the dial
    sh = np.zeros((ph, pw), np.float32)
    cv2.circle(sh, (int(pcx + 0.04 * size), int(pcy + 0.05 * size)), int(0.5 * size), 1.0, -1)
    sh = cv2.GaussianBlur(sh, (0, 0), 0.04 * size + 1)
    plane *= (1 - 0.45 * sh)[..., None]
    sw = max(6, int(0.12 * size))
    cv2.rectangle(plane, (int(pcx - sw / 2), int(pcy + 0.45 * size)), (int(pcx + sw / 2), ph),
                  (90, 110, 140), -1)
    x0, y0 = int(pcx - c), int(pcy - c)
    a = outline_mask(style, size).astype(np.float32)[..., None] / 255.0
    roi = plane[y0:y0 + size, x0:x0 + size]
    plane[y0:y0 + size, x0:x0 + size] = roi * (1 - a) + dial * a
    if look.shadow > 0:  # a soft shadow edge (a pipe, the robot) across the gauge
        th = rng.uniform(0, 2 * math.pi)
        yy, xx = np.mgrid[0:ph, 0:pw].astype(np.float32)
        dist = (xx - pcx) * math.cos(th) + (yy - pcy) * math.sin(th) - rng.uniform(-0.2, 0.3) * size
        z = np.clip(-dist / (0.03 * size), -60, 60)
        plane *= (1 - look.shadow / (1 + np.exp(z)))[..., None]
    # homography plane -> frame, and dial crop -> frame
    rot = _rotation(pose.tilt_deg, pose.tilt_axis_deg, pose.roll_deg)
    f = pose.focal_px * pose.zoom
    k = np.array([[f, 0, w / 2 + pose.offset[0] * short], [0, f, h / 2 + pose.offset[1] * short],
                  [0, 0, 1.0]])
    h_plane = k @ np.column_stack([rot[:, 0], rot[:, 1], [0, 0, pose.focal_px]]) @ np.array(
        [[1, 0, -pcx], [0, 1, -pcy], [0, 0, 1.0]])
    h_dial = h_plane @ np.array([[1, 0, pcx - c], [0, 1, pcy - c], [0, 0, 1.0]])
    out = cv2.warpPerspective(np.clip(plane, 0, 255).astype(np.uint8), h_plane, (w, h),
                              flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    out = _finish(out, look, rng)
    truth = _truth(style, dt, h_dial, look.lens_k, w, h)
    return out, truth


def _finish(img: np.ndarray, look: Look, rng) -> np.ndarray:
    h, w = img.shape[:2]
    img = _distort(img, look.lens_k)
    out = img.astype(np.float32)
    if look.light > 0:
        a = math.radians(look.light_angle_deg)
        yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
        t = ((xx - w / 2) * math.cos(a) + (yy - h / 2) * math.sin(a)) / max(w, h)
        out *= (1 + look.light * 2 * t)[..., None]
    if look.vignette > 0:
        yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
        r2 = ((xx - w / 2) ** 2 + (yy - h / 2) ** 2) / ((w / 2) ** 2 + (h / 2) ** 2)
        out *= (1 - look.vignette * r2)[..., None]
    if look.motion_blur_px > 0:
        n = max(2, int(round(look.motion_blur_px)))
        kern = np.zeros((n, n), np.float32)
        q = rng.uniform(0, math.pi)
        cv2.line(kern, (int(n / 2 - math.cos(q) * n / 2), int(n / 2 - math.sin(q) * n / 2)),
                 (int(n / 2 + math.cos(q) * n / 2), int(n / 2 + math.sin(q) * n / 2)), 1.0, 1)
        out = cv2.filter2D(out, -1, kern / max(kern.sum(), 1e-6))
    if look.blur_px > 0:
        out = cv2.GaussianBlur(out, (0, 0), look.blur_px)
    if look.noise_sigma > 0:
        out = out + rng.normal(0, look.noise_sigma, out.shape).astype(np.float32)
    img = np.clip(out, 0, 255).astype(np.uint8)
    if look.jpeg_quality is not None:
        _, buf = cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, int(look.jpeg_quality)])
        img = cv2.imdecode(buf, cv2.IMREAD_COLOR)
    return img


def _truth(style: DialStyle, dt: dict, hmat: np.ndarray, lens_k: float, w: int, h: int) -> dict:
    def to_img(p):
        return list(distort_point(*_proj(hmat, *p), lens_k, w, h))

    return {
        "value": dt["value"], "profile": style.profile(), "family": style.family,
        "style": style.name, "needle_angle_deg": dt["needle_angle_deg"],
        "pivot_xy": to_img(dt["pivot_xy"]), "min_mark_xy": to_img(dt["min_mark_xy"]),
        "max_mark_xy": to_img(dt["max_mark_xy"]), "homography": hmat.tolist(),
        "lens_k": lens_k, "frame_size": [w, h],
        "full_scale": style.max_value - style.min_value,
    }


# ----------------------------------------------------------------------------- levels


_OWN_BACKDROPS = {"marine": ("tiles", "panel"), "nordic": ("brick", "cladding"),
                  gauge_atlas.ATLAS: ("rack", "grating"),
                  gauge_foundry.FOUNDRY: ("skid", "bokeh")}


def own_backdrops(family: str) -> tuple[str, ...] | None:
    """The backdrop kinds of a family that has its own (marine, nordic, atlas, foundry)."""
    return _OWN_BACKDROPS.get(family)


def _level_pose_look(level: str, rng: np.random.Generator,
                     family: str = "plant") -> tuple[tuple, Pose, Look, str]:
    own = _OWN_BACKDROPS.get(family)  # marine, nordic, atlas, foundry: backdrops of their own
    out = _pose_look(level, rng, own)
    if family == gauge_foundry.FOUNDRY:  # photographs: shake, harder JPEG, more noise
        hard = level == "hard"
        out = (out[0], out[1], replace(
            out[2], motion_blur_px=(out[2].motion_blur_px if hard else
                                    float(rng.uniform(0, 2.5)) * bool(rng.random() < 0.4)),
            jpeg_quality=int(rng.integers(35 if hard else 45, 85)),
            noise_sigma=out[2].noise_sigma * float(rng.uniform(1.0, 1.6)),
            vignette=float(rng.uniform(0.05, 0.25))), out[3])
    if family == gauge_atlas.ATLAS:  # glare across the needle, vignetting
        p = 0.35 if level == "field" else 0.6
        out = (out[0], out[1], replace(out[2], streak_on_needle=bool(rng.random() < p),
                                       vignette=float(rng.uniform(0.1, 0.35))), out[3])
    return out


def _pose_look(level: str, rng: np.random.Generator,
               own: tuple[str, ...] | None) -> tuple[tuple, Pose, Look, str]:
    if level == "field":
        fill = float(rng.uniform(0.82, 0.95))
        slack = max(0.0, (1 - fill * 1.04) / 2)
        pose = Pose(fill=fill, offset=tuple(rng.uniform(-1, 1, 2) * slack * 0.9),
                    tilt_deg=float(rng.uniform(0, 20)), tilt_axis_deg=float(rng.uniform(0, 180)),
                    roll_deg=float(rng.uniform(-10, 10)))
        look = Look(lens_k=float(rng.uniform(0, 0.05)), light=float(rng.uniform(0, 0.25)),
                    light_angle_deg=float(rng.uniform(0, 360)), glare=float(rng.uniform(0, 0.5)),
                    streaks=int(rng.random() < 0.25), noise_sigma=float(rng.uniform(1, 5)),
                    blur_px=float(rng.uniform(0, 0.8)), jpeg_quality=int(rng.integers(60, 95)))
        kinds = list(own) if own else ["plain", "wall", "pipes"]
        return (320, 320), pose, look, str(rng.choice(kinds))
    fill = float(rng.uniform(0.4, 0.8))
    slack = max(0.0, (1 - fill * 1.04) / 2)
    pose = Pose(fill=fill, offset=tuple(rng.uniform(-1, 1, 2) * slack * 0.9),
                tilt_deg=float(rng.uniform(0, 35)), tilt_axis_deg=float(rng.uniform(0, 180)),
                roll_deg=float(rng.uniform(-15, 15)))
    look = Look(lens_k=float(rng.uniform(0, 0.15)), light=float(rng.uniform(0, 0.4)),
                light_angle_deg=float(rng.uniform(0, 360)),
                shadow=float(rng.uniform(0.2, 0.5)) if rng.random() < 0.4 else 0.0,
                glare=float(rng.uniform(0.3, 0.7)), glare_on_needle=bool(rng.random() < 0.5),
                streaks=int(rng.integers(0, 3)), noise_sigma=float(rng.uniform(2, 7)),
                motion_blur_px=float(rng.uniform(0, 4)), jpeg_quality=int(rng.integers(50, 90)))
    kinds = list(own) if own else ["wall", "pipes", "gauges"]
    return (640, 480), pose, look, str(rng.choice(kinds))


def render_sample(family: str, level: str, rng: np.random.Generator,
                  style: DialStyle | None = None) -> tuple[np.ndarray, dict]:
    """One benchmark image of a random gauge of ``family`` at ``level``, with ground truth."""
    if level not in LEVELS:
        raise ValueError(f"unknown level {level!r}; one of {', '.join(LEVELS)}")
    style = style or random_style(family, rng)
    value = random_value(style, rng)
    if level == "clean":
        img, dt = draw_dial(style, value, 300)
        return img, _truth(style, dt, np.eye(3), 0.0, 300, 300)
    size, pose, look, kind = _level_pose_look(level, rng, family)
    img, truth = compose(style, value, rng, frame_size=size, pose=pose, look=look, backdrop=kind)
    truth["level"] = level
    return img, truth

"""The dial keypoint network's data (bench/train_keypoints.py): stored samples from
the project's styled gauge generator, and the random training views of them.

A stored sample is a 224 x 224 BGR square around the ground-truth dial (1.6 x its
outer diameter) with its four keypoints (pivot, needle tip, scale min and max end
marks) and whether its scale runs clockwise; :func:`generate` makes them from the
bench's clean, field and hard levels and from *wild* scenes wider than those.
:func:`augment` draws a 128 x 128 view of one as the classical dial finder might crop
it, with light and camera blemishes, and :func:`targets` the Gaussian heatmap targets
of its keypoints.
"""

from __future__ import annotations

import math
import time

import cv2
import numpy as np

from bench.keypoint_net import IN, OUT, K
from sim_robot.gauge_scene import Look, Pose, compose, distort_point, render_sample
from sim_robot.gauge_styles import random_style, random_value

STORE = 224  # stored square around the dial
STORE_FILL = 1.6  # stored side / the dial's outer diameter
FAMILIES = ("plant", "dark", "colour", "process", "heritage", "marine", "nordic")
BACKDROPS = ("plain", "wall", "pipes", "gauges", "tiles", "panel", "brick", "cladding")


# ----------------------------------------------------------------------------- samples


def _dial_circle(truth: dict, size_guess: float | None):
    """The dial's outer circle (centre, radius) in image pixels, and the dial crop size."""
    hm = np.array(truth["homography"], float)
    k = truth["lens_k"]
    w, h = truth["frame_size"]
    if size_guess is None:
        # undistort the pivot, then solve H (c, c) = p for the crop centre c
        px, py = truth["pivot_xy"]
        cx, cy, s = w / 2.0, h / 2.0, math.hypot(w, h) / 2.0
        dx, dy = (px - cx) / s, (py - cy) / s
        f = 1 + k * (dx * dx + dy * dy)
        ux, uy = cx + dx * f * s, cy + dy * f * s
        a, b = hm[0, 0] + hm[0, 1], hm[0, 2]
        e, g = hm[2, 0] + hm[2, 1], hm[2, 2]
        c1 = (b - ux * g) / (ux * e - a)
        a2, b2 = hm[1, 0] + hm[1, 1], hm[1, 2]
        c2 = (b2 - uy * g) / (uy * e - a2)
        size_guess = c1 + c2  # 2 c
    c = size_guess / 2.0
    t = np.linspace(0, 2 * np.pi, 32, endpoint=False)
    pts = []
    for q in t:
        x, y = c + 0.49 * size_guess * math.cos(q), c + 0.49 * size_guess * math.sin(q)
        v = hm @ np.array([x, y, 1.0])
        pts.append(distort_point(v[0] / v[2], v[1] / v[2], k, w, h))
    pts = np.array(pts)
    centre = pts.mean(0)
    return centre, float(np.hypot(*(pts - centre).T).mean()), size_guess


def _tip(truth: dict, style, size: float):
    hm = np.array(truth["homography"], float)
    a = math.radians(truth["needle_angle_deg"])
    L = style.needle_len * size
    x, y = size / 2 + L * math.sin(a), size / 2 - L * math.cos(a)
    v = hm @ np.array([x, y, 1.0])
    w, h = truth["frame_size"]
    return distort_point(v[0] / v[2], v[1] / v[2], truth["lens_k"], w, h)


def _wild(family: str, rng: np.random.Generator):
    """A scene wider than the bench's levels: any backdrop for any family, tilts to 45 deg,
    rolls to 30, the dial filling 30-97 % of the frame, and every blemish of the generator
    (lens, light, shadow, glare and streaks, blur, motion blur, noise, JPEG) at random."""
    style = random_style(family, rng)
    big = rng.random() < 0.35
    w, h = (640, 480) if big else (320, 320)
    fill = float(rng.uniform(0.3, 0.8) if big else rng.uniform(0.6, 0.97))
    slack = max(0.0, (1 - fill * 1.04) / 2)
    pose = Pose(fill=fill, offset=tuple(rng.uniform(-1, 1, 2) * slack * 0.9),
                tilt_deg=float(rng.uniform(0, 45)), tilt_axis_deg=float(rng.uniform(0, 180)),
                roll_deg=float(rng.uniform(-30, 30)))
    look = Look(lens_k=float(rng.uniform(0, 0.12)), light=float(rng.uniform(0, 0.5)),
                light_angle_deg=float(rng.uniform(0, 360)),
                shadow=float(rng.uniform(0.2, 0.6)) if rng.random() < 0.3 else 0.0,
                glare=float(rng.uniform(0, 0.8)), glare_on_needle=bool(rng.random() < 0.4),
                streaks=int(rng.integers(0, 4)), noise_sigma=float(rng.uniform(0, 8)),
                blur_px=float(rng.uniform(0, 1.5)) if rng.random() < 0.5 else 0.0,
                motion_blur_px=float(rng.uniform(0, 4)) if rng.random() < 0.3 else 0.0,
                jpeg_quality=int(rng.integers(35, 95)) if rng.random() < 0.7 else None)
    img, truth = compose(style, random_value(style, rng), rng, frame_size=(w, h), pose=pose,
                         look=look, backdrop=str(rng.choice(BACKDROPS)))
    size = int(round(fill * min(w, h) / 0.98))
    return style, img, truth, float(size + size % 2)


def make_sample(family: str, level: str, rng: np.random.Generator):
    """One stored sample: (224 x 224 BGR crop, 4 x 2 keypoints in it, clockwise flag)."""
    if level == "wild":
        style, img, truth, size = _wild(family, rng)
    else:
        style = random_style(family, rng)
        img, truth = render_sample(family, level, rng, style=style)
        size = 300.0 if level == "clean" else None
    centre, radius, size = _dial_circle(truth, size)
    kps = np.array([truth["pivot_xy"], _tip(truth, style, size), truth["min_mark_xy"],
                    truth["max_mark_xy"]], float)
    side = STORE_FILL * 2 * radius
    s = STORE / side
    m = np.array([[s, 0, STORE / 2 - s * centre[0]], [0, s, STORE / 2 - s * centre[1]]])
    crop = cv2.warpAffine(img, m, (STORE, STORE), flags=cv2.INTER_AREA,
                          borderMode=cv2.BORDER_REPLICATE)
    kp = kps @ m[:, :2].T + m[:, 2]
    return crop, kp.astype(np.float32), style.max_angle_deg > style.min_angle_deg


def generate(counts: dict[str, int], seed: int, families: tuple[str, ...] = FAMILIES,
             minutes: float = 1e9) -> dict[str, np.ndarray]:
    """Samples in a seeded, shuffled order of levels and families (in proportion to
    ``counts``); stops early after ``minutes`` of wall time, keeping what it has."""
    rng = np.random.default_rng(seed)
    order = [lv for lv, n in counts.items() for _ in range(n)]
    order = [order[i] for i in rng.permutation(len(order))]
    imgs, kps, cw, fam = [], [], [], []
    t0 = time.perf_counter()
    for i, level in enumerate(order):
        if time.perf_counter() - t0 > minutes * 60.0:
            print(f"  wall-time cap: stopped after {i} of {len(order)} samples", flush=True)
            break
        f = i % len(families)
        c, k, d = make_sample(families[f], level, rng)
        imgs.append(c)
        kps.append(k)
        cw.append(d)
        fam.append(f)
        if (i + 1) % 250 == 0:
            print(f"  generated {i + 1} samples [{time.perf_counter() - t0:.0f} s]", flush=True)
    return {"img": np.stack(imgs), "kp": np.stack(kps), "cw": np.array(cw),
            "family": np.array(fam)}


# ----------------------------------------------------------------------------- views


def _photometric(out: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Light, colour and camera blemishes on a float BGR crop: gain and offset, gamma, a
    colour cast, a swap of the colour channels or grey, glare (a spot or a streak), blur,
    noise and JPEG."""
    out = out * rng.uniform(0.6, 1.35) + rng.uniform(-40, 40)
    if rng.random() < 0.3:
        out = 255.0 * (np.clip(out, 0, 255) / 255.0) ** rng.uniform(0.6, 1.6)
    if rng.random() < 0.35:  # colour cast
        out = out * rng.uniform(0.75, 1.25, 3).astype(np.float32)
    u = rng.random()
    if u < 0.15:  # other colours of face, print and needle
        out = out[:, :, rng.permutation(3)]
    elif u < 0.25:
        out = np.repeat(out.mean(2, keepdims=True), 3, 2)
    if rng.random() < 0.3:  # glare on the glass: a soft spot or a thin streak
        yy, xx = np.mgrid[0:IN, 0:IN].astype(np.float32)
        th = rng.uniform(0, math.pi)
        gx, gy = rng.uniform(0.2, 0.8, 2) * IN
        d = (xx - gx) * math.cos(th) + (yy - gy) * math.sin(th)
        if rng.random() < 0.5:
            e = -(xx - gx) * math.sin(th) + (yy - gy) * math.cos(th)
            sx, sy = rng.uniform(0.05, 0.2, 2) * IN
            alpha = np.exp(-0.5 * ((d / sx) ** 2 + (e / sy) ** 2))
        else:
            alpha = np.exp(-0.5 * (d / (rng.uniform(0.01, 0.04) * IN)) ** 2)
        alpha = (rng.uniform(0.3, 0.8) * alpha)[..., None]
        out = out * (1 - alpha) + 255.0 * alpha
    if rng.random() < 0.3:
        out = cv2.GaussianBlur(out, (0, 0), rng.uniform(0.3, 1.4))
    if rng.random() < 0.5:
        out = out + rng.normal(0, rng.uniform(1, 8), out.shape).astype(np.float32)
    out = np.clip(out, 0, 255)
    if rng.random() < 0.3:
        q = int(rng.integers(30, 90))
        _, buf = cv2.imencode(".jpg", out.astype(np.uint8), [cv2.IMWRITE_JPEG_QUALITY, q])
        out = cv2.imdecode(buf, cv2.IMREAD_COLOR).astype(np.float32)
    return out.astype(np.float32)


def augment(img: np.ndarray, kp: np.ndarray, cw: bool, rng: np.random.Generator):
    """A random 128 x 128 view of a stored sample: the dial finder's imperfect crop (side
    0.85-1.5 x the dial's diameter, shifted by up to 10 %, turned by up to 35 deg), seen
    through a small perspective warp (corners moved by up to 5 % of the side), with the
    blemishes of :func:`_photometric`."""
    diam = STORE / STORE_FILL
    side = diam * rng.uniform(0.85, 1.5)
    shift = rng.uniform(-0.1, 0.1, 2) * side
    rot = math.radians(rng.uniform(-35, 35))
    cx, cy = STORE / 2 + shift[0], STORE / 2 + shift[1]
    corners = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], np.float32) * side / 2
    rm = np.array([[math.cos(rot), -math.sin(rot)], [math.sin(rot), math.cos(rot)]])
    src = corners @ rm.T + [cx, cy]
    src = src + rng.uniform(-0.05, 0.05, (4, 2)) * side if rng.random() < 0.6 else src
    dst = np.array([[0, 0], [IN, 0], [IN, IN], [0, IN]], np.float32)
    m = cv2.getPerspectiveTransform(src.astype(np.float32), dst)
    if not cw:  # canonical clockwise scale: mirror left-right
        m = np.array([[-1, 0, IN - 1.0], [0, 1, 0], [0, 0, 1]]) @ m
    out = cv2.warpPerspective(img, m, (IN, IN), flags=cv2.INTER_AREA,
                              borderMode=cv2.BORDER_REPLICATE)
    k = cv2.perspectiveTransform(kp.reshape(-1, 1, 2).astype(np.float64), m).reshape(-1, 2)
    return _photometric(out.astype(np.float32), rng), k


def targets(kp: np.ndarray, sigma: float = 0.8) -> np.ndarray:
    """Gaussian target distributions on the 32 x 32 grid (each sums to 1)."""
    g = (np.arange(OUT) + 0.5)
    t = np.zeros((K, OUT, OUT), np.float32)
    for j in range(K):
        x, y = kp[j] * OUT / IN
        e = np.exp(-0.5 * ((g[None, :] - x) ** 2 + (g[:, None] - y) ** 2) / sigma ** 2)
        if e.sum() < 1e-6:  # off the grid: nearest cell
            e[int(np.clip(y, 0, OUT - 1)), int(np.clip(x, 0, OUT - 1))] = 1.0
        t[j] = e / e.sum()
    return t

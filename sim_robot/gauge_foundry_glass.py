"""The ``foundry`` family's glass, shadows and backdrops.

Qt-free: numpy + OpenCV only.  What lies between the face and the camera in a real
gauge: the needle's soft shadow on the face, the glass that mirrors the room and a window,
and in glycerine-filled cases the fill's meniscus under the top of the case and an air
bubble.  And the family's own backdrops for camera frames: ``skid`` (painted pipework on a
process skid, flanges with bolt circles, a hazard-striped rail) and ``bokeh`` (a busy plant
far out of focus, as in photographs taken close to a gauge).
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from .gauge_draw import SH, p

__all__ = ["backdrop", "glass", "needle_shadow"]


def needle_shadow(face: np.ndarray, polys, light, offset_px: float) -> None:
    """Darken ``face`` (float32, in place) under the needle's outline moved along ``light``:
    the needle stands off the face, so its shadow falls beside it, blurred."""
    size = face.shape[0]
    m = np.zeros((size, size), np.uint8)
    for poly in polys:
        q = np.array([p(x + light[0] * offset_px, y + light[1] * offset_px) for x, y in poly],
                     np.int32)
        cv2.fillPoly(m, [q], 255, cv2.LINE_AA, SH)
    a = cv2.GaussianBlur(m.astype(np.float32) / 255.0, (0, 0), max(0.8, 0.4 * offset_px))
    face *= (1 - 0.35 * a)[..., None]


def glass(face: np.ndarray, st, size: int, rng: np.random.Generator, light) -> None:
    """The glass over ``face`` (float32, in place): the room mirrored faintly in it, a
    window's reflection in some, and the glycerine fill's meniscus and bubble."""
    c = size / 2.0
    yy, xx = np.mgrid[0:size, 0:size].astype(np.float32)
    room = cv2.resize(rng.uniform(0, 1, (4, 6)).astype(np.float32), (size, size),
                      interpolation=cv2.INTER_CUBIC)
    room = np.clip(room + 0.5 * (1 - yy / c), 0, 1.5) * rng.uniform(0.03, 0.08)
    face += room[..., None] * (255.0 - face)
    if rng.random() < 0.5:  # a window: a soft bright quadrilateral, often across the needle
        x0, y0 = rng.uniform(-0.3, 0.2, 2) * size + c
        wdt, hgt = rng.uniform(0.08, 0.25) * size, rng.uniform(0.1, 0.3) * size
        sk = rng.uniform(-0.4, 0.4) * hgt
        quad = np.array([p(x0, y0), p(x0 + wdt, y0), p(x0 + wdt + sk, y0 + hgt),
                         p(x0 + sk, y0 + hgt)], np.int32)
        m = np.zeros((size, size), np.uint8)
        cv2.fillPoly(m, [quad], 255, cv2.LINE_AA, SH)
        a = cv2.GaussianBlur(m.astype(np.float32) / 255.0, (0, 0), rng.uniform(1.5, 5))
        face += (a * rng.uniform(0.15, 0.4))[..., None] * (255.0 - face)
    if st.fill != "glycerine":
        return
    face *= np.array([0.96, 0.99, 1.0], np.float32)  # the fill's faint yellow
    r_face = st.face_radius * size
    ym = c - r_face * rng.uniform(0.78, 0.93)  # the liquid's level under the case's top
    curve = ym - 0.05 * r_face * ((xx - c) / r_face) ** 2  # it climbs the case's wall
    air = np.clip((curve - yy) / 1.2 + 0.5, 0, 1)
    face += (air * 0.18)[..., None] * (255.0 - face)
    edge = np.exp(-((yy - curve - 1.5) / 1.1) ** 2)  # a dark line, a bright one above it
    shine = np.exp(-((yy - curve + 1.0) / 0.8) ** 2)
    face *= (1 - 0.45 * edge)[..., None]
    face += (0.5 * shine)[..., None] * (255.0 - face)
    if rng.random() < 0.7:  # an air bubble: a dark rim, a bright spot, lighter inside
        q = rng.uniform(0.15, 0.7) * r_face
        t = rng.uniform(-2.4, 2.4)
        bx, by = c + q * math.sin(t), c - q * math.cos(t)
        br = rng.uniform(0.012, 0.03) * size
        d = np.hypot(xx - bx, yy - by) / br
        face += (0.15 * np.clip(1 - d, 0, 1))[..., None] * (255.0 - face)
        face *= (1 - 0.5 * np.exp(-((d - 1) / 0.12) ** 2))[..., None]
        spot = np.hypot(xx - bx + 0.35 * br * light[0], yy - by + 0.35 * br * light[1]) / br
        face += (0.8 * np.exp(-(spot / 0.2) ** 2))[..., None] * (255.0 - face)


def backdrop(rng: np.random.Generator, w: int, h: int, kind: str) -> np.ndarray:
    """``skid``: painted pipes shaded as cylinders, flanges with bolt circles and a
    hazard-striped rail; ``bokeh``: coloured shapes and light spots far out of focus."""
    if kind == "bokeh":
        img = cv2.resize(rng.uniform(50, 190, (4, 5, 1)).astype(np.float32), (w, h),
                         interpolation=cv2.INTER_CUBIC)[..., None] * rng.uniform(0.85, 1.1, 3)
        img = np.ascontiguousarray(img, np.float32)
        for _ in range(int(rng.integers(6, 16))):  # blurred plant: blocks of colour
            x, y = int(rng.integers(0, w)), int(rng.integers(0, h))
            grey = rng.uniform(30, 220)  # plant colours: greys, with a little paint in them
            col = grey + rng.uniform(-40, 40, 3) * rng.uniform(0, 1)
            cv2.rectangle(img, (x, y), (x + int(rng.integers(20, 200)),
                                        y + int(rng.integers(20, 200))), col.tolist(), -1)
        img = cv2.GaussianBlur(img, (0, 0), rng.uniform(8, 16))
        for _ in range(int(rng.integers(3, 12))):  # light sources as bright discs
            x, y = int(rng.integers(0, w)), int(rng.integers(0, h))
            disc = np.zeros((h, w), np.float32)
            cv2.circle(disc, (x, y), int(rng.integers(6, 22)), 1.0, -1, cv2.LINE_AA)
            disc = cv2.GaussianBlur(disc, (0, 0), 1.5)
            img += disc[..., None] * rng.uniform(60, 140)
    else:
        img = np.empty((h, w, 3), np.float32)
        img[:] = rng.uniform(60, 140, 3)  # a painted steel frame behind
        for _ in range(int(rng.integers(2, 5))):  # pipes, lit from above
            col = np.array(rng.choice([[40, 180, 220], [60, 140, 60], [170, 170, 170],
                                       [40, 60, 170], [150, 110, 40]]), np.float32)
            r = int(rng.integers(18, 60))
            vertical = rng.random() < 0.4
            pos = int(rng.integers(0, w if vertical else h))
            t = np.arange(-r, r + 1, dtype=np.float32) / r
            shade = (0.45 + 0.65 * np.sqrt(np.clip(1 - t * t, 0, 1)) * (1 - 0.35 * t))
            prof = col[None, :] * shade[:, None]
            for k, row in enumerate(prof):
                q = pos - r + k
                if vertical and 0 <= q < w:
                    img[:, q] = row
                elif not vertical and 0 <= q < h:
                    img[q, :] = row
            f = int(rng.integers(0, h if vertical else w))  # a flange with its bolts
            fx, fy = (pos, f) if vertical else (f, pos)
            axes = (r + 14, 10) if vertical else (10, r + 14)
            cv2.ellipse(img, (fx, fy), axes, 0, 0, 360, (col * 0.8).tolist(), -1, cv2.LINE_AA)
            for b in range(-r, r + 1, max(8, r // 2)):
                bx, by = (fx + b, fy) if vertical else (fx, fy + b)
                cv2.circle(img, (bx, by), 3, (50, 50, 55), -1, cv2.LINE_AA)
        y0 = int(rng.integers(0, h - 30))  # a hazard-striped handrail
        for x in range(-40, w + 40, 28):
            cv2.fillConvexPoly(img, np.array([(x, y0), (x + 14, y0), (x + 34, y0 + 22),
                                              (x + 20, y0 + 22)], np.int32),
                               (20, 200, 240) if (x // 28) % 2 else (25, 25, 25))
    img += rng.normal(0, 3, img.shape).astype(np.float32)
    return np.clip(img, 0, 255).astype(np.uint8)


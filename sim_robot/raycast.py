"""The world's ray casting (the simulated lidar's and ultrasonic rangers'
sensing): a march along each ray over the occupancy grid's labels, each hit
moved back to the first of ``sub`` finer samples inside its last coarse step,
then circles (people, vehicles) cut analytically.

:func:`cast` is the compiled kernel the world uses: per ray it stops at the
first hit, where :func:`cast_reference` (the plain numpy version, kept for the
tests) samples every step of every ray out to the maximum range, and the
kernel passes over the samples in cells that a distance transform of the grid
(:func:`free_runs`) says are free. Both do the
same float32 arithmetic per sample (the march's positions) and the same
float64 arithmetic per circle, so they return the same ranges and materials.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
from numba import njit

FREE = 0


def march_steps(step: float, max_range_m: float) -> np.ndarray:
    """The coarse march's distances along a ray (float32)."""
    return np.arange(step, max_range_m + step, step, dtype=np.float32)


def fine_offsets(step: float, sub: int = 10) -> np.ndarray:
    """Offsets of the ``sub`` finer samples inside a coarse step, the last one 0."""
    return (np.arange(1, sub + 1, dtype=np.float32) / sub - 1.0) * step


@njit(cache=True)
def _label(labels, x, y, c, s, d, res, clip):
    """The label at distance ``d`` along the ray (c, s) from (x, y), all float32
    (outside the grid: FREE, or the nearest edge cell when ``clip``)."""
    col = math.floor((x + c * d) / res)
    row = math.floor((y + s * d) / res)
    h, w = labels.shape
    if clip:
        col = min(max(col, 0), w - 1)
        row = min(max(row, 0), h - 1)
    elif col < 0 or col >= w or row < 0 or row >= h:
        return FREE
    return labels[row, col]


def free_runs(labels: np.ndarray) -> np.ndarray:
    """Per cell, its chessboard distance in cells to the nearest labelled
    (non-free) cell (int32; 0 on one): every cell less than that many rows and
    columns away is free, so a ray from a point in this cell crosses nothing
    for that many cells less one."""
    free = (labels == FREE).astype(np.uint8)
    if free.all():
        return np.full(labels.shape, max(labels.shape) + 1, np.int32)
    return cv2.distanceTransform(free, cv2.DIST_C, 3).astype(np.int32)


SKIP_MARGIN_M = 1e-4  # a skip stops this short of the free run's end (float32 positions)


@njit(cache=True)
def cast(labels, runs, x, y, ca, sa, ca64, sa64, d, frac, res, max_range_m, people,
         person_mat, rng, mat):
    """Fill ``rng`` (float32, inf: nothing) and ``mat`` (uint8, 0: nothing) for
    rays from (x, y) with directions (ca, sa) in float32 (the march) and
    (ca64, sa64) in float64 (the circles); ``runs``: :func:`free_runs` of
    ``labels``; ``people``: (k, 3) x, y, radius, or None for a world without
    walkers (then no circle is cut).

    The march visits the samples ``d`` in order, as :func:`cast_reference`
    does, but passes over those that the free run of the last sample's cell
    says are free (the same samples would have found nothing), and stops at
    the first hit or when the ray has left the grid (a rectangle: it never
    comes back)."""
    xf = np.float32(x)
    yf = np.float32(y)
    rf = np.float32(res)
    h, w = labels.shape
    m_steps = d.shape[0]
    for i in range(ca.shape[0]):
        c, s = ca[i], sa[i]
        r = np.float32(np.inf)
        m = 0
        k = 0
        was_inside = False
        while k < m_steps:
            col = math.floor((xf + c * d[k]) / rf)
            row = math.floor((yf + s * d[k]) / rf)
            if col < 0 or col >= w or row < 0 or row >= h:
                if was_inside:
                    break
                k += 1
                continue
            was_inside = True
            lab = labels[row, col]
            if lab != FREE:
                m = lab
                r = d[k]
                fine = r + frac[0]  # the first finer sample that hits (the last always
                for j in range(frac.shape[0]):  # does, on the same grid cell)
                    dj = r + frac[j]
                    if _label(labels, xf, yf, c, s, dj, rf, True) != FREE:
                        fine = dj
                        break
                r = fine
                break
            reach = np.float64(d[k]) + (runs[row, col] - 1) * res - SKIP_MARGIN_M
            k += 1
            while k < m_steps and d[k] <= reach:
                k += 1
        rng[i] = r
        mat[i] = m
    if people is None:
        return
    top = np.float32(max_range_m)
    for i in range(ca.shape[0]):
        best = np.inf
        for p in range(people.shape[0]):
            dx = people[p, 0] - x
            dy = people[p, 1] - y
            rad = people[p, 2]
            b = dx * ca64[i] + dy * sa64[i]  # along the ray
            d2 = dx * dx + dy * dy - b * b  # squared miss distance
            h = math.sqrt(max(rad * rad - d2, 0.0))
            if d2 <= rad * rad and b - h > 0 and b - h < best:
                best = b - h
        rp = np.float32(best)
        if rp < rng[i] and rp <= top:
            rng[i] = rp
            mat[i] = person_mat


def cast_reference(labels: np.ndarray, res: float, x: float, y: float, angles: np.ndarray,
                   max_range_m: float, step: float, people: np.ndarray | None,
                   person_mat: int, sub: int = 10) -> tuple[np.ndarray, np.ndarray]:
    """The straightforward numpy ray cast the kernel replaces (every sample of
    every ray), for the tests: (range_m float32, material uint8)."""
    d = march_steps(step, max_range_m)
    ca = np.cos(angles).astype(np.float32)[:, None]
    sa = np.sin(angles).astype(np.float32)[:, None]
    cols = np.floor((x + ca * d) / res).astype(np.int32)
    rows = np.floor((y + sa * d) / res).astype(np.int32)
    h, w = labels.shape
    inside = (cols >= 0) & (cols < w) & (rows >= 0) & (rows < h)
    lab = np.where(inside, labels[np.clip(rows, 0, h - 1), np.clip(cols, 0, w - 1)], 0)
    hit = lab != FREE
    first = hit.argmax(axis=1)
    any_hit = hit[np.arange(len(angles)), first]
    rng = np.where(any_hit, d[first], np.inf).astype(np.float32)
    mat = np.where(any_hit, lab[np.arange(len(angles)), first], 0).astype(np.uint8)
    idx = np.flatnonzero(any_hit)
    if len(idx):  # each hit moved back to the first of sub finer samples in its last step
        dd = rng[idx, None] + fine_offsets(step, sub)[None, :]
        cols = np.floor((x + ca[idx] * dd) / res).astype(np.int32)
        rows = np.floor((y + sa[idx] * dd) / res).astype(np.int32)
        flab = labels[np.clip(rows, 0, h - 1), np.clip(cols, 0, w - 1)]
        rng[idx] = dd[np.arange(len(idx)), (flab != FREE).argmax(axis=1)]
    if people is None:
        return rng, mat
    if not len(people):
        rp = np.full(len(angles), np.inf, np.float32)
    else:
        c64, s64 = np.cos(angles)[:, None], np.sin(angles)[:, None]
        dx, dy, r = people[:, 0] - x, people[:, 1] - y, people[:, 2]
        b = dx * c64 + dy * s64
        d2 = dx * dx + dy * dy - b * b
        hh = np.sqrt(np.maximum(r * r - d2, 0.0))
        rp = np.where((d2 <= r * r) & (b - hh > 0), b - hh, np.inf).min(axis=1).astype(np.float32)
    closer = (rp < rng) & (rp <= max_range_m)
    return np.where(closer, rp, rng), np.where(closer, person_mat, mat).astype(np.uint8)


def warm_up() -> None:
    """Compile (or load from numba's cache) :func:`cast` for a world with
    walkers and one without, before a robot's clock starts."""
    labels = np.zeros((4, 4), np.uint8)
    labels[0] = 1
    runs = free_runs(labels)
    a = np.zeros(2)
    c, s = np.cos(a), np.sin(a)
    d, frac = march_steps(0.05, 0.3), fine_offsets(0.05)
    rng, mat = np.empty(2, np.float32), np.empty(2, np.uint8)
    for people in (None, np.array([[0.2, 0.2, 0.1]])):
        cast(labels, runs, 0.2, 0.2, c.astype(np.float32), s.astype(np.float32), c, s, d,
             frac, 0.1, 0.3, people, 1, rng, mat)

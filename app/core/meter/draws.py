"""The rim search's RANSAC samples, drawn from a numpy ``Generator``'s bit stream in bulk.

:func:`.dial._ransac_ellipse` draws, per hypothesis, a start and a stretch along the contour
(``Generator.integers``) and five distinct points of the stretch (``Generator.choice`` without
replacement).  Each of those calls costs several microseconds of numpy's argument handling
for one to nine small integers, about a fifth of the rim search on a whole camera frame.
:func:`ransac_samples` makes the same draws from the same words of the generator's PCG64
stream, in plain integer arithmetic, and leaves the generator in the state those calls
leave it in; so the samples, and every rim found from them, are the same.

The draws as numpy 2 makes them (``numpy/random/_generator.pyx`` and
``src/distributions/distributions.c``):

* a bounded integer in ``[0, r]`` (r < 2^32 - 1) is Lemire's multiply-and-shift on one
  32-bit word, with his rejection of the low part (Lemire 2019, "Fast random integer
  generation in an interval"); ``r = 0`` takes no word;
* a 32-bit word is the low half of a 64-bit PCG64 output, and the next one its high half;
* ``choice(span, 5, replace=False)`` is Floyd's sampling (a draw in ``[0, j]`` for
  ``j = span - 5 .. span - 1``; a value taken already is replaced by ``j``), then a
  Fisher-Yates shuffle of the five (draws in ``[0, i]``, ``i = 4 .. 1``), whose order the
  caller sorts away but whose words are spent all the same.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["ransac_samples"]

_MASK32 = 0xFFFFFFFF


def ransac_samples(rng: np.random.Generator, n: int, iters: int) -> list[np.ndarray]:
    """``iters`` samples of five contour indices (of ``n``, n >= 40), each what

        base = int(rng.integers(0, n))
        span = int(rng.integers(n // 8, n // 2 + 1))
        idx = (base + np.sort(rng.choice(span, 5, replace=False))) % n

    gives, with ``rng`` (a PCG64 ``Generator``) left as those calls leave it."""
    if not isinstance(rng.bit_generator, np.random.PCG64) or n >= 1 << 31:
        return [_sample_by_calls(rng, n) for _ in range(iters)]
    bg = rng.bit_generator
    start = bg.state
    # the stream's state: the 32-bit high half numpy keeps (if any), and the last high half
    # handed out (numpy keeps it in the state even when used)
    st = np.array([start["uinteger"], start["has_uint32"], start["uinteger"], 0], np.uint64)
    want = 6 * iters + 64  # 11 words per sample, two to a 64-bit output, and rejections
    out = np.empty((iters, 5), np.int64)
    while True:
        bg.state = start
        raw = bg.random_raw(want)
        st[:] = (start["uinteger"], start["has_uint32"], start["uinteger"], 0)
        if _draw(raw, st, n, iters, out):
            break
        want *= 2  # (a run of rejections used up the words fetched)
    # the generator's state after the words used: its outputs advanced by those taken
    # (from the state it had), with the unused high half of the last one kept
    bg.state = start
    bg.advance(int(st[3]))  # (advancing drops a kept half; it is set below)
    state = bg.state
    state["has_uint32"], state["uinteger"] = (1, int(st[0])) if st[1] else (0, int(st[2]))
    bg.state = state
    return list(out)


@njit(cache=True)
def _next32(raw, st):
    """The next 32-bit word of the stream ``raw`` (64-bit outputs) with the state ``st``:
    (kept half, has a kept half, last high half handed out, outputs used); returns -1 when
    ``raw`` is used up."""
    if st[1]:
        st[1] = 0
        st[2] = st[0]
        return np.int64(st[0])
    if st[3] >= len(raw):
        return np.int64(-1)
    v = raw[st[3]]
    st[3] += np.uint64(1)
    st[0] = v >> np.uint64(32)
    st[1] = 1
    st[2] = st[0]
    return np.int64(v & np.uint64(_MASK32))


@njit(cache=True)
def _bounded(raw, st, r):
    """An integer in [0, r] (r < 2^32 - 1), Lemire's way; -1 when ``raw`` is used up."""
    if r == 0:
        return np.int64(0)
    mask = np.uint64(_MASK32)
    excl = np.uint64(r + 1)
    w = _next32(raw, st)
    if w < 0:
        return np.int64(-1)
    m = np.uint64(w) * excl
    if (m & mask) < excl:
        threshold = (mask - np.uint64(r)) % excl
        while (m & mask) < threshold:
            w = _next32(raw, st)
            if w < 0:
                return np.int64(-1)
            m = np.uint64(w) * excl
    return np.int64(m >> np.uint64(32))


@njit(cache=True)
def _draw(raw, st, n, iters, out):
    """The samples of :func:`ransac_samples` into ``out`` (iters x 5) from the words of
    ``raw``; False when those ran out."""
    lo = n // 8
    chosen = np.empty(5, np.int64)
    for it in range(iters):
        base = _bounded(raw, st, n - 1)
        s = _bounded(raw, st, n // 2 - lo)
        if base < 0 or s < 0:
            return False
        span = lo + s
        c = 0
        for j in range(span - 5, span):  # Floyd
            t = _bounded(raw, st, j)
            if t < 0:
                return False
            taken = False
            for q in range(c):
                if chosen[q] == t:
                    taken = True
            chosen[c] = j if taken else t
            c += 1
        for i in range(4, 0, -1):  # the shuffle's draws
            if _bounded(raw, st, i) < 0:
                return False
        chosen.sort()
        for q in range(5):
            out[it, q] = (base + chosen[q]) % n
    return True


def _sample_by_calls(rng: np.random.Generator, n: int) -> np.ndarray:
    base = int(rng.integers(0, n))
    span = int(rng.integers(n // 8, n // 2 + 1))
    return (base + np.sort(rng.choice(span, 5, replace=False))) % n

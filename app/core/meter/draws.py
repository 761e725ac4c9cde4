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

__all__ = ["ransac_samples"]

_MASK32 = 0xFFFFFFFF


class _Words:
    """32-bit words of a PCG64 generator's stream, from raw 64-bit outputs fetched in bulk;
    :meth:`settle` leaves the generator as if the words used had been drawn one by one."""

    def __init__(self, rng: np.random.Generator, expect: int):
        self.bg = rng.bit_generator
        self.start = self.bg.state
        self.half = self.start["uinteger"] if self.start["has_uint32"] else None
        self.spent = self.start["uinteger"]  # the last high half handed out (kept by numpy)
        self.raw: list[int] = []
        self.used = 0  # 64-bit outputs taken
        self.expect = expect

    def next32(self) -> int:
        if self.half is not None:
            w, self.half = self.half, None
            self.spent = w
            return w
        if self.used == len(self.raw):
            self.raw.extend(self.bg.random_raw(max(self.expect, 16)).tolist())
        v = self.raw[self.used]
        self.used += 1
        self.half = self.spent = v >> 32
        return v & _MASK32

    def bounded(self, r: int) -> int:
        """An integer in [0, r] (r < 2^32 - 1), Lemire's way."""
        if r == 0:
            return 0
        excl = r + 1
        m = self.next32() * excl
        if (m & _MASK32) < excl:
            threshold = (_MASK32 - r) % excl
            while (m & _MASK32) < threshold:
                m = self.next32() * excl
        return m >> 32

    def settle(self) -> None:
        """The generator's state after the words used: its outputs advanced by those taken
        (from the state it had), with the unused high half of the last one kept."""
        self.bg.state = self.start
        self.bg.advance(self.used)  # (advancing drops a kept half; it is set below)
        st = self.bg.state
        st["has_uint32"], st["uinteger"] = (0, self.spent) if self.half is None \
            else (1, self.half)
        self.bg.state = st


def ransac_samples(rng: np.random.Generator, n: int, iters: int) -> list[np.ndarray]:
    """``iters`` samples of five contour indices (of ``n``, n >= 40), each what

        base = int(rng.integers(0, n))
        span = int(rng.integers(n // 8, n // 2 + 1))
        idx = (base + np.sort(rng.choice(span, 5, replace=False))) % n

    gives, with ``rng`` (a PCG64 ``Generator``) left as those calls leave it."""
    if not isinstance(rng.bit_generator, np.random.PCG64) or n >= 1 << 31:
        return [_sample_by_calls(rng, n) for _ in range(iters)]
    words = _Words(rng, 6 * iters + 8)  # 11 words per sample, two to a 64-bit output
    lo = n // 8
    out = []
    for _ in range(iters):
        base = words.bounded(n - 1)
        span = lo + words.bounded(n // 2 - lo)
        chosen: list[int] = []
        for j in range(span - 5, span):  # Floyd
            t = words.bounded(j)
            chosen.append(j if t in chosen else t)
        for i in (4, 3, 2, 1):  # the shuffle's draws
            words.bounded(i)
        chosen.sort()
        out.append((base + np.array(chosen, np.int64)) % n)
    words.settle()
    return out


def _sample_by_calls(rng: np.random.Generator, n: int) -> np.ndarray:
    base = int(rng.integers(0, n))
    span = int(rng.integers(n // 8, n // 2 + 1))
    return (base + np.sort(rng.choice(span, 5, replace=False))) % n

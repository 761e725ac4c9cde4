"""``np.quantile``, ``np.percentile`` and ``np.median`` of a float array, the same values,
without numpy's general machinery.

numpy's forms check their arguments, move axes, copy and partition the array at four
ranks and interpolate through several temporaries: some 50-250 µs a call, where the
partition itself takes a fraction of that.  These take the one or two order statistics the
value needs (one partition, and the least value above the lower rank for the upper) and
interpolate them as numpy does (its ``linear`` method, from the nearer rank, in the array's
own dtype).  An array holding a NaN gives NaN, as numpy's do.  Float arrays only (float32
or float64), ``q`` a Python float; the tests compare them with numpy's on many arrays.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["median", "percentile", "quantile"]


def quantile(a: np.ndarray, q: float):
    """``np.quantile(a, q)`` (the linear method) of a float array of any shape."""
    v = np.ravel(a)  # (a view where a is contiguous; np.partition copies it anyway)
    n = v.size
    vi = (n - 1) * q
    if vi >= n - 1:  # numpy takes the last order statistic (the maximum)
        return v.max()
    lo = int(math.floor(vi))
    p = np.partition(v, lo)
    x, y = p[lo], p[lo + 1:].min()  # (a NaN sorts last: it reaches the min above lo)
    if math.isnan(y):
        return y
    t = vi - lo
    d = y - x
    # numpy's interpolation: from the nearer of the two ranks
    return y - d * (1 - t) if t >= 0.5 else x + d * t


def percentile(a: np.ndarray, q: float):
    """``np.percentile(a, q)`` (the linear method) of a float array of any shape."""
    return quantile(a, q / 100.0)


def median(a: np.ndarray):
    """``np.median(a)`` of a float array of any shape: the middle order statistic, or the
    mean of the two middle ones (their sum in the array's dtype, halved)."""
    v = np.ravel(a)
    n = v.size
    k = n // 2
    p = np.partition(v, k)
    y = p[k]
    if n % 2:
        big = p[k + 1:].max() if n > 1 else y
        return big if math.isnan(big) else y  # (a NaN sorts last, past the middle)
    x = p[:k].max()  # the lower middle value: the largest below rank k
    if math.isnan(y) or (n > k + 1 and math.isnan(p[k + 1:].max())):
        return p.dtype.type(math.nan)
    return (x + y) / 2

"""Small scalar helpers every kernel uses: clamping, the exact fractional part."""

from __future__ import annotations

import numpy as np

from refnpr._jit import njit

__all__ = ["clip", "clip01", "frac", "interp", "ONE_BELOW"]

#: The largest float64 below 1.
ONE_BELOW = float(np.nextafter(1.0, 0.0))


@njit
def clip(x, lo, hi):
    """``min(max(x, lo), hi)`` (``np.clip`` of one value)."""
    m = x if x >= lo else lo
    return m if m <= hi else hi


@njit
def clip01(x):
    """``x`` clamped to [0, 1]."""
    return min(max(x, 0.0), 1.0)


@njit
def frac(x):
    """Frac(x) = x - floor(x) in [0, 1): where a tiny negative x rounds it to 1, the largest
    float below 1. (``np.floor``: a float, exact for any finite x; ``math.floor`` is an int64
    in numba and overflows beyond 2**63.)"""
    r = x - np.floor(x)
    return r if r < ONE_BELOW else ONE_BELOW


@njit
def interp(x, xp, fp):
    """``np.interp(x, xp, fp)`` of one value for increasing ``xp`` (1D arrays of one length):
    numpy's branches and arithmetic (the ends, exact knots, the slope form and its NaN
    fallbacks). The bracket search starts at the index a uniform ``xp`` on [0, 1] gives."""
    n = xp.shape[0]
    if x < xp[0]:
        return fp[0]
    if x > xp[n - 1]:
        return fp[n - 1]
    j = min(max(np.int64(x * (n - 1)), 0), n - 1)  # a guess, then the bracket
    while j > 0 and xp[j] > x:
        j -= 1
    while j < n - 1 and xp[j + 1] <= x:
        j += 1
    if j == n - 1 or xp[j] == x:
        return fp[j]
    slope = (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j])
    out = slope * (x - xp[j]) + fp[j]
    if out != out:
        out = slope * (x - xp[j + 1]) + fp[j + 1]
        if out != out and fp[j] == fp[j + 1]:
            out = fp[j]
    return out

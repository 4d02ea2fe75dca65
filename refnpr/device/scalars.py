"""Small scalar helpers every kernel uses: clamping, the exact fractional part."""

from __future__ import annotations

import numpy as np

from refnpr._jit import njit

__all__ = ["clip", "clip01", "frac", "ONE_BELOW"]

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

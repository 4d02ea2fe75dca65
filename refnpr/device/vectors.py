"""3-vectors as tuples ``(x, y, z)`` of float64: dot products and normalization.

Sums are formed x + y, then + z, everywhere, so a vector computed by two kernels has the same
bits in both.
"""

from __future__ import annotations

import math

from refnpr._jit import njit

__all__ = ["dot", "unit", "unit_scaled", "towards", "reflect"]


@njit
def dot(a, b):
    """``a . b``, summed x + y, then + z."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit
def unit(v):
    """``v / |v|``; a zero vector stays zero."""
    length = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    if length > 0.0:
        return (v[0] / length, v[1] / length, v[2] / length)
    return (0.0, 0.0, 0.0)


@njit
def unit_scaled(v):
    """``v / |v|`` scaled by its largest component first (no overflow or underflow of |v|);
    a zero vector stays zero. The arithmetic of ``formulas._shading_checks.unit_vectors``."""
    x, y, z = v
    m = max(abs(x), abs(y), abs(z))
    if m > 0.0:
        x = x / m
        y = y / m
        z = z / m
    length = math.sqrt(x * x + y * y + z * z)
    if length > 0.0:
        x = x / length
        y = y / length
        z = z / length
    return (x, y, z)


@njit
def towards(target, p):
    """The unit vector from ``p`` towards ``target`` (zero where they coincide)."""
    return unit((target[0] - p[0], target[1] - p[1], target[2] - p[2]))


@njit
def reflect(l, n, n_dot_l):
    """``2 (n . l) n - l``: the mirror direction of ``l`` about ``n`` (``n_dot_l`` given)."""
    two = 2.0 * n_dot_l
    return (two * n[0] - l[0], two * n[1] - l[1], two * n[2] - l[2])

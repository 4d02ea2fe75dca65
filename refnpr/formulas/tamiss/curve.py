"""The fitted cubic of a stroke and its slope (TAMISS sec. 3.2: r(t) = c^T (1, t, t^2, t^3)).

Private helper of :mod:`refnpr.formulas.tamiss` (which re-exports the public names). Both are
scalar device functions of the curve's own float type (float32 fits evaluate in float32): the
style kernels call them for every vertex of a drawn stroke, and :class:`~.fit.StrokeFit` and
:func:`~.segments.visible_segments` run them through their numpy faces.
"""

from __future__ import annotations

import numpy as np

from refnpr._jit import njit

from .._face import elementwise, face
from .._validate import as_float, describe, result_dtype

__all__ = ["cubic", "cubic_slope"]


@njit
def _cubic(c, s):
    return ((c[3] * s + c[2]) * s + c[1]) * s + c[0]  # Horner: c0 + c1 s + c2 s^2 + c3 s^3


def _arguments(c, s) -> tuple:
    """The float type, the coefficients' columns and ``s`` of a face's arguments."""
    arr = as_float("c", c)
    if arr.ndim < 1 or arr.shape[-1] != 4:
        raise ValueError(f"c: expected shape (..., 4) (cubic coefficients), got {describe(arr)}")
    dt = result_dtype(arr, s)
    return dt, tuple(arr[..., k] for k in range(4)), as_float("s", s).astype(dt)


@face(_cubic)
def cubic(c, s) -> np.ndarray:
    """c0 + c1 s + c2 s^2 + c3 s^3 (Horner's order) of coefficients ``c`` (..., 4) at ``s``
    (broadcasting against ``c[..., 0]``); float32 arithmetic where both are float32.
    ``cubic.scalar(c, s)`` takes the coefficients as a 4-tuple."""
    dt, cols, s_ = _arguments(c, s)
    return elementwise(cubic.scalar, dt, cols, s_, compute=dt)


@njit
def _cubic_slope(c, s, k):
    two, three, zero = k
    return ((zero * s + three * c[3]) * s + two * c[2]) * s + c[1]  # the cubic of (c1, 2c2, 3c3, 0)


@face(_cubic_slope)
def cubic_slope(c, s) -> np.ndarray:
    """dr/ds = c1 + 2 c2 s + 3 c3 s^2, as the cubic of (c1, 2 c2, 3 c3, 0) (Horner's order).
    ``cubic_slope.scalar(c, s, k)`` takes ``k = (2, 3, 0)`` in the curve's float type."""
    dt, cols, s_ = _arguments(c, s)
    k = (dt.type(2), dt.type(3), dt.type(0))
    return elementwise(cubic_slope.scalar, dt, cols, s_, k, compute=dt)

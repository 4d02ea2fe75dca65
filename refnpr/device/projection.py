"""World -> clip -> pixel: how the rasterizer projects a point, for everything that needs the
pixel a point lands on (flow, stroke motion, motion fields).

``vp`` is ``Camera.view_projection(width, height)`` (OpenGL matrices, row-major 4x4 float64).
Clip coordinates are summed in a fixed order (no BLAS, no FMA contraction), so every caller
gets the rasterizer's bits. Pixel (x, y) has its centre at (x + 0.5, y + 0.5), row 0 at the top.
"""

from __future__ import annotations

import math

from refnpr._jit import njit

__all__ = ["clip_of", "pixel_of", "project"]


@njit
def clip_of(vp, p):
    """Clip coordinates ``(x, y, z, w)`` of the world point ``p = (x, y, z)``: VP (p, 1), each
    row summed ``((m0 x + m1 y) + m2 z) + m3``."""
    x, y, z = p
    return (
        ((vp[0, 0] * x + vp[0, 1] * y) + vp[0, 2] * z) + vp[0, 3],
        ((vp[1, 0] * x + vp[1, 1] * y) + vp[1, 2] * z) + vp[1, 3],
        ((vp[2, 0] * x + vp[2, 1] * y) + vp[2, 2] * z) + vp[2, 3],
        ((vp[3, 0] * x + vp[3, 1] * y) + vp[3, 2] * z) + vp[3, 3],
    )


@njit
def pixel_of(cx, cy, w, width, height):
    """Continuous pixel coordinates of clip ``(cx, cy, ., w)`` in a ``width x height`` image:
    ``((cx / w + 1) W / 2, (1 - cy / w) H / 2)`` (w > 0; the caller handles points behind)."""
    return (cx / w + 1.0) * (0.5 * width), (1.0 - cy / w) * (0.5 * height)


@njit
def project(vp, p, size):
    """``(x, y, w_clip)`` of the world point ``p``: its continuous pixel coordinates in an
    image of ``size = (width, height)``, NaN where it is at or behind the eye (w_clip <= 0)."""
    c = clip_of(vp, p)
    if c[3] > 0.0:
        x, y = pixel_of(c[0], c[1], c[3], size[0], size[1])
        return x, y, c[3]
    return math.nan, math.nan, c[3]

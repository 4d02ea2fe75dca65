"""numba texture samplers (private; validated by refnpr.texture.sample)."""

from __future__ import annotations

import math

import numpy as np

from refnpr._jit import banded, njit


@njit(inline="always")
def _wrap(i, n):
    r = i % n
    return r + n if r < 0 else r


@njit(inline="always")  # a call passing texels and a row view pays NRT refcounts per sample
def _bilinear_into(texels, offset, rows, cols, u, v, weight, out_row):
    """out_row[c] += weight * GL_LINEAR/GL_REPEAT sample of one level at (u, v).

    u and v are first reduced to one period (u - floor(u) is exact in floating point), so huge
    coordinates cannot overflow the integer texel index."""
    x = (u - np.floor(u)) * cols - 0.5
    y = (v - np.floor(v)) * rows - 0.5
    x0 = math.floor(x)
    y0 = math.floor(y)
    fx = x - x0
    fy = y - y0
    i0 = _wrap(np.int64(x0), cols)
    i1 = _wrap(np.int64(x0) + 1, cols)
    j0 = _wrap(np.int64(y0), rows)
    j1 = _wrap(np.int64(y0) + 1, rows)
    w00 = (1.0 - fx) * (1.0 - fy)
    w10 = fx * (1.0 - fy)
    w01 = (1.0 - fx) * fy
    w11 = fx * fy
    for c in range(texels.shape[1]):
        s = (
            w00 * texels[offset + j0 * cols + i0, c]
            + w10 * texels[offset + j0 * cols + i1, c]
            + w01 * texels[offset + j1 * cols + i0, c]
            + w11 * texels[offset + j1 * cols + i1, c]
        )
        out_row[c] += weight * s


@banded("uv")
def sample_level(lo, hi, texels, offsets, shapes, uv, level, out):
    """out (P, C) = bilinear sample of integer level[p] (clamped to the pyramid) at uv (P, 2)."""
    top = offsets.shape[0] - 1
    for p in range(lo, hi):
        for c in range(out.shape[1]):
            out[p, c] = 0.0
        k = min(max(level[p], 0), top)
        _bilinear_into(
            texels, offsets[k], shapes[k, 0], shapes[k, 1], uv[p, 0], uv[p, 1], 1.0, out[p]
        )


@banded("uv")
def sample_trilinear(lo, hi, texels, offsets, shapes, uv, lod, out):
    """out (P, C) = GL_LINEAR_MIPMAP_LINEAR sample at uv (P, 2) and LOD lod (P,): lod clamped to
    [0, L - 1], bilinear in the two nearest levels, linear in frac(lod)."""
    top = offsets.shape[0] - 1
    for p in range(lo, hi):
        for c in range(out.shape[1]):
            out[p, c] = 0.0
        lam = min(max(lod[p], 0.0), float(top))
        k0 = np.int64(math.floor(lam))
        k1 = min(k0 + 1, top)
        f = lam - k0
        u = uv[p, 0]
        v = uv[p, 1]
        _bilinear_into(texels, offsets[k0], shapes[k0, 0], shapes[k0, 1], u, v, 1.0 - f, out[p])
        if f > 0.0:
            _bilinear_into(texels, offsets[k1], shapes[k1, 0], shapes[k1, 1], u, v, f, out[p])

"""OpenGL texture sampling of one sample: GL_REPEAT taps, bilinear, a mip level, trilinear,
anisotropic probes (OpenGL 4.6 sec. 8.14-8.15).

Textures are packed pyramids ``pyr = (texels, offsets, shapes)``
(:meth:`refnpr.texture.MipPyramid.packed`): ``texels (N, C)`` float64, level k's ``shapes[k] = (rows, cols)`` texels
starting at row ``offsets[k]``, row-major. Texel (i, j) of a level sits at
``((j + 0.5) / cols, (i + 0.5) / rows)`` in uv (u along columns, v along rows). Weights are
summed in one order everywhere (w00, w10, w01, w11), and a level's value enters a trilinear
sum as ``0 + (1 - f) s0``, then ``+ f s1``.
"""

from __future__ import annotations

import math

import numpy as np

from refnpr._jit import njit

#: Smallest footprint / gradient ``gl_lod`` takes the logarithm of (a finite LOD).
LOD_FLOOR = 2.0**-64


@njit
def gl_lod(dx, dy, texels_u, texels_v):
    """OpenGL 4.x sec. 8.14 isotropic LOD lambda = log2 rho, rho = max(|d(u,v)/dx|, |d(u,v)/dy|)
    in texels of a ``texels_u x texels_v`` texture (libm's hypot and log2), at least LOD_FLOOR;
    ``dx = (du/dx, dv/dx)``, ``dy = (du/dy, dv/dy)`` per pixel."""
    rho = max(
        math.hypot(dx[0] * texels_u, dx[1] * texels_v),
        math.hypot(dy[0] * texels_u, dy[1] * texels_v),
    )
    return math.log2(max(rho, LOD_FLOOR))


__all__ = [
    "LOD_FLOOR",
    "gl_lod",
    "wrap",
    "taps",
    "tap_value",
    "bilinear",
    "level",
    "trilinear",
    "probes",
    "level_probes",
    "footprint",
    "level_weights",
]


@njit
def wrap(i, n):
    """``i`` modulo ``n`` in ``[0, n)`` (GL_REPEAT of a texel index)."""
    r = i % n
    return r + n if r < 0 else r


@njit
def taps(offset, rows, cols, u, v):
    """The four texels and weights of a GL_LINEAR / GL_REPEAT sample of one level at (u, v):
    ``(i00, i10, i01, i11, w00, w10, w01, w11)``, texel rows of the packed ``texels``.

    u and v are reduced to one period first (``u - floor(u)`` is exact), so huge coordinates
    cannot overflow an index; GL_REPEAT by compare and subtract where the index is at most one
    period out (always, for a finite uv), the modulo otherwise.
    """
    x = (u - np.floor(u)) * cols - 0.5
    y = (v - np.floor(v)) * rows - 0.5
    x0 = math.floor(x)
    y0 = math.floor(y)
    fx = x - x0
    fy = y - y0
    ix = np.int64(x0)
    iy = np.int64(y0)
    if -1 <= ix and ix < cols and -1 <= iy and iy < rows:
        i0 = ix if ix >= 0 else cols - 1
        i1 = ix + 1 if ix + 1 < cols else ix + 1 - cols
        j0 = iy if iy >= 0 else rows - 1
        j1 = iy + 1 if iy + 1 < rows else iy + 1 - rows
    else:
        i0 = wrap(ix, cols)
        i1 = wrap(ix + 1, cols)
        j0 = wrap(iy, rows)
        j1 = wrap(iy + 1, rows)
    w00 = (1.0 - fx) * (1.0 - fy)
    w10 = fx * (1.0 - fy)
    w01 = (1.0 - fx) * fy
    w11 = fx * fy
    r0 = offset + j0 * cols
    r1 = offset + j1 * cols
    return r0 + i0, r0 + i1, r1 + i0, r1 + i1, w00, w10, w01, w11


@njit
def tap_value(texels, t, c):
    """Channel ``c`` of the bilinear sample whose :func:`taps` are ``t``."""
    i00, i10, i01, i11, w00, w10, w01, w11 = t
    return w00 * texels[i00, c] + w10 * texels[i10, c] + w01 * texels[i01, c] + w11 * texels[i11, c]


@njit
def bilinear(texels, offset, rows, cols, u, v, c):
    """Channel ``c`` of a GL_LINEAR / GL_REPEAT sample of one level (rows, cols at ``offset``)."""
    return tap_value(texels, taps(offset, rows, cols, u, v), c)


@njit
def level(pyr, k, u, v, c):
    """Bilinear sample of integer level ``k`` (clamped to the pyramid) of ``pyr``."""
    texels, offsets, shapes = pyr
    top = offsets.shape[0] - 1
    k = min(max(k, 0), top)
    return 0.0 + 1.0 * bilinear(texels, offsets[k], shapes[k, 0], shapes[k, 1], u, v, c)


@njit
def trilinear(pyr, u, v, lod, c):
    """GL_LINEAR_MIPMAP_LINEAR sample: lod clamped to [0, L - 1], bilinear in the two nearest
    levels, linear in frac(lod)."""
    texels, offsets, shapes = pyr
    k0, k1, f = level_weights(offsets.shape[0], lod)
    r = 0.0 + (1.0 - f) * bilinear(texels, offsets[k0], shapes[k0, 0], shapes[k0, 1], u, v, c)
    if f > 0.0:
        r = r + f * bilinear(texels, offsets[k1], shapes[k1, 0], shapes[k1, 1], u, v, c)
    return r


@njit
def probes(pyr, u, v, lod, n, axis, c):
    """Anisotropic filtering: the mean of ``n`` trilinear probes at ``(u, v) + axis ((j + 1/2)
    / n - 1/2)``, j = 0 .. n - 1, along the footprint's major ``axis = (du, dv)``; ``n = 0``:
    one trilinear sample (isotropic)."""
    if n == 0:
        return trilinear(pyr, u, v, lod, c)
    acc = 0.0
    for j in range(n):
        t = (j + 0.5) / n - 0.5
        acc = acc + trilinear(pyr, u + axis[0] * t, v + axis[1] * t, lod, c)
    return acc / n


@njit
def level_probes(pyr, k, u, v, n, axis):
    """Channel 0 of level ``k``: one bilinear sample (``n = 0``) or the mean of ``n`` probes
    along ``axis``, as :func:`probes` places them."""
    if n == 0:
        return level(pyr, k, u, v, np.int64(0))
    acc = 0.0
    for j in range(n):
        t = (j + 0.5) / n - 0.5
        acc = acc + level(pyr, k, u + axis[0] * t, v + axis[1] * t, np.int64(0))
    return acc / n


@njit
def footprint(dx, dy, rows, cols, anisotropy):
    """LOD and probes of a sample whose uv derivatives are ``dx = (du/dx, dv/dx)`` and ``dy =
    (du/dy, dv/dy)``, for a level-0 texture of ``rows x cols`` texels (OpenGL 4.6 sec. 8.14).

    The footprint's axes in texels have lengths P_x = |dx| and P_y = |dy|. ``anisotropy == 1``:
    the isotropic ``lod = log2 max(P_x, P_y)`` and no probes (``n = 0``). Otherwise (sec.
    8.14.1, GL_TEXTURE_MAX_ANISOTROPY = ``anisotropy``): ``n = min(ceil(P_max / P_min),
    anisotropy)`` probes along the major axis, ``lod = log2(P_max / n)``. Returns ``(lod, n,
    axis)`` with the major axis ``(du, dv)`` in uv ((0, 0) when isotropic). The lengths are
    ``sqrt(a a + b b)`` (GLSL's ``length``), not :func:`gl_lod`'s libm hypot, which makes the
    halftone kernel's hot loop ~10 % slower; the LOD has :func:`gl_lod`'s floor, LOD_FLOOR.
    """
    ax = dx[0] * cols
    ay = dx[1] * rows
    px = math.sqrt(ax * ax + ay * ay)
    bx = dy[0] * cols
    by = dy[1] * rows
    py = math.sqrt(bx * bx + by * by)
    p_max = max(px, py)
    if anisotropy == 1:
        return math.log2(max(p_max, LOD_FLOOR)), np.int64(0), (0.0, 0.0)
    p_min = min(px, py)
    ratio = p_max / max(p_min, LOD_FLOOR)
    n = np.int64(min(max(math.ceil(ratio - 1e-9), 1.0), float(anisotropy)))
    lod = math.log2(max(p_max / n, LOD_FLOOR))
    if px >= py:
        return lod, n, (dx[0], dx[1])
    return lod, n, (dy[0], dy[1])


@njit
def level_weights(n_levels, lod):
    """The two levels a trilinear sample of a pyramid of ``n_levels`` levels blends at ``lod``
    and the weight of the second, as :func:`trilinear` picks them: ``(k0, k1, f)`` with lod
    clamped to [0, L - 1], k0 = floor, k1 = min(k0 + 1, L - 1), f = frac."""
    top = n_levels - 1
    lam = min(max(lod, 0.0), float(top))
    k0 = np.int64(math.floor(lam))
    return k0, min(k0 + 1, top), lam - k0

"""numba kernels of the style layer (private; inputs validated by the public modules)."""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from refnpr._jit import banded, njit
from refnpr.device.projection import clip_of, pixel_of
from refnpr.device.sampling import gl_lod, trilinear


@njit
def _visible(depth, x, y, w, rel_tol):
    """An edge point at sample coords (x, y) with eye depth w is visible if it is not behind the
    farthest surface in the 3x3 samples around it (silhouettes border farther surfaces)."""
    nh, nw = depth.shape
    cx = int(math.floor(x))
    cy = int(math.floor(y))
    far = -1.0
    for j in range(cy - 1, cy + 2):
        for i in range(cx - 1, cx + 2):
            if 0 <= i < nw and 0 <= j < nh:
                d = depth[j, i]
                if d > far:
                    far = d
    if far < 0.0:
        return False  # entirely outside the image
    return w <= far * (1.0 + rel_tol)


@njit
def _splat_capsule(cov, a, b, radius):
    """cov = max(cov, clamp(radius + 0.5 - distance(sample centre, segment ab), 0, 1)), with
    ``a``, ``b`` the segment's ends in sample coordinates."""
    nh, nw = cov.shape
    ax, ay = a
    bx, by = b
    x0 = max(int(math.floor(min(ax, bx) - radius - 1.0)), 0)
    x1 = min(int(math.ceil(max(ax, bx) + radius + 1.0)), nw - 1)
    y0 = max(int(math.floor(min(ay, by) - radius - 1.0)), 0)
    y1 = min(int(math.ceil(max(ay, by) + radius + 1.0)), nh - 1)
    dx = bx - ax
    dy = by - ay
    len2 = dx * dx + dy * dy
    for j in range(y0, y1 + 1):
        py = j + 0.5
        for i in range(x0, x1 + 1):
            px = i + 0.5
            t = 0.0
            if len2 > 0.0:
                t = ((px - ax) * dx + (py - ay) * dy) / len2
                t = min(max(t, 0.0), 1.0)
            ex = ax + t * dx - px
            ey = ay + t * dy - py
            c = radius + 0.5 - math.sqrt(ex * ex + ey * ey)
            if c > 1.0:
                c = 1.0
            if c > cov[j, i]:
                cov[j, i] = c


@njit
def _vertex(positions, i):
    return positions[i, 0], positions[i, 1], positions[i, 2]


@njit
def draw_edges(positions, vp, edges, depth, line, cov):
    """Anti-aliased, depth-tested edges into cov (nH, nW) (serial: deterministic max-blend).

    positions (N, 3) float64: world vertices, projected through ``vp`` (the sample grid's
    view-projection matrix) as the rasterizer projects them (``device.projection``); edges
    (E, 2) vertex indices; depth (nH, nW) float64; line = (radius, rel_tol, step): the capsule
    radius in samples, the visibility test's relative depth slack, the piece length. Each edge
    is clipped to the near plane (z >= -w), projected to the sample grid, walked in pieces of at
    most ``step`` samples, and every piece whose midpoint is visible is drawn as a capsule.
    """
    radius, rel_tol, step = line
    nh, nw = cov.shape
    for e in range(edges.shape[0]):
        a = clip_of(vp, _vertex(positions, edges[e, 0]))
        b = clip_of(vp, _vertex(positions, edges[e, 1]))
        da = a[2] + a[3]
        db = b[2] + b[3]
        if da < 0.0 and db < 0.0:
            continue
        t0 = 0.0
        t1 = 1.0
        if da < 0.0:
            t0 = da / (da - db)
        elif db < 0.0:
            t1 = da / (da - db)
        # clipped endpoints in clip space
        ax = a[0] + t0 * (b[0] - a[0])
        ay = a[1] + t0 * (b[1] - a[1])
        aw = a[3] + t0 * (b[3] - a[3])
        bx = a[0] + t1 * (b[0] - a[0])
        by = a[1] + t1 * (b[1] - a[1])
        bw = a[3] + t1 * (b[3] - a[3])
        if aw <= 0.0 or bw <= 0.0:
            continue
        # sample-grid coordinates (continuous; sample s has its centre at s + 0.5)
        sax, say = pixel_of(ax, ay, aw, nw, nh)
        sbx, sby = pixel_of(bx, by, bw, nw, nh)
        length = math.sqrt((sbx - sax) ** 2 + (sby - say) ** 2)
        if not math.isfinite(length):
            continue
        pieces = max(1, int(math.ceil(length / step)))
        if pieces > 4 * (nw + nh):
            pieces = 4 * (nw + nh)
        ia = 1.0 / aw
        ib = 1.0 / bw
        for k in range(pieces):
            s0 = k / pieces
            s1 = (k + 1) / pieces
            sm = 0.5 * (s0 + s1)
            px = sax + sm * (sbx - sax)
            py = say + sm * (sby - say)
            w = 1.0 / (ia + sm * (ib - ia))  # 1/w is affine in screen space
            if _visible(depth, px, py, w, rel_tol):
                _splat_capsule(
                    cov,
                    (sax + s0 * (sbx - sax), say + s0 * (sby - say)),
                    (sax + s1 * (sbx - sax), say + s1 * (sby - say)),
                    radius,
                )


@banded("cov")
def ink_over(lo, hi, rgba, cov, ink):
    """Straight-alpha "over" of ink with coverage ``cov`` on top of ``rgba``, in place.

    rgba : (nH, nW, 4) float32 (read and overwritten); cov : (nH, nW) float64 in [0, 1];
    ink : (3,) float64. Per sample, in float64: a = c + a_b (1 - c); colour = (ink c + rgb_b a_b
    (1 - c)) / a, 0 where a = 0 -- the numpy expression ``Contoured`` used before, term for term.
    """
    nh, nw = cov.shape
    for j in range(lo, hi):
        for i in range(nw):
            c = cov[j, i]
            ab = np.float64(rgba[j, i, 3])
            a = c + ab * (1.0 - c)
            for k in range(3):
                premult = ink[k] * c + np.float64(rgba[j, i, k]) * ab * (1.0 - c)
                rgba[j, i, k] = premult / a if a > 0.0 else 0.0
            rgba[j, i, 3] = a


#: ``Under.mode`` codes of :func:`ink_composite`: what the ink is drawn over.
UNDER_RGBA = 0
UNDER_PAPER = 1
UNDER_NONE = 2


class Under(NamedTuple):
    """What :func:`ink_composite` draws the ink over: ``mode`` UNDER_RGBA (``rgba (nH, nW, 4)``
    float32, a base style's RGBA), UNDER_PAPER (``paper (3,)`` float64, already clipped and
    rounded to float32, on the samples where ``mask (nH, nW)`` bool; transparent elsewhere) or
    UNDER_NONE (transparent; the arrays unused)."""

    mode: int
    rgba: np.ndarray
    mask: np.ndarray
    paper: np.ndarray


@njit
def _base(under, j, i):
    """The straight-alpha base colour ``(r, g, b, a)`` under sample (j, i)."""
    if under.mode == UNDER_RGBA:
        rgba = under.rgba
        return (
            np.float64(rgba[j, i, 0]),
            np.float64(rgba[j, i, 1]),
            np.float64(rgba[j, i, 2]),
            np.float64(rgba[j, i, 3]),
        )
    if under.mode == UNDER_PAPER and under.mask[j, i]:
        return under.paper[0], under.paper[1], under.paper[2], 1.0
    return 0.0, 0.0, 0.0, 0.0


@banded("out")
def ink_composite(lo, hi, under, ink, out):
    """Straight-alpha "over" of ink on top of a base, one pass (``tamiss.compose.composite_ink``).

    under : :class:`Under`; ink = (coverage, rgb): coverage (nH, nW) float64, rgb (1, 3) one
    colour or (nH * nW, 3) one per sample, float64. out : (nH, nW, 4) float32. Per sample, in
    float64 and in the numpy expression's order: a = clip(coverage, 0, 1); k = a_b (1 - a);
    alpha = a + k; rgb = clip((ink_rgb a + rgb_b k) / alpha, 0, 1), 0 where alpha = 0.
    """
    coverage, ink_rgb = ink
    nw = coverage.shape[1]
    per_sample = ink_rgb.shape[0] > 1
    for j in range(lo, hi):
        for i in range(nw):
            a = min(max(coverage[j, i], 0.0), 1.0)
            base = _base(under, j, i)
            k = base[3] * (1.0 - a)
            alpha = a + k
            s = j * nw + i if per_sample else 0
            for c in range(3):
                premult = ink_rgb[s, c] * a + base[c] * k
                v = premult / alpha if alpha > 0.0 else 0.0
                out[j, i, c] = min(max(v, 0.0), 1.0)
            out[j, i, 3] = alpha


@banded("out")
def sample_albedo(lo, hi, grids, objects, pyr, out):
    """``out[y, x, :3]`` = the trilinear sample of the packed pyramid ``pyr`` (3 channels) at
    the sample's uv times its object's uv scale, at the GL isotropic LOD of the scaled per-pixel
    derivatives, for the samples whose object is marked; others are not written.
    ``grids = (mesh_id, uv, duv_dx, duv_dy)``, ``objects = (marked (O,) bool, uv_scale (O, 2))``
    (``refnpr.styles.albedo``)."""
    mesh_id, uv, gx, gy = grids
    marked, scale = objects
    shapes = pyr[2]
    tu = np.float64(shapes[0, 1])
    tv = np.float64(shapes[0, 0])
    for y in range(lo, hi):
        for x in range(mesh_id.shape[1]):
            mi = mesh_id[y, x]
            if mi < 0 or not marked[mi]:
                continue
            su = scale[mi, 0]
            sv = scale[mi, 1]
            u = np.float64(uv[y, x, 0]) * su
            v = np.float64(uv[y, x, 1]) * sv
            dx = (np.float64(gx[y, x, 0]) * su, np.float64(gx[y, x, 1]) * sv)
            dy = (np.float64(gy[y, x, 0]) * su, np.float64(gy[y, x, 1]) * sv)
            lod = gl_lod(dx, dy, tu, tv)
            for c in range(3):
                out[y, x, c] = trilinear(pyr, u, v, lod, c)

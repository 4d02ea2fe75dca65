"""numba kernels of the rasterizer. Private: inputs are validated by :mod:`refnpr.raster.rasterize`.

Conventions shared by every kernel
----------------------------------
* Sample grid: ``spp = n * n`` samples per pixel laid out as an ``(n H) x (n W)`` image; sample
  ``(sx, sy)`` has its centre at pixel coordinates ``((sx + 0.5) / n, (sy + 0.5) / n)``.
* Fixed point: vertices are snapped to 1/256 pixel (8 sub-pixel bits). Edge functions are evaluated
  in units of ``1 / (512 n)`` pixel, where sample centres are the integers ``512 s + 256`` and a
  snapped vertex ``X / 256`` px is ``2 n X``; every product fits in int64 (the guard band bounds
  the coordinates), so coverage is exact and deterministic.
* Interpolation uses the exact float64 clip-space vertices: for triangle t,
  ``lam[t] @ (sx, sy, 1)`` gives ``lambda'_i = b_i / w`` (perspective-correct barycentrics over w),
  their sum ``Q = 1 / w`` and ``b_i = lambda'_i / Q``. Both P = sum(lambda'_i f_i) and Q are affine in
  the sample position, so derivatives follow from the quotient rule.
* Kernels take records (the named tuples below) and take their arrays into locals once, before
  their loops (an array read from a record inside a loop takes and drops a reference each
  time). Per-primitive helpers take numbers and tuples of numbers: a primitive's six snapped
  coordinates ``c = (X0, Y0, X1, Y1, X2, Y2)``, its inclusive sample box ``b = (sx0, sx1, sy0,
  sy1)``, a tile's rectangle ``(x0, y0, x1, y1)``, a vertex's clip ``(x, y, w)``. The banded
  kernels are called through :func:`refnpr._jit.call_banded`, which types the records once
  per call rather than once per band.
* World -> clip -> pixel is :mod:`refnpr.device.projection` (``clip_of``, ``pixel_of``); the
  snapping to 1/256 px (round half up) is the rasterizer's.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from refnpr._jit import banded, njit, specialised
from refnpr.device.projection import clip_of, pixel_of
from refnpr.device.sampling import LOD_FLOOR, gl_lod

# Clip planes as (a, b, c, d): inside where a x + b y + c z + d w >= 0. Guard band G fills d for x, y.
# Order: near, far, left, right, bottom, top.
N_PLANES = 6
MAX_POLY = 3 + N_PLANES  # Sutherland-Hodgman adds at most one vertex per plane


# --- Records


class Grid(NamedTuple):
    """The image, its sample grid and its tiles (ints)."""

    width: int  # pixels
    height: int
    n: int  # samples per pixel along each axis
    nw: int  # n * width: samples per row
    nh: int  # n * height
    tile: int  # tile edge in samples (a power of two)
    shift: int  # log2(tile)
    tiles_x: int  # tiles per row


class Setup(NamedTuple):
    """How triangles are set up and binned."""

    guard: float  # guard band half-width in NDC units (clipping planes x, y = +-guard w)
    cull: int  # 1: drop back-facing (clockwise in NDC) triangles
    chunk: int  # triangles per binning chunk


class Verts(NamedTuple):
    """The vertex stage's output (N vertices)."""

    clip: np.ndarray  # (N, 4) float64 clip coordinates
    snapped: np.ndarray  # (N, 2) int32 pixel position in 1/256 px (where outcode == 0)
    outcode: np.ndarray  # (N,) uint8: bit p set where the vertex is outside clip plane p


class Tris(NamedTuple):
    """Per triangle (M), from ``setup_triangles``."""

    coords: np.ndarray  # (M, 6) int32 snapped coordinates, canonical orientation
    bbox: np.ndarray  # (M, 4) int32 inclusive sample box (sx0, sx1, sy0, sy1)
    status: np.ndarray  # (M,) int8: 0 rejected, 1 one primitive, 2 needs clipping
    qplane: np.ndarray  # (M, 3) float64: Q = 1/w = a sx + b sy + c


class Pieces(NamedTuple):
    """The clipped triangles' pieces (K), from ``clip_triangles``."""

    todo: np.ndarray  # (T,) int64 the triangles clipped (status 2), increasing
    first: np.ndarray  # (T + 1,) int64: the pieces of todo[i] are first[i] .. first[i + 1] - 1
    coords: np.ndarray  # (K, 6) int32, as Tris.coords
    bbox: np.ndarray  # (K, 4) int32, as Tris.bbox
    parent: np.ndarray  # (K,) int64 the triangle of each piece


class Bins(NamedTuple):
    """Per-tile primitive lists: references r < M are triangles, r >= M pieces r - M."""

    first: np.ndarray  # (tiles + 1,) int64: tile k's list is lists[first[k]:first[k + 1]]
    lists: np.ndarray  # int32 or int64


class DepthRange(NamedTuple):
    """The per-sample near/far clip on Q = 1/w."""

    q_lo: float
    q_hi: float


class Visible(NamedTuple):
    """The visibility pass's output."""

    tri_id: np.ndarray  # (nH, nW) int32
    depth: np.ndarray  # (nH, nW) float32, or (0, 0): not written


class Tables(NamedTuple):
    """Per-vertex tables of the interpolation pass (N rows, float64)."""

    dtab: np.ndarray  # (N, Cd) values with per-pixel derivatives
    vtab: np.ndarray  # (N, Cv) values only
    ntab: np.ndarray  # (N, 3k), k in {0, 1}: normals (renormalized after interpolation)


class Outs(NamedTuple):
    """The interpolation pass's outputs, (nH, nW, C) each (zero-width ones are not written)."""

    d: np.ndarray  # (.., Cd) values of dtab
    dx: np.ndarray  # (.., Cd) d/dx per pixel
    dy: np.ndarray  # (.., Cd) d/dy per pixel
    v: np.ndarray  # (.., Cv) values of vtab
    normal: np.ndarray  # (.., 3k)
    w: np.ndarray  # (.., k), k in {0, 1}: depth w = 1 / Q


class Scales(NamedTuple):
    """What ``lod`` and ``dyadic_scale`` are computed for."""

    texels_u: float  # texture width in texels (lod)
    texels_v: float  # texture height in texels (lod)
    coord: int  # the coordinate of Veryovka eq. 5: 0 u, 1 v
    log2_period: float  # log2 of eq. 5's w (pixels)


# --- Vertices, clipping, triangle setup


@njit
def _plane_dist(p, x, y, z, w, guard):
    if p == 0:
        return z + w  # near: z_ndc >= -1
    if p == 1:
        return w - z  # far: z_ndc <= 1
    if p == 2:
        return x + guard * w
    if p == 3:
        return guard * w - x
    if p == 4:
        return y + guard * w
    return guard * w - y


@njit
def _snap(cx, cy, w, width, height):
    """Clip (cx, cy, ., w) -> ``(X, Y)`` int64, the pixel position in 1/256 px (round half up)."""
    px, py = pixel_of(cx, cy, w, width, height)
    return np.int64(math.floor(px * 256.0 + 0.5)), np.int64(math.floor(py * 256.0 + 0.5))


@njit
def _signed_area(c):
    """Twice the signed area of snapped ``c = (X0, Y0, X1, Y1, X2, Y2)``, screen y down (int64)."""
    x0 = np.int64(c[0])
    y0 = np.int64(c[1])
    return (np.int64(c[2]) - x0) * (np.int64(c[5]) - y0) - (np.int64(c[3]) - y0) * (
        np.int64(c[4]) - x0
    )


@njit
def _lex_greater(a, b):
    for i in range(4):
        if a[i] > b[i]:
            return True
        if a[i] < b[i]:
            return False
    return False


@njit
def _clip_polygon(v0, v1, v2, guard, poly, tmp):
    """Sutherland-Hodgman clip of a triangle against the six planes in homogeneous clip space,
    into ``poly`` (MAX_POLY + 1, 4); returns its vertex count. Edge intersections are computed
    from the lexicographically smaller endpoint, so two triangles sharing an edge get
    bit-identical clipped vertices (watertight clipping)."""
    for k in range(4):
        poly[0, k] = v0[k]
        poly[1, k] = v1[k]
        poly[2, k] = v2[k]
    count = 3
    for p in range(N_PLANES):
        if count == 0:
            return 0
        out = 0
        for i in range(count):
            j = (i + 1) % count
            da = _plane_dist(p, poly[i, 0], poly[i, 1], poly[i, 2], poly[i, 3], guard)
            db = _plane_dist(p, poly[j, 0], poly[j, 1], poly[j, 2], poly[j, 3], guard)
            if da >= 0.0:
                for k in range(4):
                    tmp[out, k] = poly[i, k]
                out += 1
            if (da >= 0.0) != (db >= 0.0):
                # canonical order of the endpoints -> identical intersection for shared edges
                a, b, dA, dB = (j, i, db, da) if _lex_greater(poly[i], poly[j]) else (i, j, da, db)
                s = dA / (dA - dB)
                for k in range(4):
                    tmp[out, k] = poly[a, k] + s * (poly[b, k] - poly[a, k])
                out += 1
        count = out
        for i in range(count):
            for k in range(4):
                poly[i, k] = tmp[i, k]
    return count


@njit
def _lam_rows(v0, v1, v2, nw, nh):
    """``(det, M^-1 S row-major)`` for M = [[x0 x1 x2], [y0 y1 y2], [w0 w1 w2]] (clip x, y, w of
    the exact vertices, ``vi = (xi, yi, wi)``) and S mapping sample (sx, sy, 1) to (ndc_x, ndc_y,
    1) = (2 sx / nW + 1/nW - 1, 1 - 1/nH - 2 sy / nH, 1): row i gives lambda'_i = b_i / w.
    det == 0: the triangle's plane passes through the eye."""
    x0, y0, w0 = v0
    x1, y1, w1 = v1
    x2, y2, w2 = v2
    a00 = y1 * w2 - y2 * w1
    a01 = x2 * w1 - x1 * w2
    a02 = x1 * y2 - x2 * y1
    a10 = y2 * w0 - y0 * w2
    a11 = x0 * w2 - x2 * w0
    a12 = x2 * y0 - x0 * y2
    a20 = y0 * w1 - y1 * w0
    a21 = x1 * w0 - x0 * w1
    a22 = x0 * y1 - x1 * y0
    det = x0 * a00 + x1 * a10 + x2 * a20
    inv = 1.0 / det if det != 0.0 else 0.0
    sxx = 2.0 / nw
    sx1 = 1.0 / nw - 1.0
    syy = -2.0 / nh
    sy1 = 1.0 - 1.0 / nh
    return (
        det,
        a00 * inv * sxx,
        a01 * inv * syy,
        (a00 * sx1 + a01 * sy1 + a02) * inv,
        a10 * inv * sxx,
        a11 * inv * syy,
        (a10 * sx1 + a11 * sy1 + a12) * inv,
        a20 * inv * sxx,
        a21 * inv * syy,
        (a20 * sx1 + a21 * sy1 + a22) * inv,
    )


@banded("positions")
def transform_vertices(lo, hi, positions, vp, grid, guard, verts):
    """Vertex stage: clip = VP (p, 1) (``clip_of``: a fixed evaluation order, no BLAS, no FMA
    contraction), the clip-plane outcode bits, and for vertices inside every plane the position
    snapped to 1/256 px (the same ``_snap`` the clipper uses, so shared vertices agree bitwise)."""
    clip, snapped, outcode = verts
    width = grid.width
    height = grid.height
    for i in range(lo, hi):
        cx, cy, cz, cw = clip_of(vp, (positions[i, 0], positions[i, 1], positions[i, 2]))
        clip[i, 0] = cx
        clip[i, 1] = cy
        clip[i, 2] = cz
        clip[i, 3] = cw
        code = 0
        for p in range(N_PLANES):
            if _plane_dist(p, cx, cy, cz, cw, guard) < 0.0:
                code |= 1 << p
        outcode[i] = code
        sx, sy = _snap(cx, cy, cw, width, height) if code == 0 else (0, 0)
        snapped[i, 0] = sx
        snapped[i, 1] = sy


@njit
def _sample_bbox(c, n, nw, nh):
    """Inclusive sample box ``(sx0, sx1, sy0, sy1)`` of snapped ``c`` on the n-times grid. In
    units of 1/(512 n) px, X is 2 n X and sample s is centred at 512 s + 256, so the first sample
    right of xmin is ceil((xmin - 256) / 512) (shifts floor)."""
    c0, c1, c2, c3, c4, c5 = c
    xmin = np.int64(min(c0, min(c2, c4))) * 2 * n
    xmax = np.int64(max(c0, max(c2, c4))) * 2 * n
    ymin = np.int64(min(c1, min(c3, c5))) * 2 * n
    ymax = np.int64(max(c1, max(c3, c5))) * 2 * n
    sx0 = max(-((256 - xmin) >> 9), 0)
    sx1 = min((xmax - 256) >> 9, nw - 1)
    sy0 = max(-((256 - ymin) >> 9), 0)
    sy1 = min((ymax - 256) >> 9, nh - 1)
    return sx0, sx1, sy0, sy1


@njit(inline="always")
def _primitive(c, cull, n, nw, nh):
    """``(keep, c, box)``: snapped ``c`` in canonical orientation (vertices 1 and 2 swapped where
    needed so that the interior is where all edge functions are >= 0) and its ``_sample_bbox``;
    keep is False for a zero-area or culled primitive, or one covering no sample centre."""
    area = _signed_area(c)
    # Screen y points down, so a triangle counter-clockwise in NDC (front-facing in GL) has area < 0.
    keep = area != 0 and not (cull == 1 and area > 0)
    c0, c1, c2, c3, c4, c5 = c
    if area < 0:
        c2, c3, c4, c5 = c4, c5, c2, c3
    c = (c0, c1, c2, c3, c4, c5)
    box = _sample_bbox(c, n, nw, nh)
    return keep and box[0] <= box[1] and box[2] <= box[3], c, box


# The per-primitive rows (a whole triangle's row t < M of coords / bbox, else a clipped piece's
# row t - M of the pieces' coords / bbox) are read as scalars in the loops themselves: a row
# view, or an array passed to a helper (inlined or not), updates the array's reference count
# (atomically, on a cache line the threads share), which in the binning and visibility loops
# cost 2-4x the loops' own work (benchmarks/README.md, cold start).


@banded("counts")
def setup_triangles(lo, hi, verts, faces, grid, setup, tris, counts):
    """Per triangle, over chunks of ``setup.chunk``: trivial reject, the depth plane qplane[t] =
    (a, b, c) with Q = 1/w = a sx + b sy + c (exact vertices), and status[t]: 0 rejected, 1 one
    primitive (coords[t], bbox[t] from ``_primitive``; counts[c, tile] += 1 for every tile it
    touches), 2 needs clipping (counted later by ``bin_count_clipped``)."""
    clip, snapped, outcode = verts
    coords, bbox, status, qplane = tris
    n, nw, nh, shift, tiles_x = grid.n, grid.nw, grid.nh, grid.shift, grid.tiles_x
    _, cull, chunk = setup
    m = faces.shape[0]
    for c in range(lo, hi):
        for t in range(c * chunk, min(m, (c + 1) * chunk)):
            i0 = faces[t, 0]
            i1 = faces[t, 1]
            i2 = faces[t, 2]
            status[t] = 0
            o0 = outcode[i0]
            o1 = outcode[i1]
            o2 = outcode[i2]
            if (o0 & o1 & o2) != 0:
                continue  # all three vertices outside one plane
            clipped = (o0 | o1 | o2) != 0
            sx0 = sx1 = sy0 = sy1 = 0
            if not clipped:  # scalars, not row views (see above)
                x0, y0 = snapped[i0, 0], snapped[i0, 1]
                x1, y1 = snapped[i1, 0], snapped[i1, 1]
                x2, y2 = snapped[i2, 0], snapped[i2, 1]
                keep, c6, box = _primitive((x0, y0, x1, y1, x2, y2), cull, n, nw, nh)
                if not keep:
                    continue
                for q in range(6):
                    coords[t, q] = c6[q]
                sx0, sx1, sy0, sy1 = box
            det, l00, l01, l02, l10, l11, l12, l20, l21, l22 = _lam_rows(
                (clip[i0, 0], clip[i0, 1], clip[i0, 3]),
                (clip[i1, 0], clip[i1, 1], clip[i1, 3]),
                (clip[i2, 0], clip[i2, 1], clip[i2, 3]),
                nw,
                nh,
            )
            if det == 0.0 or not math.isfinite(det):
                continue  # the triangle's plane passes through the eye: it projects to a line
            qplane[t, 0] = l00 + l10 + l20
            qplane[t, 1] = l01 + l11 + l21
            qplane[t, 2] = l02 + l12 + l22
            if clipped:
                status[t] = 2
                continue
            status[t] = 1
            bbox[t, 0] = sx0
            bbox[t, 1] = sx1
            bbox[t, 2] = sy0
            bbox[t, 3] = sy1
            for ty in range(sy0 >> shift, (sy1 >> shift) + 1):  # as bin_count_clipped, inline
                for tx in range(sx0 >> shift, (sx1 >> shift) + 1):
                    counts[c, ty * tiles_x + tx] += 1


@njit
def clip_triangles(clip, faces, todo, grid, setup, max_out):
    """Clip the triangles ``todo`` (status 2), fan-triangulate and snap the result: the fields
    of :class:`Pieces` after ``todo``, in the order of ``todo`` (deterministic); pieces that
    cover no sample centre are dropped."""
    width, height, n, nw, nh = grid.width, grid.height, grid.n, grid.nw, grid.nh
    guard, cull, _ = setup
    sub = np.empty((max_out, 6), dtype=np.int32)
    sub_bbox = np.empty((max_out, 4), dtype=np.int32)
    parent = np.empty(max_out, dtype=np.int64)
    first = np.zeros(todo.shape[0] + 1, dtype=np.int64)
    poly = np.empty((MAX_POLY + 1, 4))
    tmp = np.empty((MAX_POLY + 1, 4))
    pts = np.empty(2 * (MAX_POLY + 1), dtype=np.int64)
    k = 0
    for i in range(todo.shape[0]):
        t = todo[i]
        first[i] = k
        cnt = _clip_polygon(
            clip[faces[t, 0]], clip[faces[t, 1]], clip[faces[t, 2]], guard, poly, tmp
        )
        for j in range(cnt):
            pts[2 * j], pts[2 * j + 1] = _snap(poly[j, 0], poly[j, 1], poly[j, 3], width, height)
        for j in range(1, cnt - 1):
            c = (pts[0], pts[1], pts[2 * j], pts[2 * j + 1], pts[2 * j + 2], pts[2 * j + 3])
            keep, c, box = _primitive(c, cull, n, nw, nh)
            if not keep:
                continue
            for q in range(6):
                sub[k, q] = c[q]
            for q in range(4):
                sub_bbox[k, q] = box[q]
            parent[k] = t
            k += 1
    first[todo.shape[0]] = k
    return sub[:k].copy(), sub_bbox[:k].copy(), parent[:k].copy(), first


# --- Binning and visibility


@njit
def bin_count_clipped(pieces, grid, chunk, counts):
    """Add the clipped triangles' pieces to the tile counts of their triangle's chunk."""
    todo, first, _, bbox, _ = pieces
    shift = grid.shift
    tiles_x = grid.tiles_x
    for i in range(todo.shape[0]):
        c = todo[i] // chunk
        for j in range(first[i], first[i + 1]):
            sx0, sx1, sy0, sy1 = bbox[j, 0], bbox[j, 1], bbox[j, 2], bbox[j, 3]
            for ty in range(sy0 >> shift, (sy1 >> shift) + 1):
                for tx in range(sx0 >> shift, (sx1 >> shift) + 1):
                    counts[c, ty * tiles_x + tx] += 1


@banded("offsets")
def bin_fill(c_lo, c_hi, tris, pieces, grid, setup, offsets, lists):
    """Write primitive references into per-tile lists (the traversal of the counts), so every
    tile's list is in increasing triangle order whatever the thread count. ``offsets[c, k]``:
    where chunk c's references of tile k start in ``lists``."""
    _, bbox, status, _ = tris
    todo, sub_first, _, sub_bbox, _ = pieces
    shift = grid.shift
    tiles_x = grid.tiles_x
    chunk = setup.chunk
    m = status.shape[0]
    for c in range(c_lo, c_hi):
        lo = c * chunk
        hi = min(m, lo + chunk)
        cur = np.searchsorted(todo, lo)
        cursor = offsets[c].copy()
        for t in range(lo, hi):
            st = status[t]
            if st == 0:
                continue
            if st == 1:
                first, last = t, t + 1
            else:
                first, last = m + sub_first[cur], m + sub_first[cur + 1]
                cur += 1
            for ref in range(first, last):
                if ref < m:
                    sx0, sx1, sy0, sy1 = bbox[ref, 0], bbox[ref, 1], bbox[ref, 2], bbox[ref, 3]
                else:
                    r = ref - m
                    sx0, sx1 = sub_bbox[r, 0], sub_bbox[r, 1]
                    sy0, sy1 = sub_bbox[r, 2], sub_bbox[r, 3]
                for ty in range(sy0 >> shift, (sy1 >> shift) + 1):
                    for tx in range(sx0 >> shift, (sx1 >> shift) + 1):
                        k = ty * tiles_x + tx
                        lists[cursor[k]] = ref
                        cursor[k] += 1


@njit
def _edge_setup(xa, ya, xb, yb, n):
    """Edge a->b of the canonical (area > 0) triangle, vertices in 1/256 px: E(sx, sy) = A sx +
    B sy + C (int64), with the top-left bias folded into C so that a sample is inside where
    E >= 0 for all three edges."""
    ax = np.int64(xa) * 2 * n
    ay = np.int64(ya) * 2 * n
    bx = np.int64(xb) * 2 * n
    by = np.int64(yb) * 2 * n
    dx = bx - ax
    dy = by - ay
    # Top-left rule for y-down screens with the interior where E > 0: left edges go up
    # (dy < 0), top edges are horizontal going right (dy == 0, dx > 0); others exclude E == 0.
    bias = 0 if (dy < 0 or (dy == 0 and dx > 0)) else 1
    return -dy * 512, dx * 512, dx * (256 - ay) - dy * (256 - ax) - bias


@njit
def _tile_rect(k, tiles_x, tile, nw, nh):
    """Sample rectangle [x0, x1) x [y0, y1) of tile k: ``(x0, y0, x1, y1)``."""
    ty = k // tiles_x
    tx = k - ty * tiles_x
    x0 = tx * tile
    y0 = ty * tile
    return x0, y0, min(x0 + tile, nw), min(y0 + tile, nh)


@njit
def _prim_in_tile(c, b, n, rect):
    """A primitive's sample box ``b`` clipped to the tile ``rect`` and its three edge functions."""
    c0, c1, c2, c3, c4, c5 = c
    x0, y0, x1, y1 = rect
    sx0 = max(np.int64(b[0]), x0)
    sx1 = min(np.int64(b[1]), x1 - 1)
    sy0 = max(np.int64(b[2]), y0)
    sy1 = min(np.int64(b[3]), y1 - 1)
    A0, B0, C0 = _edge_setup(c2, c3, c4, c5, n)  # edge 1 -> 2
    A1, B1, C1 = _edge_setup(c4, c5, c0, c1, n)  # edge 2 -> 0
    A2, B2, C2 = _edge_setup(c0, c1, c2, c3, n)  # edge 0 -> 1
    return sx0, sx1, sy0, sy1, A0, B0, C0, A1, B1, C1, A2, B2, C2


def _tiles(tris, pieces, bins, *_):
    """The loop length of the tile kernels: one task per tile."""
    return bins.first.shape[0] - 1


#: Modes of the tile kernel: depth-tested visibility, or the debug count of claims per sample.
VISIBILITY, COUNT = 0, 1


@specialised
def _raster_for(mode):
    """The tile kernel of ``mode`` (``raster_visibility`` or ``raster_count``): one coverage loop,
    the other mode's code pruned before typing."""

    @banded(_tiles)
    def raster(lo, hi, tris, pieces, bins, grid, depth_range, out):
        coords, bbox, _, qplane = tris
        _, _, sub, sub_bbox, sub_parent = pieces
        tile_first, tile_lists = bins
        n, nw, nh, tile, tiles_x = grid.n, grid.nw, grid.nh, grid.tile, grid.tiles_x
        q_lo, q_hi = depth_range
        m = coords.shape[0]
        if mode == VISIBILITY:
            tri_id, depth = out
        for k in range(lo, hi):
            x0, y0, x1, y1 = _tile_rect(k, tiles_x, tile, nw, nh)
            if mode == VISIBILITY:
                qbuf = np.full((y1 - y0, x1 - x0), -np.inf)
                ibuf = np.full((y1 - y0, x1 - x0), -1, dtype=np.int32)
            for e in range(tile_first[k], tile_first[k + 1]):
                ref = tile_lists[e]
                if ref < m:  # scalars, not row views (see above)
                    t = ref
                    c = (
                        coords[ref, 0],
                        coords[ref, 1],
                        coords[ref, 2],
                        coords[ref, 3],
                        coords[ref, 4],
                        coords[ref, 5],
                    )
                    b = (bbox[ref, 0], bbox[ref, 1], bbox[ref, 2], bbox[ref, 3])
                else:
                    r = ref - m
                    t = sub_parent[r]
                    c = (sub[r, 0], sub[r, 1], sub[r, 2], sub[r, 3], sub[r, 4], sub[r, 5])
                    b = (sub_bbox[r, 0], sub_bbox[r, 1], sub_bbox[r, 2], sub_bbox[r, 3])
                sx0, sx1, sy0, sy1, A0, B0, C0, A1, B1, C1, A2, B2, C2 = _prim_in_tile(
                    c, b, n, (x0, y0, x1, y1)
                )
                qa = qplane[t, 0]
                qb = qplane[t, 1]
                qc = qplane[t, 2]
                for sy in range(sy0, sy1 + 1):
                    e0 = A0 * sx0 + B0 * sy + C0
                    e1 = A1 * sx0 + B1 * sy + C1
                    e2 = A2 * sx0 + B2 * sy + C2
                    for sx in range(sx0, sx1 + 1):
                        if (e0 | e1 | e2) >= 0:
                            q = qa * sx + qb * sy + qc
                            # per-sample depth clip (as GL's): snapping may cover a sample whose
                            # exact point lies beyond the near/far plane (there Q -> 0 at a horizon)
                            if mode == COUNT:
                                if q_lo <= q <= q_hi:
                                    out[sy, sx] += 1
                            elif q > qbuf[sy - y0, sx - x0] and q_lo <= q <= q_hi:
                                qbuf[sy - y0, sx - x0] = q
                                ibuf[sy - y0, sx - x0] = t
                        e0 += A0
                        e1 += A1
                        e2 += A2
            if mode == VISIBILITY:
                for sy in range(y0, y1):
                    for sx in range(x0, x1):
                        tri_id[sy, sx] = ibuf[sy - y0, sx - x0]
                if depth.shape[0] > 0:
                    for sy in range(y0, y1):
                        for sx in range(x0, x1):
                            if ibuf[sy - y0, sx - x0] < 0:
                                depth[sy, sx] = np.inf
                            else:
                                depth[sy, sx] = 1.0 / qbuf[sy - y0, sx - x0]

    return raster


#: Depth-tested visibility, one tile per task: out.tri_id (nH, nW) int32 gets the nearest parent
#: triangle index (-1 where empty). Depth is Q = 1/w of the exact vertices (larger is nearer);
#: ties keep the earlier primitive (lists are in increasing triangle order), so the result is
#: independent of the thread count and of the tile size. Samples whose exact Q lies outside
#: [q_lo, q_hi] (beyond the far/near plane, with a relative slack) are not covered. out.depth
#: (nH, nW) float32, or shape (0, 0): also w = 1 / Q of the winner (+inf where empty), the value
#: ``interp_depth`` computes from the same plane (so bit-identical), without its second pass.
raster_visibility = _raster_for(VISIBILITY)
#: Debug: out[sy, sx] (int32) += how many primitives claim each sample: the coverage rule and the
#: per-sample near/far clip of ``raster_visibility``, without the depth test between them.
raster_count = _raster_for(COUNT)


# --- Interpolation: depth, barycentrics, and one fused pass over the requested per-vertex tables


@njit
def mark_visible(tri_id, mark):
    """mark[t] = 1 for every triangle that owns at least one sample."""
    for sy in range(tri_id.shape[0]):
        for sx in range(tri_id.shape[1]):
            t = tri_id[sy, sx]
            if t >= 0:
                mark[t] = 1


@banded("faces")
def lam_for_marked(lo, hi, clip, faces, mark, grid, lam):
    """lam[t] (3, 3) for every marked triangle (see _lam_rows); others are left untouched."""
    nw = grid.nw
    nh = grid.nh
    for t in range(lo, hi):
        if mark[t] == 0:
            continue
        i0 = faces[t, 0]
        i1 = faces[t, 1]
        i2 = faces[t, 2]
        r = _lam_rows(
            (clip[i0, 0], clip[i0, 1], clip[i0, 3]),
            (clip[i1, 0], clip[i1, 1], clip[i1, 3]),
            (clip[i2, 0], clip[i2, 1], clip[i2, 3]),
            nw,
            nh,
        )
        for i in range(9):
            lam[t, i // 3, i % 3] = r[i + 1]


@njit
def _lambdas(lam, t, sx, sy):
    """lambda'_i = b_i / w of triangle t at sample (sx, sy) (affine in the sample position)."""
    return (
        lam[t, 0, 0] * sx + lam[t, 0, 1] * sy + lam[t, 0, 2],
        lam[t, 1, 0] * sx + lam[t, 1, 1] * sy + lam[t, 1, 2],
        lam[t, 2, 0] * sx + lam[t, 2, 1] * sy + lam[t, 2, 2],
    )


@banded("tri_id")
def interp_depth(lo, hi, tri_id, qplane, depth):
    """depth = w = 1 / Q (eye-space distance along the view axis); +inf where empty."""
    for sy in range(lo, hi):
        for sx in range(tri_id.shape[1]):
            t = tri_id[sy, sx]
            depth[sy, sx] = (
                np.inf if t < 0 else 1.0 / (qplane[t, 0] * sx + qplane[t, 1] * sy + qplane[t, 2])
            )


@banded("tri_id")
def interp_bary(lo, hi, tri_id, lam, bary):
    """Perspective-correct barycentrics b_i = lambda'_i / Q; 0 where empty."""
    for sy in range(lo, hi):
        for sx in range(tri_id.shape[1]):
            t = tri_id[sy, sx]
            if t < 0:
                for i in range(3):
                    bary[sy, sx, i] = 0.0
                continue
            l0, l1, l2 = _lambdas(lam, t, sx, sy)
            q = l0 + l1 + l2
            inv_q = 1.0 / q  # one division per sample (divisions dominate these kernels)
            bary[sy, sx, 0] = l0 * inv_q
            bary[sy, sx, 1] = l1 * inv_q
            bary[sy, sx, 2] = l2 * inv_q


@banded("tri_id")
def interp_ndc_z(lo, hi, tri_id, lam, faces, z, ndc):
    """OpenGL NDC depth z_clip / w_clip: z_clip interpolated as a value (``z (N,)`` float64, the
    vertices' clip z), divided by w = 1 / Q, in float64; 1 where empty."""
    for sy in range(lo, hi):
        for sx in range(tri_id.shape[1]):
            t = tri_id[sy, sx]
            if t < 0:
                ndc[sy, sx] = 1.0
                continue
            l0, l1, l2 = _lambdas(lam, t, sx, sy)
            q = l0 + l1 + l2
            inv_q = 1.0 / q
            zc = (l0 * z[faces[t, 0]] + l1 * z[faces[t, 1]] + l2 * z[faces[t, 2]]) * inv_q
            ndc[sy, sx] = zc / inv_q


@specialised
def _interp_for(full):
    """``interp_fused`` (``full`` False) or ``interp_fused_full`` (True)."""

    @banded("tri_id")
    def interp(lo, hi, tri_id, lam, faces, n, tables, outs):
        dtab, vtab, ntab = tables
        dout, dxout, dyout, vout, nout, wout = outs
        if full:  # loop counts fixed at compile time (~1.5x faster)
            cd = 2
            cv = 0
            k_n = 1
            k_w = 1
        else:
            cd = dtab.shape[1]
            cv = vtab.shape[1]
            k_n = ntab.shape[1] // 3
            k_w = wout.shape[2]
        for sy in range(lo, hi):
            for sx in range(tri_id.shape[1]):
                t = tri_id[sy, sx]
                if t < 0:
                    for c in range(k_w):
                        wout[sy, sx, c] = np.inf
                    for c in range(cd):
                        dout[sy, sx, c] = 0.0
                        dxout[sy, sx, c] = 0.0
                        dyout[sy, sx, c] = 0.0
                    for c in range(cv):
                        vout[sy, sx, c] = 0.0
                    for c in range(3 * k_n):
                        nout[sy, sx, c] = 0.0
                    continue
                l0, l1, l2 = _lambdas(lam, t, sx, sy)
                q = l0 + l1 + l2
                inv_q = 1.0 / q  # one division per sample (divisions dominate these kernels)
                for c in range(k_w):
                    wout[sy, sx, c] = inv_q
                i0 = faces[t, 0]
                i1 = faces[t, 1]
                i2 = faces[t, 2]
                if cd > 0:
                    ax0 = lam[t, 0, 0] * n
                    ax1 = lam[t, 1, 0] * n
                    ax2 = lam[t, 2, 0] * n
                    ay0 = lam[t, 0, 1] * n
                    ay1 = lam[t, 1, 1] * n
                    ay2 = lam[t, 2, 1] * n
                    qx = ax0 + ax1 + ax2
                    qy = ay0 + ay1 + ay2
                    for c in range(cd):
                        f0 = dtab[i0, c]
                        f1 = dtab[i1, c]
                        f2 = dtab[i2, c]
                        f = (l0 * f0 + l1 * f1 + l2 * f2) * inv_q
                        dout[sy, sx, c] = f
                        dxout[sy, sx, c] = (ax0 * f0 + ax1 * f1 + ax2 * f2 - f * qx) * inv_q
                        dyout[sy, sx, c] = (ay0 * f0 + ay1 * f1 + ay2 * f2 - f * qy) * inv_q
                for c in range(cv):
                    vout[sy, sx, c] = (
                        l0 * vtab[i0, c] + l1 * vtab[i1, c] + l2 * vtab[i2, c]
                    ) * inv_q
                for _ in range(k_n):
                    nx = l0 * ntab[i0, 0] + l1 * ntab[i1, 0] + l2 * ntab[i2, 0]
                    ny = l0 * ntab[i0, 1] + l1 * ntab[i1, 1] + l2 * ntab[i2, 1]
                    nz = l0 * ntab[i0, 2] + l1 * ntab[i1, 2] + l2 * ntab[i2, 2]
                    length = math.sqrt(nx * nx + ny * ny + nz * nz)
                    inv_len = 1.0 / length if length > 0.0 else 0.0
                    nout[sy, sx, 0] = nx * inv_len
                    nout[sy, sx, 1] = ny * inv_len
                    nout[sy, sx, 2] = nz * inv_len

    return interp


#: All requested per-vertex quantities in one pass over the samples, so each sample gathers its
#: triangle's planes and indices once (on dense meshes these gathers dominate). tables.dtab
#: (N, Cd): values with analytic per-pixel derivatives -> outs.d, outs.dx, outs.dy (nH, nW, Cd);
#: tables.vtab (N, Cv): values only -> outs.v; tables.ntab (N, 3k), k in {0, 1}: normals,
#: renormalized -> outs.normal; outs.w (nH, nW, k): depth w = 1 / Q (+inf where empty).
#: Zero-width tables cost nothing (their loops run zero times). Empty samples get 0. f = P / Q
#: and df = (dP - f dQ) / Q with d(sample)/d(pixel) = n.
interp_fused = _interp_for(False)
#: ``interp_fused`` for the full G-buffer: dtab (N, 2), ntab (N, 3), w (nH, nW, 1), no values
#: (vtab, v not read); the same operations in the same order (bit-identical results).
interp_fused_full = _interp_for(True)


@banded("tri_id")
def mesh_ids(lo, hi, tri_id, first_tri, mesh_id):
    """mesh_id (nH, nW) int32: the mesh of each sample's triangle, -1 where empty. first_tri
    (M + 1,) int64: cumulative face counts; the mesh of triangle t is ``searchsorted(first_tri,
    t, side="right") - 1`` (by bisection: meshes without faces are skipped)."""
    m = first_tri.shape[0]
    for sy in range(lo, hi):
        for sx in range(tri_id.shape[1]):
            t = tri_id[sy, sx]
            if t < 0:
                mesh_id[sy, sx] = -1
                continue
            lo = 0
            hi = m
            while lo < hi:
                mid = (lo + hi) >> 1
                if first_tri[mid] <= t:
                    lo = mid + 1
                else:
                    hi = mid
            mesh_id[sy, sx] = lo - 1


# --- Screen-space scales of the uv derivatives


@njit
def dyadic_scale_of(gx, gy, log2_period):
    """Veryovka eq. 5 with d = 1 / |grad_k| for the gradient ``(gx, gy)`` of the line coordinate
    per pixel: s = log2(d / w) = -log2 |grad_k| - log2 w, |grad_k| at least ``LOD_FLOOR``, s
    clipped to [-64, 64] (finite even where the coordinate is constant on screen)."""
    s = -math.log2(max(math.hypot(gx, gy), LOD_FLOOR)) - log2_period  # eq. 5
    return min(max(s, -64.0), 64.0)


@banded("tri_id")
def screen_scales(lo, hi, tri_id, duv_dx, duv_dy, scales, lod, dyadic):
    """lod (``gl_lod``) and dyadic (``dyadic_scale_of`` of the coordinate ``scales.coord``),
    (nH, nW) each or (nH, 0): not computed, of every sample from its uv derivatives duv_dx,
    duv_dy (nH, nW, 2) as stored (in float64); 0 where empty."""
    tw, th, k, log2_period = scales
    do_lod = lod.shape[1] > 0
    do_dyadic = dyadic.shape[1] > 0
    for sy in range(lo, hi):
        for sx in range(tri_id.shape[1]):
            empty = tri_id[sy, sx] < 0
            ux = np.float64(duv_dx[sy, sx, 0])
            vx = np.float64(duv_dx[sy, sx, 1])
            uy = np.float64(duv_dy[sy, sx, 0])
            vy = np.float64(duv_dy[sy, sx, 1])
            if do_lod:
                lod[sy, sx] = 0.0 if empty else gl_lod((ux, vx), (uy, vy), tw, th)
            if do_dyadic:
                if empty:
                    dyadic[sy, sx] = 0.0
                elif k == 1:
                    dyadic[sy, sx] = dyadic_scale_of(vx, vy, log2_period)
                else:
                    dyadic[sy, sx] = dyadic_scale_of(ux, uy, log2_period)


@banded("coverage")
def resolve_coverage(lo, hi, tri_id, n, coverage):
    """coverage[y, x] = fraction of the n x n samples of pixel (x, y) covered by a triangle."""
    nn = float(n * n)
    for y in range(lo, hi):
        for x in range(coverage.shape[1]):
            k = 0
            for j in range(n):
                for i in range(n):
                    if tri_id[y * n + j, x * n + i] >= 0:
                        k += 1
            coverage[y, x] = k / nn  # correctly rounded k / n^2

"""numba kernel of X-Toon shading (private; inputs validated by ``evaluation.shade_rgba``).

One parallel pass over the rows (a row per task, no reductions, so the result does not depend
on the thread count). Per covered sample (``mesh_id >= 0``): the unit shading normal, the tone
n . l (sec. 3) and the detail D of an attribute map (sec. 3.1, 3.2); then, over the row's
covered span, the bilinear edge-clamped lookup in the 2D toon texture (sec. 3) and the
straight-alpha RGBA (``_lookup_row``: the lookup as a loop of its own, without the first pass's
branches and calls, took the 1080p kernel from 12.8 to 8.6 ms, benchmarks/README.md), or the
grey attribute images of ``show``. float64 arithmetic in the order of the numpy code it replaces
(``unit_rows``, ``detail_values``, ``refnpr.formulas.xtoon``, ``XToonStyle.shade``), float32
storage; ``log`` and ``pow`` are libm's, numpy's may be its SIMD ones (an ulp apart in float64).

Where the normals or D come from elsewhere (shape abstraction, per-vertex detail, flow, a user
map) the caller passes the tone and D of the covered samples as flat arrays in row-major mask
order (``given``), with ``offsets[y]`` the index of row y's first covered sample.
"""

from __future__ import annotations

import math

import numpy as np

from refnpr._jit import banded, njit

#: ``detail_kind`` codes of :func:`shade_xtoon` (D computed in the kernel).
DETAIL_DEPTH_AXIS = 0  # sec. 3.1 LOA, z = the G-buffer depth (Fig. 2b)
DETAIL_DEPTH_EYE = 1  # sec. 3.1 LOA, z = distance to the eye (Fig. 2a)
DETAIL_FOCUS_AXIS = 2  # sec. 3.1 depth of field, z = G-buffer depth
DETAIL_FOCUS_EYE = 3  # sec. 3.1 depth of field, z = distance to the eye
DETAIL_ORIENTATION = 4  # sec. 3.2 |n . v|^r
DETAIL_HIGHLIGHT = 5  # sec. 3.2 |v . r|^s
DETAIL_NONE = 6  # D = 1
#: ``show`` codes.
SHOW_COLOR = 0
SHOW_DETAIL = 1
SHOW_INVERSE = 2
SHOW_TONE = 3
#: Distances are clamped to at least this before the log (``detail.TINY``).
TINY = 1e-9


@njit(inline="always")
def _clip01(x):
    return min(max(x, 0.0), 1.0)


@njit(inline="always")
def _srgb_to_linear(x):
    """IEC 61966-2-1, as ``texture.srgb_to_linear``."""
    if x <= 0.04045:
        return x / 12.92
    return ((x + 0.055) / 1.055) ** 2.4


@njit(inline="always")
def _lookup_row(tone_row, d_row, mrow, tex, rows, cols, modulate, diffuse, orow, xs, xe):
    """The straight-alpha RGBA of samples ``xs..xe - 1`` of one row into ``orow`` (the row's
    ``(nW * 4,)`` float32 view), 0 where ``mrow < 0``: the bilinear, edge-clamped lookup of
    (tone, D) = ``(tone_row[x], d_row[x])`` (float64, finite) in ``tex``, the toon texture's
    ``(rows * cols * 4,)`` float64 values. Branch-free over the span (an uncovered sample's
    lookup is computed and dropped); the texel offsets are unsigned (non-negative by
    construction), which spares every load numba's negative-index wraparound.
    """
    j_top = max(cols - 2, 0)
    i_top = max(rows - 2, 0)
    for x in range(xs, xe):
        mi = mrow[x]
        covered = mi >= 0
        m = max(mi, 0)
        # sec. 3: bilinear, edge-clamped lookup (texel centres, GL_LINEAR + CLAMP_TO_EDGE)
        tx = min(max(_clip01(tone_row[x]) * cols - 0.5, 0.0), cols - 1.0)
        ty = min(max(_clip01(d_row[x]) * rows - 0.5, 0.0), rows - 1.0)
        j0 = min(int(math.floor(tx)), j_top)
        i0 = min(int(math.floor(ty)), i_top)
        j1 = min(j0 + 1, cols - 1)
        i1 = min(i0 + 1, rows - 1)
        fx = tx - j0
        fy = ty - i0
        a00 = np.uint64((i0 * cols + j0) * 4)
        a01 = np.uint64((i0 * cols + j1) * 4)
        a10 = np.uint64((i1 * cols + j0) * 4)
        a11 = np.uint64((i1 * cols + j1) * 4)
        for ch in range(4):
            c = np.uint64(ch)
            top = tex[a00 + c] * (1.0 - fx) + tex[a01 + c] * fx
            bottom = tex[a10 + c] * (1.0 - fx) + tex[a11 + c] * fx
            v = top * (1.0 - fy) + bottom * fy
            if modulate and ch < 3:
                v = v * diffuse[m, ch]
            orow[4 * x + ch] = _clip01(v) if covered else 0.0


@banded("mesh_id")
def shade_xtoon(
    lo,
    hi,
    mesh_id,
    normal,
    depth,
    position,
    given,
    offsets,
    flat_tone,
    flat_detail,
    light_point,
    light_vec,
    eye,
    half_lambert,
    detail_kind,
    params,
    one_sided,
    texture,
    rows,
    cols,
    modulate,
    diffuse,
    show,
    out,
    bad_rows,
):
    """Shade every sample of ``out (nH, nW, 4)`` float32 (written in full; zero where empty).

    mesh_id (nH, nW) int: covered where >= 0 (object index for ``diffuse``).
    normal (nH, nW, 3) float: G-buffer normals (any shape when ``given``), normalized here.
    depth (nH, nW) float: view-axis depth (the ``*_AXIS`` maps; else any shape).
    position (nH, nW, 3) float: world positions (point light, eye distances, orientation,
    highlight; else any shape).
    given: tone and D are ``flat_tone``, ``flat_detail (K,)`` float64 at the covered samples in
    row-major order, row y's from ``offsets[y]`` (offsets (nH + 1,) int64); else computed here.
    light_point: the light is a point light at ``light_vec (3,)`` float64, else the direction
    towards it. eye (3,) float64. half_lambert: tone (n.l + 1) / 2, else clip(n.l, 0, 1).
    detail_kind: a ``DETAIL_*`` code; params (6,) float64: z_min, log(r) (depth), z_focus,
    z_min, and the near/far log ratios (focus: z_focus, z_focus - z_min, z_focus + z_min, log
    ratio near, log ratio far at 0..4), r (orientation, at 0), s (highlight, at 0).
    texture (rows * cols * 4,) float64: the toon texture's (rows, cols, 4) values (rows
    growing with D), flat; rows and cols: its shape.
    modulate: multiply the colour by ``diffuse (O, 3)`` float64 of the sample's object.
    show: a ``SHOW_*`` code. bad_rows (nH,) uint8: set to 1 where a tone or D is NaN.
    """
    nh, nw = mesh_id.shape
    # a row in two passes (colour): tone and D of each sample into the row's scratch, and the
    # span of covered samples; then the lookup over that span (``_lookup_row``), zeros around
    tone_row = np.empty(nw)
    d_row = np.empty(nw)
    for y in range(lo, hi):
        k = offsets[y] if given else 0
        bad_rows[y] = 0
        xs = nw  # covered span [xs, xe)
        xe = 0
        for x in range(nw):
            mi = mesh_id[y, x]
            if mi < 0:
                if show == SHOW_COLOR:
                    tone_row[x] = 0.0
                    d_row[x] = 0.0
                else:
                    out[y, x, 0] = 0.0
                    out[y, x, 1] = 0.0
                    out[y, x, 2] = 0.0
                    out[y, x, 3] = 0.0
                continue
            xs = min(xs, x)
            xe = x + 1
            if given:
                tone = flat_tone[k]
                d = flat_detail[k]
                k += 1
            else:
                nx = np.float64(normal[y, x, 0])  # unit_rows of the G-buffer normal
                ny = np.float64(normal[y, x, 1])
                nz = np.float64(normal[y, x, 2])
                length = math.sqrt(nx * nx + ny * ny + nz * nz)
                if length > 0.0:
                    nx = nx / length
                    ny = ny / length
                    nz = nz / length
                else:
                    nx = 0.0
                    ny = 0.0
                    nz = 0.0
                px = 0.0
                py = 0.0
                pz = 0.0
                if position.shape[0] == nh:
                    px = np.float64(position[y, x, 0])
                    py = np.float64(position[y, x, 1])
                    pz = np.float64(position[y, x, 2])
                lx = light_vec[0]
                ly = light_vec[1]
                lz = light_vec[2]
                if light_point:  # unit_rows(light.position - p)
                    lx = lx - px
                    ly = ly - py
                    lz = lz - pz
                    length = math.sqrt(lx * lx + ly * ly + lz * lz)
                    if length > 0.0:
                        lx = lx / length
                        ly = ly / length
                        lz = lz / length
                    else:
                        lx = 0.0
                        ly = 0.0
                        lz = 0.0
                n_dot_l = nx * lx + ny * ly + nz * lz
                if half_lambert:
                    tone = 0.5 * (n_dot_l + 1.0)  # half-Lambert: n.l mapped to [0, 1]
                else:
                    tone = _clip01(n_dot_l)  # sec. 3: tone from n.l, clamped
                if detail_kind <= DETAIL_FOCUS_EYE:
                    if detail_kind == DETAIL_DEPTH_AXIS or detail_kind == DETAIL_FOCUS_AXIS:
                        z = np.float64(depth[y, x])  # Fig. 2b
                    else:  # Fig. 2a: |p - eye|
                        ex = px - eye[0]
                        ey = py - eye[1]
                        ez = pz - eye[2]
                        z = math.sqrt(ex * ex + ey * ey + ez * ez)
                    z = max(z, TINY)
                    if detail_kind <= DETAIL_DEPTH_EYE:
                        d = 1.0 - math.log(z / params[0]) / params[1]  # sec. 3.1: 1 - log_r
                    elif z < params[0]:  # sec. 3.1, depth of field, near branch
                        d = 1.0 - math.log(z / params[1]) / params[3]
                    else:  # far branch
                        d = 1.0 - math.log(z / params[2]) / params[4]
                    d = _clip01(d)
                elif detail_kind <= DETAIL_HIGHLIGHT:
                    vx = eye[0] - px  # v = unit vector towards the eye
                    vy = eye[1] - py
                    vz = eye[2] - pz
                    length = max(math.sqrt(vx * vx + vy * vy + vz * vz), TINY)
                    vx = vx / length
                    vy = vy / length
                    vz = vz / length
                    if detail_kind == DETAIL_ORIENTATION:
                        c = nx * vx + ny * vy + nz * vz
                        c = min(max(c, -1.0), 1.0)
                        d = min(abs(c), 1.0) ** params[0]  # sec. 3.2: |n.v|^r
                    else:
                        two = 2.0 * n_dot_l  # r = 2 (n.l) n - l
                        rx = two * nx - lx
                        ry = two * ny - ly
                        rz = two * nz - lz
                        c = vx * rx + vy * ry + vz * rz
                        c = min(max(c, -1.0), 1.0)
                        base = max(c, 0.0) if one_sided else abs(c)
                        d = min(base, 1.0) ** params[0]  # sec. 3.2: |v.r|^s (Phong)
                else:
                    d = 1.0
            if tone != tone or d != d:
                bad_rows[y] = 1
                tone = 0.0
                d = 0.0
            if show != SHOW_COLOR:
                if show == SHOW_DETAIL:
                    value = d
                elif show == SHOW_INVERSE:
                    value = 1.0 - d
                else:
                    value = tone
                grey = _srgb_to_linear(_clip01(value))  # shown (sRGB) value = the quantity
                grey = _clip01(grey)
                out[y, x, 0] = grey
                out[y, x, 1] = grey
                out[y, x, 2] = grey
                out[y, x, 3] = 1.0
                continue
            tone_row[x] = tone
            d_row[x] = d
        if show == SHOW_COLOR:
            orow = out[y].reshape(-1)
            for i in range(4 * xs):
                orow[i] = 0.0
            for i in range(4 * max(xe, xs), 4 * nw):
                orow[i] = 0.0
            if xe > xs:
                _lookup_row(
                    tone_row,
                    d_row,
                    mesh_id[y],
                    texture,
                    rows,
                    cols,
                    modulate,
                    diffuse,
                    orow,
                    xs,
                    xe,
                )

"""numba kernels of the TAM / TAMISS styles (no validation here; see the calling modules).

The per-sample formulas are the scalar functions of :mod:`refnpr.formulas.tamiss` (the stroke
field, the fit's regressors and cubic) and :mod:`refnpr.formulas.lighting` (the darkness's
diffuse colour); the kernels compose them. Kernels take records: the frame record
(:class:`refnpr.styles._frame.Frame`) where they read the G-buffer, the style record
(``params.PARAMS.record`` / ``TAM_PARAMS.record``) for the parameters, and tuples of arrays for
the rest, unpacked into locals before their loops.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from refnpr._jit import banded, njit, specialised
from refnpr.device.lights import LIGHT_POINT, light_dir
from refnpr.device.vectors import dot, unit_scaled
from refnpr.formulas import lighting
from refnpr.formulas.tamiss import curve, moments
from refnpr.formulas.tamiss import field as rptam

from .params import TAM_PARAMS


def _inline(scalar):
    """The device function ``scalar`` (a formula's ``f.scalar``, a device-layer function)
    compiled into each kernel that calls it, as numba IR (``inline="always"``): the same
    function, one source, inlined before LLVM sees the loops. Measured on the 1080p teapot: the
    fragment gathering 58-60 ms so, 64-68 ms as calls that LLVM inlines (the loops' registers
    are allocated worse)."""
    return njit(inline="always")(scalar.py_func)


_diffuse = _inline(lighting.diffuse.scalar)
_term = _inline(lighting.illumination_term.scalar)
_dot = _inline(dot)
_unit_scaled = _inline(unit_scaled)
_light_dir = _inline(light_dir)
_darkness = _inline(rptam.darkness.scalar)
_hash01 = _inline(rptam.hash01.scalar)
_pack_id = _inline(rptam.pack_id.scalar)
_born_at = _inline(rptam.born_at.scalar)
_layer_frame = _inline(rptam.layer_frame.scalar)
_dyadic_scale = _inline(rptam.dyadic_scale.scalar)
_level_rule = _inline(rptam.level_rule.scalar)
_fade_in = _inline(rptam.fade_in.scalar)
_layer_density = _inline(rptam.layer_density.scalar)
_row_distance = _inline(rptam.row_distance.scalar)
_stroke_length = _inline(rptam.stroke_length.scalar)
_stroke_start = _inline(rptam.stroke_start.scalar)
_stroke_param = _inline(rptam.stroke_param.scalar)
_width_factor = _inline(rptam.width_factor.scalar)
_tam_opacity = _inline(rptam.tam_opacity.scalar)
_tam_coverage = _inline(rptam.tam_coverage.scalar)
_ink_over = _inline(rptam.ink_over.scalar)
_normalize_t = _inline(moments.normalize_t.scalar)
_regressors = _inline(moments.fragment_regressors.scalar)
_cubic = _inline(curve.cubic.scalar)
_cubic_slope = _inline(curve.cubic_slope.scalar)

_KX = rptam.KX
_KX7 = rptam.KX7
_M1 = np.uint64(0x9E3779B97F4A7C15)
#: The TAM record's code of density_mode "clip".
CLIP = TAM_PARAMS.code("density_mode", "clip")

_CHUNK = 512
_CAP = 256
#: Rows of the sample grid per band of ``raster_strips`` (a band is one index of its loop).
_BAND = 16


# ---------------------------------------------------------------------- tables


class InputTables(NamedTuple):
    """What ``sample_inputs`` reads beside the frame record.

    sample : (N,) int64 flat sample indices of the covered samples
    bary : (nH nW, 3) barycentrics (smooth derivatives; else a stand-in)
    charts : (T,) int64 chart per triangle
    faces : (T, 3) int64 into ``frames`` (V, 3, 2), the per-vertex [dP/du, dP/dv]
    sym_m : (8, 2, 2) the signed permutations; sym : (T,) int64 index of each triangle's
    offset : (T, 2) its chart's offset; group : (T,) int64 its chart's id group
    smooth, orient, shade : bool, what the pass computes
    """

    sample: np.ndarray
    bary: np.ndarray
    charts: np.ndarray
    faces: np.ndarray
    frames: np.ndarray
    sym_m: np.ndarray
    sym: np.ndarray
    offset: np.ndarray
    group: np.ndarray
    smooth: bool
    orient: bool
    shade: bool


class Layers(NamedTuple):
    """Per hatching layer: cos and sin of its angle, the darkness where it starts."""

    cos_a: np.ndarray
    sin_a: np.ndarray
    tone_lo: np.ndarray


class Chunks(NamedTuple):
    """Sample chunks of one ``field_gather`` call: chunk index, where its fragments go, the
    room there, and (output) how many it had."""

    index: np.ndarray
    dst_off: np.ndarray
    dst_cap: np.ndarray
    count: np.ndarray


class Runs(NamedTuple):
    """Runs of gathered fragments ``finish_fragments`` copies: from, length, to."""

    src_off: np.ndarray
    src_len: np.ndarray
    dst_off: np.ndarray


# ---------------------------------------------------------------------- charts


@njit
def _find(parent, i):
    root = i
    while parent[root] != root:
        root = parent[root]
    while parent[i] != root:  # path compression
        nxt = parent[i]
        parent[i] = root
        i = nxt
    return root


@njit
def chart_labels(faces, n_vertices):
    """(M,) int64 component label per face, labels 0..C-1 in order of first appearance."""
    parent = np.arange(n_vertices)
    for f in range(faces.shape[0]):
        a = _find(parent, faces[f, 0])
        for j in range(1, 3):
            b = _find(parent, faces[f, j])
            if a != b:
                if a < b:
                    parent[b] = a
                else:
                    parent[a] = b
                    a = b
    label_of_root = np.full(n_vertices, -1, dtype=np.int64)
    out = np.empty(faces.shape[0], dtype=np.int64)
    nxt = 0
    for f in range(faces.shape[0]):
        r = _find(parent, faces[f, 0])
        if label_of_root[r] < 0:
            label_of_root[r] = nxt
            nxt += 1
        out[f] = label_of_root[r]
    return out


# ---------------------------------------------------------------------- per-sample inputs


@njit(inline="always")
def _smooth_duv(g, n, d, dps, flat):
    """d(uv)/dx and d(uv)/dy ``(du_x, dv_x, du_y, dv_y)`` of the pixel footprints ``dps =
    (dP/dx, dP/dy)`` moved along the view ray onto the plane of the shading normal ``n``,
    dP_n = dP - (n . dP) / (n . D) D (D = ``d``, position - eye), by least squares in the
    interpolated frame ``g = (dP/du, dP/dv)``: duv = (F^T F)^-1 F^T dP_n. Where the frame is
    degenerate or the view grazes (|n . D| < 0.05 |D| |n|): the rasterizer's ``flat`` values."""
    gu, gv = g
    a00 = _dot(gu, gu)
    a01 = _dot(gu, gv)
    a11 = _dot(gv, gv)
    det = a00 * a11 - a01 * a01
    if not (det > 1e-12 * (a00 * a11) and det > 0.0):
        return flat
    nd = _dot(n, d)
    dlen = math.sqrt(_dot(d, d))
    if not (abs(nd) >= 0.05 * dlen * math.sqrt(_dot(n, n)) and dlen > 0.0):
        return flat
    du_x, dv_x = _footprint_uv(gu, gv, (a00, a01, a11, det), n, d, nd, dps[0])
    du_y, dv_y = _footprint_uv(gu, gv, (a00, a01, a11, det), n, d, nd, dps[1])
    return du_x, dv_x, du_y, dv_y


@njit(inline="always")
def _footprint_uv(gu, gv, a, n, d, nd, dp):
    """One footprint of :func:`_smooth_duv` (``a = (a00, a01, a11, det)`` of F^T F)."""
    a00, a01, a11, det = a
    lam = _dot(n, dp) / nd
    pn = (dp[0] - lam * d[0], dp[1] - lam * d[1], dp[2] - lam * d[2])
    r0 = _dot(gu, pn)
    r1 = _dot(gv, pn)
    return (a11 * r0 - a01 * r1) / det, (a00 * r1 - a01 * r0) / det


@njit
def _row3(a, i):
    return np.float64(a[i, 0]), np.float64(a[i, 1]), np.float64(a[i, 2])


@njit(inline="always")  # takes arrays: inlined, no reference counts per sample
def _frame_at(faces, frames, bary, tri, sp):
    """The vertex frames [dP/du, dP/dv] of triangle ``tri`` interpolated at sample ``sp``."""
    gu0 = 0.0
    gu1 = 0.0
    gu2 = 0.0
    gv0 = 0.0
    gv1 = 0.0
    gv2 = 0.0
    for c in range(3):
        v = faces[tri, c]
        b = np.float64(bary[sp, c])
        gu0 += b * frames[v, 0, 0]
        gu1 += b * frames[v, 1, 0]
        gu2 += b * frames[v, 2, 0]
        gv0 += b * frames[v, 0, 1]
        gv1 += b * frames[v, 1, 1]
        gv2 += b * frames[v, 2, 1]
    return (gu0, gu1, gu2), (gv0, gv1, gv2)


@banded(lambda frame, tables, out, chunk_max: chunk_max.shape[0])
def sample_inputs(lo, hi, frame, tables, out, chunk_max):
    """Per-sample field inputs of the covered samples ``tables.sample`` (flat indices of the
    frame's grid) into ``out = (uv, duv_dx, duv_dy, uv_scale, darkness, chart)`` ((N, 2) x 4,
    (N,), (N,) int64): uv, flat duv_dx / duv_dy and the uv_scale of the sample's object, chart
    ``charts[tri]``; with ``smooth`` the derivatives of :func:`_smooth_duv`; with ``orient``
    u' = M u + offset with M = ``sym_m[sym[tri]]`` (signed permutations) on uv, the derivatives
    and (|M|) the scale, and chart ``group[tri]``; with ``shade`` the darkness of the diffuse
    colour. ``chunk_max`` (chunks,) receives max |u' s| over each chunk of ``_CHUNK`` samples
    (NaN uv: inf)."""
    n_all = frame.cover.size
    tri_id = frame.cover.reshape(n_all)
    mesh_id = frame.mesh_id.reshape(n_all)
    uv = frame.uv.reshape((n_all, 2))
    duv_dx = frame.duv_dx.reshape((n_all, 2))
    duv_dy = frame.duv_dy.reshape((n_all, 2))
    normal = frame.normal.reshape((-1, 3))
    position = frame.position.reshape((-1, 3))
    dpos_dx = frame.dposition_dx.reshape((-1, 3))
    dpos_dy = frame.dposition_dy.reshape((-1, 3))
    scale = frame.materials.uv_scale
    ambient = frame.materials.ambient
    diffuse = frame.materials.diffuse
    kinds = frame.lights.kind
    vecs = frame.lights.vec
    units = frame.lights.unit
    colors = frame.lights.color
    eye = (frame.eye[0], frame.eye[1], frame.eye[2])
    sample, bary, charts, faces, frames, sym_m, sym, offset, group, smooth, orient, shade = tables
    out_uv, out_dx, out_dy, out_scale, out_dark, out_chart = out
    for ci in range(lo, hi):
        cmax = 0.0
        for i in range(ci * _CHUNK, min(sample.shape[0], (ci + 1) * _CHUNK)):
            sp = sample[i]
            tri = tri_id[sp]
            mi = max(mesh_id[sp], 0)
            su = scale[mi, 0]
            sv = scale[mi, 1]
            u0 = np.float64(uv[sp, 0])
            u1 = np.float64(uv[sp, 1])
            xu = np.float64(duv_dx[sp, 0])
            xv = np.float64(duv_dx[sp, 1])
            yu = np.float64(duv_dy[sp, 0])
            yv = np.float64(duv_dy[sp, 1])
            if smooth:
                g = _frame_at(faces, frames, bary, tri, sp)
                pos = _row3(position, sp)
                d = (pos[0] - eye[0], pos[1] - eye[1], pos[2] - eye[2])
                n = _row3(normal, sp)
                dps = (_row3(dpos_dx, sp), _row3(dpos_dy, sp))
                xu, xv, yu, yv = _smooth_duv(g, n, d, dps, (xu, xv, yu, yv))
            if orient:
                k = sym[tri]
                m00 = sym_m[k, 0, 0]
                m01 = sym_m[k, 0, 1]
                m10 = sym_m[k, 1, 0]
                m11 = sym_m[k, 1, 1]
                out_uv[i, 0] = (0.0 + m00 * u0 + m01 * u1) + offset[tri, 0]
                out_uv[i, 1] = (0.0 + m10 * u0 + m11 * u1) + offset[tri, 1]
                out_dx[i, 0] = 0.0 + m00 * xu + m01 * xv
                out_dx[i, 1] = 0.0 + m10 * xu + m11 * xv
                out_dy[i, 0] = 0.0 + m00 * yu + m01 * yv
                out_dy[i, 1] = 0.0 + m10 * yu + m11 * yv
                out_scale[i, 0] = 0.0 + abs(m00) * su + abs(m01) * sv
                out_scale[i, 1] = 0.0 + abs(m10) * su + abs(m11) * sv
                out_chart[i] = group[tri]
            else:
                out_uv[i, 0] = u0
                out_uv[i, 1] = u1
                out_dx[i, 0] = xu
                out_dx[i, 1] = xv
                out_dy[i, 0] = yu
                out_dy[i, 1] = yv
                out_scale[i, 0] = su
                out_scale[i, 1] = sv
                out_chart[i] = charts[tri]
            e_u = abs(out_uv[i, 0] * out_scale[i, 0])
            e_v = abs(out_uv[i, 1] * out_scale[i, 1])
            if e_u != e_u or e_v != e_v:
                cmax = np.inf  # NaN uv: the caller rejects it
            else:
                cmax = max(cmax, e_u, e_v)
            if shade:
                # the darkness of Veryovka eq. 1's diffuse colour m_a l_a + sum_i m_d f_d l_i;
                # f_d is lighting.diffuse with its normalizations (unit_scaled) hoisted: N once
                # per sample, a directional L once per frame (Lights.unit); clamped to 1
                nu = _unit_scaled(_row3(normal, sp))
                r = ambient[mi, 0]  # eq. 1: m_a l_a (Materials.ambient)
                g = ambient[mi, 1]
                b = ambient[mi, 2]
                for li in range(kinds.shape[0]):
                    if kinds[li] == LIGHT_POINT:
                        pos = _row3(position, sp)
                        vec = (vecs[li, 0], vecs[li, 1], vecs[li, 2])
                        lu = _unit_scaled(_light_dir(True, vec, pos))
                    else:
                        lu = (units[li, 0], units[li, 1], units[li, 2])
                    fd = _diffuse(nu, lu, False)  # eq. 1: f_d = max(N.L, 0)
                    fd = fd if fd <= 1.0 else 1.0  # unit vectors: N.L <= 1 up to rounding
                    r = _term(r, diffuse[mi, 0], fd, colors[li, 0])  # eq. 1: + m_d f_d l_i
                    g = _term(g, diffuse[mi, 1], fd, colors[li, 1])
                    b = _term(b, diffuse[mi, 2], fd, colors[li, 2])
                out_dark[i] = _darkness(r, g, b)
        chunk_max[ci] = cmax


# ---------------------------------------------------------------------- the stroke field


@njit(inline="always")
def _levels(s, max_level):
    """L, the top level enumerated (L + 1 while it fades in), the gain of levels <= L and of
    level L + 1 (``level_rule``, ``fade_in``) of a dyadic scale s."""
    big_l, f, thin = _level_rule(s, max_level)
    return big_l, big_l + 1 if f > 0.0 else big_l, thin, _fade_in(f)


@njit(inline="always")
def _level_rows(lev, levels, rho, q, hw_q):
    """Level ``lev`` of ``levels`` (:func:`_levels`): the density limit rho gain of its
    strokes, 2^lev, 2^-lev (a power of two: x * 2^-lev == x / 2^lev, bit for bit), the rows per
    unit of q and the first and last row within ``hw_q`` of q."""
    big_l, top, thin, alpha = levels
    gain = thin if lev <= big_l else alpha
    scale = float(1 << lev)
    rows = 7.0 * scale
    ry0 = int(math.floor((q - hw_q) * rows))
    return gain * rho, scale, 1.0 / scale, rows, ry0, int(math.floor((q + hw_q) * rows)) + 1


@njit(inline="always")
def _cells(ry, p, scale, half_cells):
    """Row ``ry``'s cell row gy and row r, the base seed set's column kx = KX[r] and kx / 7, p in
    cells of the row's seeds, and the first and last cell within ``half_cells`` of it."""
    gy = ry // 7
    r = ry - 7 * gy
    kx7 = _KX7[r]
    ps = p * scale - kx7
    gx0 = int(math.floor(ps - half_cells))
    return gy, r, _KX[r], kx7, ps, gx0, int(math.floor(ps + half_cells)) + 1


@njit(inline="always")
def _enumerate(style, frame, at, ink, capped):
    """``ink`` over the TAM strokes of one sample and layer (``frame = (p, q, d_p, d_q, s)`` of
    the layer, ``at = (rho, chart, layer)``): the strokes within hw_px = width (1 + width_jitter)
    / 2 + 0.5 across and end_px = 0.5 past their ends, in the order level, row, cell.

    ``capped`` False, the fast path, cheapest test first: a stroke is passed over before its
    length is hashed when its cell centre is farther from p than any length reaches (half the
    longest length plus end_px, with a margin far above rounding) or when its density test
    fails (tau < rho gain is both modes' opacity > 0). Returns -1.0 when more than ``_CAP``
    strokes could be candidates. ``capped`` True: only the first ``_CAP`` candidates (strokes
    within the band, before the density test) ink the sample, as docs/kit.md's ``tam-field``
    spells it. Where both return an ink it is the same bits.
    """
    p, q, d_p, d_q, s = frame
    rho, chart, layer = at
    if not (s == s):  # NaN scale
        return ink
    lam = style.length
    len_jit = style.length_jitter
    wid_jit = style.width_jitter
    width_px = style.width
    clip = style.density_mode == CLIP
    hw_px = 0.5 * width_px * (1.0 + wid_jit) + 0.5
    end_px = 0.5
    levels = _levels(s, style.max_level)
    n = 0  # fast: strokes that could be candidates (an upper bound); capped: candidates
    # divisions hoisted or made exact products (double division is slow): the same values
    hw_q = hw_px / d_q
    end_cells = end_px / d_p
    for lev in range(levels[1] + 1):
        limit, scale, inv_scale, rows, ry0, ry1 = _level_rows(lev, levels, rho, q, hw_q)
        if limit <= 0.0:
            continue
        half_cells = 0.5 * lam * (1.0 + len_jit) + end_cells * scale
        reach = 0.5 * lam * (1.0 + abs(len_jit)) + end_cells * scale
        for ry in range(ry0, ry1 + 1):
            dist = _row_distance(q, ry, rows, d_q)
            if dist > hw_px:
                continue
            gy, r, kx, kx7, ps, gx0, gx1 = _cells(ry, p, scale, half_cells)
            margin = reach + 1e-6 + 1e-9 * (abs(ps) + reach)
            for gx in range(gx0, gx1 + 1):
                if not _born_at(lev, gx, gy, r, kx):
                    continue  # inherited: enumerated at its birth level
                if not capped:
                    n += 1
                    if n > _CAP:
                        return -1.0
                    if abs(ps - gx) > margin:
                        continue  # beyond > end_px for every length
                sid = _pack_id(chart, layer, lev, gx, gy, r)
                tau = _hash01(sid, style.salt_tone)
                if not (capped or tau < limit):
                    continue  # opacity 0 in both modes
                length = _stroke_length(_hash01(sid, style.salt_length), lam, len_jit, inv_scale)
                t, beyond = _stroke_param(p, _stroke_start(gx, kx7, inv_scale, length), length, d_p)
                if beyond > end_px:
                    continue
                if capped:
                    n += 1
                    if n > _CAP:
                        return ink
                opacity = _tam_opacity(limit, tau, style.fade, clip)
                if opacity <= 0.0:
                    continue
                wf = _width_factor(_hash01(sid, style.salt_width), wid_jit)
                ink = _ink_over(ink, _tam_coverage(width_px, wf, dist, beyond) * opacity)
    return ink


#: :func:`_enumerate` as a call, for the rare capped path (a sample and layer with more than
#: ``_CAP`` candidates; the record holds numbers only): inlined at a second call site as well,
#: it made tam_pass compile 0.5 s longer.
_enumerate_capped = njit(_enumerate.py_func)


@njit(inline="always")
def _sample_args(uv, duv_dx, duv_dy, uv_scale, i):
    """A sample's (uv, duv_dx, duv_dy, uv_scale) as pairs (the arguments of layer_frame)."""
    return (
        (uv[i, 0], uv[i, 1]),
        (duv_dx[i, 0], duv_dx[i, 1]),
        (duv_dy[i, 0], duv_dy[i, 1]),
        (uv_scale[i, 0], uv_scale[i, 1]),
    )


@banded(lambda samples, layers, style, ink: (samples[0].shape[0] + _CHUNK - 1) // _CHUNK)
def tam_pass(lo, hi, samples, layers, style, ink):
    """``ink[i]`` = anti-aliased ink coverage 1 - prod(1 - a) of the TAM strokes over each of
    the N samples (``samples``: :func:`sample_inputs`' arrays), ``layers`` (:class:`Layers`),
    ``style`` the ``tam`` record: a binary (clip) or smooth (fade) density decision per sample."""
    uv, duv_dx, duv_dy, uv_scale, darkness, chart = samples
    cos_a, sin_a, tone_lo = layers
    for ci in range(lo, hi):
        for i in range(ci * _CHUNK, min(uv.shape[0], (ci + 1) * _CHUNK)):
            a_uv, a_dx, a_dy, a_scale = _sample_args(uv, duv_dx, duv_dy, uv_scale, i)
            total = 0.0
            for lay in range(cos_a.shape[0]):
                rho = _layer_density(darkness[i], tone_lo[lay], style.density)
                if rho <= 0.0:
                    continue
                p, q, d_p, d_q = _layer_frame(a_uv, a_dx, a_dy, a_scale, cos_a[lay], sin_a[lay])
                if not (d_q == d_q):
                    continue
                frame = (p, q, d_p, d_q, _dyadic_scale(d_q, style.period))
                at = (rho, chart[i], lay)
                fast = _enumerate(style, frame, at, total, False)
                total = fast if fast >= 0.0 else _enumerate_capped(style, frame, at, total, True)
            ink[i] = total


@banded(lambda chunks, samples, layers, style, out: chunks.index.shape[0])
def field_gather(lo, hi, chunks, samples, layers, style, out):
    """TAMISS fragments of the sample chunks ``chunks.index`` (``_CHUNK`` samples each) in one
    pass; ``style`` the ``tamiss`` record.

    A sample emits a fragment for every stroke within ``gather_width / 2`` pixels across whose
    t is in [0, 1] and that passes tau < rho gain (the enumeration of :func:`_enumerate`, end_px
    = 0, at most ``_CAP`` candidates per sample and layer). The fragments of chunk
    ``chunks.index[j]`` (ordered by sample, layer, level, row, cell) are written from
    ``chunks.dst_off[j]`` into ``out = (id, t, layer, birth level, sample index)``, at most
    ``chunks.dst_cap[j]`` of them; ``chunks.count[j]`` receives their number (which may exceed
    the room: then run the chunk again with room for all).
    """
    index, dst_off, dst_cap, count = chunks
    uv, duv_dx, duv_dy, uv_scale, darkness, chart = samples
    cos_a, sin_a, tone_lo = layers
    out_id, out_t, out_layer, out_level, out_src = out
    lam = style.length
    len_jit = style.length_jitter
    hw_px = 0.5 * style.gather_width
    for j in range(lo, hi):
        ci = index[j]
        base = dst_off[j]
        cap = dst_cap[j]
        k = 0
        for i in range(ci * _CHUNK, min(uv.shape[0], (ci + 1) * _CHUNK)):
            a_uv, a_dx, a_dy, a_scale = _sample_args(uv, duv_dx, duv_dy, uv_scale, i)
            dark = darkness[i]
            ch = chart[i]
            for lay in range(cos_a.shape[0]):
                rho = _layer_density(dark, tone_lo[lay], style.density)
                if rho <= 0.0:
                    continue
                p, q, d_p, d_q = _layer_frame(a_uv, a_dx, a_dy, a_scale, cos_a[lay], sin_a[lay])
                if not (d_q == d_q):
                    continue
                s = _dyadic_scale(d_q, style.period)
                if not (s == s):  # NaN scale
                    continue
                levels = _levels(s, style.max_level)
                n = 0
                hw_q = hw_px / d_q  # hoisted (double division is slow)
                for lev in range(levels[1] + 1):
                    limit, scale, inv_scale, rows, ry0, ry1 = _level_rows(lev, levels, rho, q, hw_q)
                    if limit <= 0.0:
                        continue
                    half_cells = 0.5 * lam * (1.0 + len_jit) + 0.0 / d_p * scale
                    reach = 0.5 * lam * (1.0 + abs(len_jit)) + 1e-6
                    for ry in range(ry0, ry1 + 1):
                        dist = _row_distance(q, ry, rows, d_q)
                        if dist > hw_px:
                            continue
                        gy, r, kx, kx7, ps, gx0, gx1 = _cells(ry, p, scale, half_cells)
                        margin = reach + 1e-9 * abs(ps)
                        for gx in range(gx0, gx1 + 1):
                            if abs(ps - gx) > margin:
                                continue  # every length puts t outside [0, 1]: rejected below
                            if not _born_at(lev, gx, gy, r, kx):
                                continue  # inherited: enumerated at its birth level
                            sid = _pack_id(ch, lay, lev, gx, gy, r)
                            h_len = _hash01(sid, style.salt_length)
                            length = _stroke_length(h_len, lam, len_jit, inv_scale)
                            p_start = _stroke_start(gx, kx7, inv_scale, length)
                            t, beyond = _stroke_param(p, p_start, length, d_p)
                            if beyond > 0.0:
                                continue
                            if n < _CAP:
                                tau = _hash01(sid, style.salt_tone)
                                if tau < limit and t >= 0.0 and t <= 1.0:
                                    if k < cap:
                                        o = base + k
                                        out_id[o] = sid
                                        out_t[o] = t
                                        out_layer[o] = lay
                                        out_level[o] = lev
                                        out_src[o] = i
                                    k += 1
                                n += 1
        count[j] = k


@njit(inline="always")
def _divmod_floor(a, b):
    """(a // b, a % b) for int64 a, b > 0, |a| < 2^52: the float quotient is within one of the
    floor, corrected by the remainder (no 64-bit integer division)."""
    q = np.int64(math.floor(a / b))
    r = a - q * b
    if r < 0:
        q -= 1
        r += b
    elif r >= b:
        q += 1
        r -= b
    return q, r


@banded(lambda runs, src, gathered, out, grid: runs.src_off.shape[0])
def finish_fragments(lo, hi, runs, src, gathered, out, grid):
    """Copy runs ``[src_off[j], + src_len[j])`` of ``gathered = (id, t, layer, level)`` to
    ``dst_off[j]`` of ``out = (id, t, layer, level, sample, x, y)``, with each fragment's flat
    sample index ``sample[index]`` (``src = (index, sample)``) and its centre in pixels
    ((sx + 0.5) / n, (sy + 0.5) / n) on a grid ``grid = (width, n)`` samples wide."""
    src_off = runs.src_off
    src_len = runs.src_len
    dst_off = runs.dst_off
    index, sample = src
    in_id, in_t, in_layer, in_level = gathered
    out_id, out_t, out_layer, out_level, out_sample, out_x, out_y = out
    width, n_axis = grid
    for j in range(lo, hi):
        a = src_off[j]
        b = dst_off[j]
        last = -1
        px = 0.0
        py = 0.0
        for m in range(src_len[j]):
            sp = sample[index[a + m]]
            if sp != last:  # a sample's fragments are consecutive: its centre once
                sy, sx = _divmod_floor(sp, width)
                px = (sx + 0.5) / n_axis
                py = (sy + 0.5) / n_axis
                last = sp
            out_id[b + m] = in_id[a + m]
            out_t[b + m] = in_t[a + m]
            out_layer[b + m] = in_layer[a + m]
            out_level[b + m] = in_level[a + m]
            out_sample[b + m] = sp
            out_x[b + m] = px
            out_y[b + m] = py


# ---------------------------------------------------------------------- grouping and sums


def group_keys(keys):
    """Stable grouping of ``keys`` (n,) int64 by value, without a full sort.

    Returns ``uid`` (S,) the distinct keys ascending, ``starts`` (S + 1,) int64 and ``perm``
    (n,) int64: the positions of key ``uid[g]`` are ``perm[starts[g]:starts[g + 1]]`` in
    increasing order, i.e. ``perm`` is the stable argsort of ``keys``. Two kernels: the groups
    by hashing (:func:`_group_first`), then, with the S distinct keys sorted by numpy (they are
    distinct, so any sort gives the same order; numba's own sort would compile for ~1 s on a
    cold start), the counting pass (:func:`_group_perm`).
    """
    grp, first = _group_first(keys)
    return _group_perm(grp, first, np.argsort(first))


@njit
def _group_first(keys):
    """Group index ``grp`` (n,) of each key, in order of first appearance, and ``first`` (S,)
    the key of each group."""
    n = keys.shape[0]
    size = 16
    while size < 2 * n:
        size *= 2
    mask = np.uint64(size - 1)
    slot_key = np.empty(size, dtype=np.int64)
    slot_grp = np.full(size, -1, dtype=np.int64)
    grp = np.empty(n, dtype=np.int64)
    first = np.empty(n, dtype=np.int64)
    ng = 0
    for i in range(n):
        key = keys[i]
        h = (np.uint64(key) * _M1) >> np.uint64(20)
        while True:
            j = np.int64(h & mask)
            g = slot_grp[j]
            if g < 0:
                slot_grp[j] = ng
                slot_key[j] = key
                first[ng] = key
                grp[i] = ng
                ng += 1
                break
            if slot_key[j] == key:
                grp[i] = g
                break
            h = h + np.uint64(1)
    return grp, first[:ng].copy()


@njit
def _group_perm(grp, first, order):
    """``group_keys``'s (uid, starts, perm) from the groups of :func:`_group_first` and
    ``order`` (S,), the argsort of their keys ``first``."""
    n = grp.shape[0]
    ng = first.shape[0]
    rank = np.empty(ng, dtype=np.int64)
    uid = np.empty(ng, dtype=np.int64)
    for r in range(ng):
        rank[order[r]] = r
        uid[r] = first[order[r]]
    starts = np.zeros(ng + 1, dtype=np.int64)
    for i in range(n):
        starts[rank[grp[i]] + 1] += 1
    for r in range(ng):
        starts[r + 1] += starts[r]
    fill = starts[:-1].copy()
    perm = np.empty(n, dtype=np.int64)
    for i in range(n):
        r = rank[grp[i]]
        perm[fill[r]] = i
        fill[r] += 1
    return uid, starts, perm


@njit
def _pairwise_block(a, lo, n, c, zero):
    """numpy's pairwise summation (``add.reduce``) of ``a[lo:lo + n, c]`` in a's dtype for n <=
    128: one block, eight accumulators (no recursion, which numba's cache does not reload)."""
    if n < 8:
        res = zero
        for i in range(lo, lo + n):
            res += a[i, c]
        return res
    r0 = a[lo, c]
    r1 = a[lo + 1, c]
    r2 = a[lo + 2, c]
    r3 = a[lo + 3, c]
    r4 = a[lo + 4, c]
    r5 = a[lo + 5, c]
    r6 = a[lo + 6, c]
    r7 = a[lo + 7, c]
    i = 8
    while i < n - (n % 8):
        r0 += a[lo + i, c]
        r1 += a[lo + i + 1, c]
        r2 += a[lo + i + 2, c]
        r3 += a[lo + i + 3, c]
        r4 += a[lo + i + 4, c]
        r5 += a[lo + i + 5, c]
        r6 += a[lo + i + 6, c]
        r7 += a[lo + i + 7, c]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += a[lo + i, c]
        i += 1
    return res


@njit
def _pairwise(a, lo, n, c, zero):
    """numpy's pairwise summation (``add.reduce``) of ``a[lo:lo + n, c]`` in a's dtype."""
    if n <= 128:
        return _pairwise_block(a, lo, n, c, zero)
    n2 = n // 2
    n2 -= n2 % 8
    return _pairwise(a, lo, n2, c, zero) + _pairwise(a, lo + n2, n - n2, c, zero)


@banded(lambda groups, frags, half_c, out, rows: groups[1].shape[0] - 1)
def group_sums(i_lo, i_hi, groups, frags, half_c, out, rows):
    """Per group g (fragments ``perm[starts[g]:starts[g + 1]]``, ``groups = (perm, starts)``,
    in that order) of ``frags = (t, x, y)``: min and max of t, the centre of the (x, y) bounding
    box, and the sums of the 15 regressors (``fragment_regressors`` of s = ``normalize_t``(t,
    lo, hi), x - o_x, y - o_y) into ``out = (lo, hi, origin, moments)``, all in the dtype of
    t, x, y, ``half_c`` (a 1-array holding 0.5) and the outputs; summed as ``aggregate``
    (``reduceat``: the first row plus numpy's pairwise sum of the others). ``rows`` (n, 15) is
    scratch."""
    perm, starts = groups
    t, x, y = frags
    lo, hi, origin, moments = out
    hc = half_c[0]
    one = hc + hc
    zero = hc - hc
    for g in range(i_lo, i_hi):
        a = starts[g]
        b = starts[g + 1]
        i = perm[a]
        tl = t[i]
        th = t[i]
        xl = x[i]
        xh = x[i]
        yl = y[i]
        yh = y[i]
        for m in range(a + 1, b):
            i = perm[m]
            tl = min(tl, t[i])  # min blending pass
            th = max(th, t[i])  # max blending pass
            xl = min(xl, x[i])
            xh = max(xh, x[i])
            yl = min(yl, y[i])
            yh = max(yh, y[i])
        ox = (xl + xh) * hc
        oy = (yl + yh) * hc
        lo[g] = tl
        hi[g] = th
        origin[g, 0] = ox
        origin[g, 1] = oy
        for m in range(a, b):
            i = perm[m]
            s = _normalize_t(t[i], tl, th, hc)
            reg = _regressors(s, x[i] - ox, y[i] - oy, one)
            rows[m, 0] = reg[0]  # stored one by one: a loop indexes the tuple in memory
            rows[m, 1] = reg[1]
            rows[m, 2] = reg[2]
            rows[m, 3] = reg[3]
            rows[m, 4] = reg[4]
            rows[m, 5] = reg[5]
            rows[m, 6] = reg[6]
            rows[m, 7] = reg[7]
            rows[m, 8] = reg[8]
            rows[m, 9] = reg[9]
            rows[m, 10] = reg[10]
            rows[m, 11] = reg[11]
            rows[m, 12] = reg[12]
            rows[m, 13] = reg[13]
            rows[m, 14] = reg[14]
        for c in range(15):  # additive blending pass
            acc = rows[a, c]
            if b - a > 1:
                acc += _pairwise(rows, a + 1, b - a - 1, c, zero)
            moments[g, c] = acc


# ---------------------------------------------------------------------- fitted curves


@njit
def _row4(c, i):
    return (c[i, 0], c[i, 1], c[i, 2], c[i, 3])


@banded("t")
def mean_speeds(i_lo, i_hi, t, fit, half_c, span, seg, out):
    """Per fitted stroke i: the length of the polyline through the curve at t[i, :] (S, M),
    M <= 129, over ``span[i]`` (float64; 0 where span <= 0), into ``out`` (S,) float64.

    ``fit = (c_x, c_y, t_min, t_max)`` (S, 4), (S,) in one float dtype with ``t`` and
    ``half_c`` (a 1-array holding 0.5): the curve is ``cubic`` of ``normalize_t``(t) in that
    dtype, then in float64 the segment lengths hypot(dx, dy) summed as numpy's pairwise
    ``sum``; ``seg`` (S, M - 1) float64 is scratch."""
    c_x, c_y, t_min, t_max = fit
    hc = half_c[0]
    m = t.shape[1]
    seg_t = seg.T  # (M - 1, S): the rows of seg as _pairwise_block's columns
    for i in range(i_lo, i_hi):
        cx = _row4(c_x, i)
        cy = _row4(c_y, i)
        lo = t_min[i]
        hi = t_max[i]
        xp = 0.0
        yp = 0.0
        for k in range(m):
            s = _normalize_t(t[i, k], lo, hi, hc)
            x64 = np.float64(_cubic(cx, s))
            y64 = np.float64(_cubic(cy, s))
            if k > 0:
                seg[i, k - 1] = math.hypot(x64 - xp, y64 - yp)
            xp = x64
            yp = y64
        arc = _pairwise_block(seg_t, 0, m - 1, i, 0.0)
        out[i] = arc / span[i] if span[i] > 0.0 else 0.0


@banded("t")
def centrelines(i_lo, i_hi, t, fit, consts, ext, tbuf, out):
    """Points x, y and unit tangents tx, ty (``out``, (S, K) float64 each) of the drawn curves
    at t (S, K) float64 (finite): t clipped to [t_min, t_max], the ``cubic`` and its
    ``cubic_slope`` (times ds/dt = 2 / (hi - lo), 0 where hi - lo <= 0) of ``normalize_t``(t)
    in the dtype of ``fit = (c_x, c_y, t_min, t_max)`` and ``consts`` (0.5, 2, 3, 0), then in
    float64 the unit tangent (the chord r(hi) - r(lo) where the derivative vanishes) and, with
    ``ext = (speed, extend)`` (extend: some t outside its row's range), the tangent line past
    the ends at ``speed`` (S,) px per unit t; ``tbuf`` (S, K) in the fit's dtype is scratch."""
    c_x, c_y, t_min, t_max = fit
    speed, extend = ext
    x, y, tx, ty = out
    c05 = consts[0]
    k23 = (consts[1], consts[2], consts[3])
    two = consts[1]
    zero = consts[3]
    for i in range(i_lo, i_hi):
        cx = _row4(c_x, i)
        cy = _row4(c_y, i)
        lo = t_min[i]
        hi = t_max[i]
        lo64 = np.float64(lo)
        hi64 = np.float64(hi)
        width = hi - lo
        ds = two / width if width > zero else zero
        s_lo = _normalize_t(lo, lo, hi, c05)
        s_hi = _normalize_t(hi, lo, hi, c05)
        fx = np.float64(_cubic(cx, s_hi)) - np.float64(_cubic(cx, s_lo))
        fy = np.float64(_cubic(cy, s_hi)) - np.float64(_cubic(cy, s_lo))
        fn = math.hypot(fx, fy)
        fok = fn > 1e-12
        gx = fx / fn if fok else 1.0
        gy = fy / fn if fok else 0.0
        for j in range(t.shape[1]):
            tj = t[i, j]
            tc = min(max(tj, lo64), hi64)
            tbuf[i, j] = tc  # t in the fit's dtype (rounded, as astype)
            s = _normalize_t(tbuf[i, j], lo, hi, c05)
            px = np.float64(_cubic(cx, s))
            py = np.float64(_cubic(cy, s))
            dx = np.float64(_cubic_slope(cx, s, k23) * ds)
            dy = np.float64(_cubic_slope(cy, s, k23) * ds)
            n = math.hypot(dx, dy)
            if n > 1e-12:
                ux = dx / n
                uy = dy / n
            else:
                ux = gx
                uy = gy
            if extend:
                if tj < lo64:
                    d_out = (tj - lo64) * speed[i]
                elif tj > hi64:
                    d_out = (tj - hi64) * speed[i]
                else:
                    d_out = 0.0 * speed[i]
                px = px + d_out * ux
                py = py + d_out * uy
            x[i, j] = px
            y[i, j] = py
            tx[i, j] = ux
            ty[i, j] = uy


@banded(lambda centre, normal, h, sides: h.shape[0])
def strip_sides(lo, hi, centre, normal, h, sides):
    """Strip vertices ``sides = (left, right)`` (P, K, 2): left = (x + h nx, y + h ny), right =
    (x - h nx, y - h ny), from (P, K) float64 centreline points ``centre = (x, y)``, unit
    normals ``normal = (nx, ny)`` and half widths ``h``."""
    x, y = centre
    nx, ny = normal
    left, right = sides
    for i in range(lo, hi):
        for j in range(x.shape[1]):
            ox = h[i, j] * nx[i, j]
            oy = h[i, j] * ny[i, j]
            left[i, j, 0] = x[i, j] + ox
            left[i, j, 1] = y[i, j] + oy
            right[i, j, 0] = x[i, j] - ox
            right[i, j, 1] = y[i, j] - oy


# ---------------------------------------------------------------------- strip raster


@njit
def _edge(ax, ay, bx, by, px, py):
    return (bx - ax) * (py - ay) - (by - ay) * (px - ax)


@njit
def _popcount(x):
    c = 0
    while x:
        x &= x - np.uint64(1)
        c += 1
    return c


@njit
def strip_bbox(left, right, nh, nw, out):
    """Per piece the inclusive sample bbox x0, y0, x1, y1 of its vertices, clipped to the
    (nh, nw) grid, into ``out`` (P, 4) int64; (0, 0, -1, -1) for a piece with a non-finite
    vertex. left, right : (P, K, 2) float64. The numpy formula: floor of the min / max over
    both sides, clipped to [-1, n], then the low corner raised to 0 and the high one lowered
    to n - 1 (min, max, floor and clip round nothing), for any finite vertex."""
    for pc in range(left.shape[0]):
        finite = True
        xl = np.inf
        xh = -np.inf
        yl = np.inf
        yh = -np.inf
        for side in range(2):
            a = left if side == 0 else right
            for j in range(a.shape[1]):
                vx = a[pc, j, 0]
                vy = a[pc, j, 1]
                if not (math.isfinite(vx) and math.isfinite(vy)):
                    finite = False
                xl = min(xl, vx)
                xh = max(xh, vx)
                yl = min(yl, vy)
                yh = max(yh, vy)
        if not finite:
            out[pc, 0] = 0
            out[pc, 1] = 0
            out[pc, 2] = -1
            out[pc, 3] = -1
            continue
        # clipped before the floor (numba's floor is an int64: 1e19 would not fit), the same
        # as numpy's clip of the float floor
        out[pc, 0] = max(math.floor(min(max(xl, -1.0), float(nw))), 0)
        out[pc, 1] = max(math.floor(min(max(yl, -1.0), float(nh))), 0)
        out[pc, 2] = min(math.floor(min(max(xh, -1.0), float(nw))), nw - 1)
        out[pc, 3] = min(math.floor(min(max(yh, -1.0), float(nh))), nh - 1)


@njit(inline="always")
def _texel(c, size, wrap):
    """Texel column c wrapped (c mod size, as Python's %) or clamped to [0, size - 1]; the
    wrap of a column at most one period off without an integer division."""
    if not wrap:
        return min(max(c, 0), size - 1)
    if 0 <= c < size:
        return c
    if -size <= c < 0:
        return c + size
    if size <= c < 2 * size:
        return c - size
    return c % size


@njit(inline="always")
def _floor_in(v, lo, hi):
    """floor(v) as an int, v first clamped to [lo - 1, hi + 1] (lo, hi ints)."""
    return int(math.floor(min(max(v, lo - 1.0), hi + 1.0)))


@njit(inline="always")
def _corner(high, aa, inv):
    """Offset (j + 0.5) / aa of the last sub-sample row or column of a pixel if ``high``, else
    of the first (the same expression as the sub-sample positions of ``raster_strips``)."""
    return ((aa - 1) + 0.5) * inv if high else (0 + 0.5) * inv


class Strips(NamedTuple):
    """The pieces ``raster_strips`` draws: left, right (P, K, 2) vertices in sample units, tv
    (P, K) the brush u (stroke t) per vertex pair, opacity (P,), colors (P, 3) (or (0, 3): ink
    only)."""

    left: np.ndarray
    right: np.ndarray
    tv: np.ndarray
    opacity: np.ndarray
    colors: np.ndarray


@specialised
def raster_strips_for(aa):
    """:func:`raster_strips` for ``aa`` sub-samples per axis (1..8): with ``aa`` a constant,
    LLVM unrolls the aa x aa coverage loop of each sample (the same operations, same bits;
    ~30 % faster at aa = 4 on the TAMISS teapot's strokes, benchmarks/README.md)."""

    @banded(lambda strips, bbox, grid, brush, out: (grid[0] + _BAND - 1) // _BAND)
    def raster_strips(b_lo, b_hi, strips, bbox, grid, brush, out):
        """Rasterize :class:`Strips` into ``out = (alpha, pieces, rgb)`` ((nh, nw) float64,
        (nh, nw) int32 pieces touching each sample, (nh, nw, 3) float64) with "over" in piece
        order, on the ``grid = (nh, nw)``.

        Banded over bands of ``_BAND`` grid rows (``b_lo``, ``b_hi``: band indices); every band
        walks all pieces in order, so each sample composites them in piece order whatever the
        banding. ``bbox`` (P, 4) int64 x0, y0, x1, y1 (inclusive, clipped); aa (the factory's):
        sub-samples per axis (<= 8); ``brush = (texels, t_wrap)``: (Hb, Wb) alpha multiplier
        sampled at (u = t, v = across), wrapping in u when ``t_wrap``. Each piece's coverage is
        the fraction of aa x aa sub-samples inside any of its 2 (K - 1) triangles (L_i, R_i,
        L_i+1) and (R_i, R_i+1, L_i+1). With colours (P, 3), ``rgb`` accumulates premultiplied
        colour with the same "over".
        """
        left = strips.left
        right = strips.right
        tv = strips.tv
        opacity = strips.opacity
        colors = strips.colors
        nh, nw = grid
        tex, t_wrap = brush
        out_alpha, out_strokes, out_rgb = out
        n_pieces = left.shape[0]
        colored = colors.shape[0] == n_pieces and n_pieces > 0
        k = left.shape[1]
        band = _BAND
        inv = 1.0 / aa
        hb = tex.shape[0]
        wb = tex.shape[1]
        # per-piece scratch (a piece's bbox within the band), reset for each piece
        mask = np.empty(band * nw, dtype=np.uint64)
        best = np.empty(band * nw)
        bu = np.empty(band * nw)
        bv = np.empty(band * nw)
        for bi in range(b_lo, b_hi):
            y_lo = bi * band
            y_hi = min(nh, y_lo + band) - 1
            for pc in range(n_pieces):
                x0 = bbox[pc, 0]
                y0 = max(bbox[pc, 1], y_lo)
                x1 = bbox[pc, 2]
                y1 = min(bbox[pc, 3], y_hi)
                if y1 < y0 or x1 < x0:
                    continue
                w = x1 - x0 + 1
                h = y1 - y0 + 1
                for idx in range(h * w):
                    mask[idx] = 0
                    best[idx] = -np.inf
                    bu[idx] = 0.0
                    bv[idx] = 0.0
                for seg in range(k - 1):
                    for tri in range(2):
                        if tri == 0:
                            ax, ay = left[pc, seg, 0], left[pc, seg, 1]
                            bx, by = right[pc, seg, 0], right[pc, seg, 1]
                            cx, cy = left[pc, seg + 1, 0], left[pc, seg + 1, 1]
                            ta, tb, tc = tv[pc, seg], tv[pc, seg], tv[pc, seg + 1]
                            va, vb, vc = 0.0, 1.0, 0.0
                        else:
                            ax, ay = right[pc, seg, 0], right[pc, seg, 1]
                            bx, by = right[pc, seg + 1, 0], right[pc, seg + 1, 1]
                            cx, cy = left[pc, seg + 1, 0], left[pc, seg + 1, 1]
                            ta, tb, tc = tv[pc, seg], tv[pc, seg + 1], tv[pc, seg + 1]
                            va, vb, vc = 1.0, 1.0, 0.0
                        area = _edge(ax, ay, bx, by, cx, cy)
                        if abs(area) < 1e-12:
                            continue
                        sgn = 1.0 if area > 0.0 else -1.0
                        # bounds clamped in float before the integer conversion (a vertex at 1e300
                        # would not fit an int64); within [x0 - 1, x1 + 1] the same as unclamped
                        tx0 = max(x0, _floor_in(min(ax, bx, cx), x0, x1))
                        tx1 = min(x1, _floor_in(max(ax, bx, cx), x0, x1))
                        ty0 = max(y0, _floor_in(min(ay, by, cy), y0, y1))
                        ty1 = min(y1, _floor_in(max(ay, by, cy), y0, y1))
                        if ty1 < ty0 or tx1 < tx0:
                            continue  # outside this band (or the piece's clipped bbox)
                        # the factors of _edge's two products (same values, computed once)
                        e0x, e0y = cx - bx, cy - by
                        e1x, e1y = ax - cx, ay - cy
                        e2x, e2y = bx - ax, by - ay
                        # per edge, the sub-sample of a pixel most inside it: every rounding step of
                        # the test below (py - by, e0x (.), px - bx, e0y (.), r0 - (.), (.) sgn) is
                        # monotonic, so the rounded values are monotonic along each axis of the
                        # aa x aa grid and their maximum is at this corner; where it is outside,
                        # so are all the pixel's sub-samples (exactly: same values, no margin)
                        oy0, ox0 = (
                            _corner(e0x * sgn > 0.0, aa, inv),
                            _corner(e0y * sgn < 0.0, aa, inv),
                        )
                        oy1, ox1 = (
                            _corner(e1x * sgn > 0.0, aa, inv),
                            _corner(e1y * sgn < 0.0, aa, inv),
                        )
                        oy2, ox2 = (
                            _corner(e2x * sgn > 0.0, aa, inv),
                            _corner(e2y * sgn < 0.0, aa, inv),
                        )
                        for y in range(ty0, ty1 + 1):
                            for x in range(tx0, tx1 + 1):
                                idx = (y - y0) * w + (x - x0)
                                if not (
                                    (e0x * (y + oy0 - by) - e0y * (x + ox0 - bx)) * sgn < 0.0
                                    or (e1x * (y + oy1 - cy) - e1y * (x + ox1 - cx)) * sgn < 0.0
                                    or (e2x * (y + oy2 - ay) - e2y * (x + ox2 - ax)) * sgn < 0.0
                                ):
                                    bits = mask[idx]
                                    for sj in range(aa):
                                        py = y + (sj + 0.5) * inv
                                        r0 = e0x * (py - by)
                                        r1 = e1x * (py - cy)
                                        r2 = e2x * (py - ay)
                                        for si in range(aa):
                                            px = x + (si + 0.5) * inv
                                            # inside all three edges (_edge's values), no branches
                                            inside = (
                                                ((r0 - e0y * (px - bx)) * sgn >= 0.0)
                                                & ((r1 - e1y * (px - cx)) * sgn >= 0.0)
                                                & ((r2 - e2y * (px - ax)) * sgn >= 0.0)
                                            )
                                            bits |= np.uint64(inside) << np.uint64(sj * aa + si)
                                    mask[idx] = bits
                                # brush coordinates from the triangle the sample centre is most in
                                pcx = x + 0.5
                                pcy = y + 0.5
                                w0 = _edge(bx, by, cx, cy, pcx, pcy) / area
                                w1 = _edge(cx, cy, ax, ay, pcx, pcy) / area
                                w2 = 1.0 - w0 - w1
                                m = min(w0, w1, w2)
                                if m > best[idx]:
                                    best[idx] = m
                                    w0c = max(w0, 0.0)
                                    w1c = max(w1, 0.0)
                                    w2c = max(w2, 0.0)
                                    ws = w0c + w1c + w2c
                                    bu[idx] = (w0c * ta + w1c * tb + w2c * tc) / ws
                                    bv[idx] = (w0c * va + w1c * vb + w2c * vc) / ws
                for y in range(y0, y1 + 1):
                    for x in range(x0, x1 + 1):
                        idx = (y - y0) * w + (x - x0)
                        if mask[idx] == 0:
                            continue
                        cov = _popcount(mask[idx]) / (aa * aa)
                        # bilinear brush lookup, texel centres at (i + 0.5) / size
                        fu = bu[idx] * wb - 0.5
                        fv = min(max(bv[idx], 0.0), 1.0) * hb - 0.5
                        iu = int(math.floor(fu))
                        iv = int(math.floor(fv))
                        au = fu - iu
                        av = fv - iv
                        cc0 = _texel(iu, wb, t_wrap)  # the two columns, once for both rows
                        cc1 = _texel(iu + 1, wb, t_wrap)
                        val = 0.0
                        for dv in range(2):
                            rr = min(max(iv + dv, 0), hb - 1)
                            wv = av if dv == 1 else 1.0 - av
                            val += (1.0 - au) * wv * tex[rr, cc0]
                            val += au * wv * tex[rr, cc1]
                        a = cov * opacity[pc] * val
                        out_alpha[y, x] = _ink_over(out_alpha[y, x], a)
                        if colored:
                            for ch in range(3):
                                out_rgb[y, x, ch] = colors[pc, ch] * a + out_rgb[y, x, ch] * (
                                    1.0 - a
                                )
                        out_strokes[y, x] += 1

    return raster_strips

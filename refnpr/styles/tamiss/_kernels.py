"""numba kernels of the TAM / TAMISS styles (no validation here; see the calling modules).

* ``chart_labels``: connected components of a mesh's faces through shared vertex indices.
* ``field_pass``: per G-buffer sample, enumerate the strokes of the RPTAM field
  (``field``) that cover it, then either count/emit TAMISS fragments or accumulate the
  anti-aliased TAM/RPTAM ink (the TAM modes through ``_tam_layer``, the enumeration fused with
  the accumulation, same bits).
* ``raster_strips_for(aa)``: anti-aliased rasterization of image-space triangle strips (supersampled
  coverage of the union of a strip's triangles), composited in order with "over";
  ``strip_bbox``: the pieces' clipped sample bboxes it takes.
* ``sample_inputs``: the per-sample field inputs straight from the G-buffer channels (compaction,
  smooth derivatives as ``smooth_duv``, chart orientation, diffuse colour) in one pass.
* ``field_gather`` / ``finish_fragments``: TAMISS fragments in one pass over sample chunks (the
  COUNT and EMIT passes of ``field_pass`` fused), then copied to their places in chunk order.
* ``mean_speeds``: the fitted curves' polyline length per unit t (``strokes.mean_speed``);
  ``centrelines``: points and unit tangents of the drawn curves (``strokes.centreline``).
* ``strip_sides``: the strip's left / right vertices from the centreline, as numpy's.
* ``group_keys`` / ``group_sums``: grouping of fragments by stroke id (a stable argsort by
  hashing and a counting pass) and the per-stroke min/max and regressor sums, parallel over
  strokes, each summed in a fixed order (bits do not depend on the thread count).
"""

from __future__ import annotations

import math

import numpy as np

from refnpr._jit import banded, njit, specialised

_M1 = np.uint64(0x9E3779B97F4A7C15)
_M2 = np.uint64(0xBF58476D1CE4E5B9)
_M3 = np.uint64(0x94D049BB133111EB)
_S30 = np.uint64(30)
_S27 = np.uint64(27)
_S31 = np.uint64(31)
_S11 = np.uint64(11)
_INV53 = 1.0 / 9007199254740992.0
_KX = np.array([0, 6, 5, 1, 3, 4, 2], dtype=np.int64)
#: kx / 7.0 per row residue, divided once here (the same float64 values the loops divided).
_KX7 = _KX / 7.0
_CELL_OFF = 1 << 21
#: Rec. 709 luminance weights (the darkness of ``sample_inputs``).
_LUMA_R = 0.2126
_LUMA_G = 0.7152
_LUMA_B = 0.0722

#: Fragment pass modes.
MODE_COUNT, MODE_EMIT, MODE_TAM_CLIP, MODE_TAM_FADE = 0, 1, 2, 3

_CHUNK = 512
_CAP = 256
#: Rows of the sample grid per band of ``raster_strips`` (a band is one index of its loop).
_BAND = 16


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


@njit
def _splitmix(z):
    z = z + _M1
    z = (z ^ (z >> _S30)) * _M2
    z = (z ^ (z >> _S27)) * _M3
    return z ^ (z >> _S31)


@njit
def _hash01(sid, salt_off):
    z = np.uint64(sid) + salt_off
    return np.float64(_splitmix(z) >> _S11) * _INV53


@njit
def _pack(chart, layer, level, gx, gy, r):
    v = chart * 4 + layer
    v = v * 16 + level
    v = (v << 22) + (gx + _CELL_OFF)
    v = (v << 22) + (gy + _CELL_OFF)
    return v * 8 + r


@njit(inline="always")  # one call site; as a call, its six arrays cost NRT refcounts per sample
def _enumerate(
    p,
    q,
    d_p,
    d_q,
    s,
    rho,
    chart,
    layer,
    max_level,
    lam,
    len_jit,
    hw_px,
    end_px,
    salt_len,
    c_id,
    c_t,
    c_dist,
    c_end,
    c_gain,
    c_level,
):
    """Strokes within ``hw_px`` of (p, q) across and ``end_px`` beyond their ends.

    Fills the candidate arrays (id, t, distance across in px, signed distance past the nearest
    end in px (negative inside the stroke), density gain, birth level) and returns their number (at most the arrays' length). The
    gain multiplies rho in the density test: 1 for levels <= L, 2^f - 1 for level L + 1, and
    2^s below level 0 (s < 0: rows denser than the period are thinned to keep the ink).
    """
    cap = c_id.shape[0]
    if not (s == s):  # NaN scale
        return 0
    big_l = math.floor(s)
    f = s - big_l
    thin = 1.0
    if big_l < 0:  # rows closer than the period even at level 0: thin them, same ink
        thin = math.pow(2.0, s)
        big_l = 0
        f = 0.0
    if big_l >= max_level:
        big_l = max_level
        f = 0.0
    top = big_l + 1 if f > 0.0 else big_l
    alpha = math.pow(2.0, f) - 1.0  # ink-preserving fade-in of level L + 1
    n = 0
    # divisions hoisted or made exact products (double division is slow): the same values
    hw_q = hw_px / d_q
    end_cells = end_px / d_p
    for lev in range(top + 1):
        gain = thin if lev <= big_l else alpha
        if gain * rho <= 0.0:
            continue
        scale = float(1 << lev)
        inv_scale = 1.0 / scale  # a power of two: x * inv_scale == x / scale, bit for bit
        rows = 7.0 * scale
        ry0 = int(math.floor((q - hw_q) * rows))
        ry1 = int(math.floor((q + hw_q) * rows)) + 1
        half_cells = 0.5 * lam * (1.0 + len_jit) + end_cells * scale
        for ry in range(ry0, ry1 + 1):
            q_row = ry / rows
            dist = abs(q - q_row) * d_q
            if dist > hw_px:
                continue
            gy = ry // 7
            r = ry - 7 * gy
            kx = _KX[r]
            kx7 = _KX7[r]
            ps = p * scale - kx7
            gx0 = int(math.floor(ps - half_cells))
            gx1 = int(math.floor(ps + half_cells)) + 1
            for gx in range(gx0, gx1 + 1):
                if lev > 0 and (gx & 1) == (kx & 1) and (gy & 1) == (r & 1):
                    continue  # inherited: enumerated at its birth level
                sid = _pack(chart, layer, lev, gx, gy, r)
                h = _hash01(sid, salt_len)
                length = lam * (1.0 + len_jit * (2.0 * h - 1.0)) * inv_scale
                p_start = (gx + kx7) * inv_scale - 0.5 * length
                t = (p - p_start) / length
                beyond = max(-t, t - 1.0) * length * d_p  # signed: < 0 inside the stroke
                if beyond > end_px:
                    continue
                if n < cap:
                    c_id[n] = sid
                    c_t[n] = t
                    c_dist[n] = dist
                    c_end[n] = beyond
                    c_gain[n] = gain
                    c_level[n] = lev
                    n += 1
    return n


@njit  # scalars only, so a call costs no reference counts; compiled once, not into field_pass
def _tam_layer(
    p,
    q,
    d_p,
    d_q,
    s,
    rho,
    chart,
    layer,
    max_level,
    lam,
    len_jit,
    wid_jit,
    width_px,
    fade,
    clip,
    salt_len,
    salt_tone,
    salt_wid,
    ink,
):
    """``ink`` over the TAM strokes of one sample and layer: :func:`_enumerate` (hw_px as
    ``field_pass`` sets it, end_px = 0.5) fused with ``field_pass``'s TAM accumulation, cheapest
    test first. Returns the new ink, or -1.0 when more than ``_CAP`` strokes could have been
    candidates: then ``_enumerate``'s cap may drop some, and the caller takes that path instead.

    Same strokes in the same order, each tested on the same values as there: a stroke is passed
    over before its length is hashed when its cell centre is farther from p than any length
    reaches (half the longest length plus end_px, with a margin far above rounding) or when its
    density test fails (tau < rho gain is both modes' opacity > 0), so the ink is the same bits.
    """
    if not (s == s):  # NaN scale
        return ink
    hw_px = 0.5 * width_px * (1.0 + wid_jit) + 0.5
    end_px = 0.5
    big_l = math.floor(s)
    f = s - big_l
    thin = 1.0
    if big_l < 0:
        thin = math.pow(2.0, s)
        big_l = 0
        f = 0.0
    if big_l >= max_level:
        big_l = max_level
        f = 0.0
    top = big_l + 1 if f > 0.0 else big_l
    alpha = math.pow(2.0, f) - 1.0
    seen = 0  # strokes that _enumerate could have kept (an upper bound of its count)
    hw_q = hw_px / d_q
    end_cells = end_px / d_p
    for lev in range(top + 1):
        gain = thin if lev <= big_l else alpha
        if gain * rho <= 0.0:
            continue
        limit = rho * gain
        scale = float(1 << lev)
        inv_scale = 1.0 / scale
        rows = 7.0 * scale
        ry0 = int(math.floor((q - hw_q) * rows))
        ry1 = int(math.floor((q + hw_q) * rows)) + 1
        half_cells = 0.5 * lam * (1.0 + len_jit) + end_cells * scale
        for ry in range(ry0, ry1 + 1):
            q_row = ry / rows
            dist = abs(q - q_row) * d_q
            if dist > hw_px:
                continue
            gy = ry // 7
            r = ry - 7 * gy
            kx = _KX[r]
            kx7 = _KX7[r]
            ps = p * scale - kx7
            gx0 = int(math.floor(ps - half_cells))
            gx1 = int(math.floor(ps + half_cells)) + 1
            reach = 0.5 * lam * (1.0 + abs(len_jit)) + end_cells * scale
            reach = reach + 1e-6 + 1e-9 * (abs(ps) + reach)
            for gx in range(gx0, gx1 + 1):
                if lev > 0 and (gx & 1) == (kx & 1) and (gy & 1) == (r & 1):
                    continue  # inherited: enumerated at its birth level
                seen += 1
                if seen > _CAP:
                    return -1.0
                if abs(ps - gx) > reach:
                    continue  # beyond > end_px for every length
                sid = _pack(chart, layer, lev, gx, gy, r)
                tau = _hash01(sid, salt_tone)
                if not (tau < limit):
                    continue  # opacity 0 in both modes
                h = _hash01(sid, salt_len)
                length = lam * (1.0 + len_jit * (2.0 * h - 1.0)) * inv_scale
                p_start = (gx + kx7) * inv_scale - 0.5 * length
                t = (p - p_start) / length
                beyond = max(-t, t - 1.0) * length * d_p
                if beyond > end_px:
                    continue
                if clip:
                    opacity = 1.0
                else:
                    opacity = min(max((limit - tau) / fade, 0.0), 1.0)
                if opacity <= 0.0:
                    continue
                wf = 1.0 + wid_jit * (2.0 * _hash01(sid, salt_wid) - 1.0)
                cov_q = min(max(0.5 * width_px * wf - dist + 0.5, 0.0), 1.0)
                cov_p = min(max(0.5 - beyond, 0.0), 1.0)
                a = cov_q * cov_p * opacity
                ink = ink + a * (1.0 - ink)
    return ink


@banded(lambda mode, uv, *rest: (uv.shape[0] + _CHUNK - 1) // _CHUNK)
def field_pass(
    lo,
    hi,
    mode,
    uv,
    duv_dx,
    duv_dy,
    uv_scale,
    darkness,
    chart,
    cos_a,
    sin_a,
    tone_lo,
    density,
    period,
    max_level,
    lam,
    len_jit,
    wid_jit,
    width_px,
    fade,
    salt_tone,
    salt_len,
    salt_wid,
    offsets,
    counts,
    out_id,
    out_t,
    out_layer,
    out_level,
    out_ink,
):
    """One pass over N samples (all inputs (N, ...) on valid samples only).

    mode COUNT: ``counts[i]`` = fragments of sample i. EMIT: write them at ``offsets[i]`` into
    ``out_*`` (id, t, layer, birth level). TAM_CLIP / TAM_FADE: ``out_ink[i]`` = anti-aliased ink
    coverage 1 - prod(1 - a) of the strokes over sample i, with a binary (clip) or smooth (fade)
    density decision. ``width_px`` is the gather band (COUNT/EMIT) or the stroke width (TAM).
    """
    n_samples = uv.shape[0]
    n_layers = cos_a.shape[0]
    tam = mode >= 2
    c_id = np.empty(_CAP, dtype=np.int64)  # candidates of one sample and layer (scratch)
    c_t = np.empty(_CAP)
    c_dist = np.empty(_CAP)
    c_end = np.empty(_CAP)
    c_gain = np.empty(_CAP)
    c_level = np.empty(_CAP, dtype=np.int64)
    for ci in range(lo, hi):
        for i in range(ci * _CHUNK, min(n_samples, (ci + 1) * _CHUNK)):
            su = uv_scale[i, 0]
            sv = uv_scale[i, 1]
            u = uv[i, 0] * su
            v = uv[i, 1] * sv
            ux = duv_dx[i, 0] * su
            vx = duv_dx[i, 1] * sv
            uy = duv_dy[i, 0] * su
            vy = duv_dy[i, 1] * sv
            k = 0
            ink = 0.0
            for lay in range(n_layers):
                ca = cos_a[lay]
                sa = sin_a[lay]
                rho = (darkness[i] - tone_lo[lay]) / (1.0 - tone_lo[lay]) * density
                rho = min(max(rho, 0.0), 1.0)
                if rho <= 0.0:
                    continue
                p = ca * u + sa * v
                q = -sa * u + ca * v
                gp = math.hypot(ca * ux + sa * vx, ca * uy + sa * vy)
                gq = math.hypot(-sa * ux + ca * vx, -sa * uy + ca * vy)
                if not (gq > 0.0 and gp > 0.0 and gq < 1e30 and gp < 1e30):
                    continue
                d_p = 1.0 / gp
                d_q = 1.0 / gq
                s = math.log2(d_q / (7.0 * period))
                if tam:
                    fused = _tam_layer(
                        p, q, d_p, d_q, s, rho, chart[i], lay, max_level, lam, len_jit,
                        wid_jit, width_px, fade, mode == 2, salt_len, salt_tone, salt_wid, ink,
                    )  # fmt: skip
                    if fused >= 0.0:
                        ink = fused
                        continue
                    hw = 0.5 * width_px * (1.0 + wid_jit) + 0.5  # more than _CAP candidates
                    end = 0.5
                else:
                    hw = 0.5 * width_px
                    end = 0.0
                n = _enumerate(
                    p,
                    q,
                    d_p,
                    d_q,
                    s,
                    rho,
                    chart[i],
                    lay,
                    max_level,
                    lam,
                    len_jit,
                    hw,
                    end,
                    salt_len,
                    c_id,
                    c_t,
                    c_dist,
                    c_end,
                    c_gain,
                    c_level,
                )
                for j in range(n):
                    tau = _hash01(c_id[j], salt_tone)
                    limit = rho * c_gain[j]
                    if tam:
                        if mode == 2:
                            opacity = 1.0 if tau < limit else 0.0
                        else:
                            opacity = min(max((limit - tau) / fade, 0.0), 1.0)
                        if opacity <= 0.0:
                            continue
                        wf = 1.0 + wid_jit * (2.0 * _hash01(c_id[j], salt_wid) - 1.0)
                        cov_q = min(max(0.5 * width_px * wf - c_dist[j] + 0.5, 0.0), 1.0)
                        cov_p = min(max(0.5 - c_end[j], 0.0), 1.0)
                        a = cov_q * cov_p * opacity
                        ink = ink + a * (1.0 - ink)
                    else:
                        if not (tau < limit and c_t[j] >= 0.0 and c_t[j] <= 1.0):
                            continue
                        if mode == 1:
                            o = offsets[i] + k
                            out_id[o] = c_id[j]
                            out_t[o] = c_t[j]
                            out_layer[o] = lay
                            out_level[o] = c_level[j]
                        k += 1
            if mode == 0:
                counts[i] = k
            elif tam:
                out_ink[i] = ink


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


@specialised
def raster_strips_for(aa):
    """:func:`raster_strips` for ``aa`` sub-samples per axis (1..8): with ``aa`` a constant,
    LLVM unrolls the aa x aa coverage loop of each sample (the same operations, same bits;
    ~30 % faster at aa = 4 on the TAMISS teapot's strokes, benchmarks/README.md)."""

    @banded(lambda left, right, tv, opacity, bbox, nh, *rest: (nh + _BAND - 1) // _BAND)
    def raster_strips(
        b_lo,
        b_hi,
        left,
        right,
        tv,
        opacity,
        bbox,
        nh,
        nw,
        brush,
        t_wrap,
        out_alpha,
        out_strokes,
        colors,
        out_rgb,
    ):
        """Rasterize strips into ``out_alpha`` (nh, nw) with "over" in piece order.

        Banded over bands of ``_BAND`` grid rows (``b_lo``, ``b_hi``: band indices); every band
        walks all pieces in order, so each sample composites them in piece order whatever the
        banding.

        left, right : (P, K, 2) vertices in sample units; tv : (P, K) brush u (stroke t) per
        vertex pair; opacity : (P,); bbox : (P, 4) int64 x0, y0, x1, y1 (inclusive, clipped);
        aa (the factory's) : sub-samples per axis (<= 8); brush : (Hb, Wb) alpha multiplier
        sampled at (u = t, v = across), wrapping in u when ``t_wrap``; out_strokes : (nh, nw) int32, number of pieces touching each sample.
        Each piece's coverage is the fraction of aa x aa sub-samples inside any of its 2 (K - 1)
        triangles (L_i, R_i, L_i+1) and (R_i, R_i+1, L_i+1). With ``colors`` (P, 3) (else (0, 3)),
        ``out_rgb`` (nh, nw, 3) accumulates premultiplied colour with the same "over".
        """
        n_pieces = left.shape[0]
        colored = colors.shape[0] == n_pieces and n_pieces > 0
        k = left.shape[1]
        band = _BAND
        inv = 1.0 / aa
        hb = brush.shape[0]
        wb = brush.shape[1]
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
                                            # inside all three edges (_edge's values), without branches
                                            inside = (
                                                ((r0 - e0y * (px - bx)) * sgn >= 0.0)
                                                & ((r1 - e1y * (px - cx)) * sgn >= 0.0)
                                                & ((r2 - e2y * (px - ax)) * sgn >= 0.0)
                                            )
                                            bits |= np.uint64(inside) << np.uint64(sj * aa + si)
                                    mask[idx] = bits
                                # brush coordinates from the triangle the sample centre is most inside
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
                            val += (1.0 - au) * wv * brush[rr, cc0]
                            val += au * wv * brush[rr, cc1]
                        a = cov * opacity[pc] * val
                        out_alpha[y, x] = out_alpha[y, x] + a * (1.0 - out_alpha[y, x])
                        if colored:
                            for ch in range(3):
                                out_rgb[y, x, ch] = colors[pc, ch] * a + out_rgb[y, x, ch] * (
                                    1.0 - a
                                )
                        out_strokes[y, x] += 1

    return raster_strips


@banded("tri")
def smooth_duv(
    lo, hi, tri, bary, faces, frames, normal, position, dpos_dx, dpos_dy, eye, duv_dx, duv_dy
):
    """Replace ``duv_dx``, ``duv_dy`` (N, 2) in place by the smooth reconstruction.

    tri : (N,) global triangle; bary : (N, 3); faces : (T, 3) into ``frames`` (V, 3, 2), the
    per-vertex [dP/du, dP/dv]; normal, position, dpos_dx, dpos_dy : (N, 3); eye : (3,). The
    pixel footprint dP is moved along the view ray onto the plane of the shading normal,
    dP_n = dP - (n . dP) / (n . D) D with D = position - eye, and uv follows from the
    interpolated frame F by least squares, duv = (F^T F)^-1 F^T dP_n. Where the frame is
    degenerate or the view grazes (|n . D| < 0.05 |D|) the flat values are kept.
    """
    for i in range(lo, hi):
        f = tri[i]
        gu0 = 0.0
        gu1 = 0.0
        gu2 = 0.0
        gv0 = 0.0
        gv1 = 0.0
        gv2 = 0.0
        for c in range(3):
            v = faces[f, c]
            b = bary[i, c]
            gu0 += b * frames[v, 0, 0]
            gu1 += b * frames[v, 1, 0]
            gu2 += b * frames[v, 2, 0]
            gv0 += b * frames[v, 0, 1]
            gv1 += b * frames[v, 1, 1]
            gv2 += b * frames[v, 2, 1]
        a00 = gu0 * gu0 + gu1 * gu1 + gu2 * gu2
        a01 = gu0 * gv0 + gu1 * gv1 + gu2 * gv2
        a11 = gv0 * gv0 + gv1 * gv1 + gv2 * gv2
        det = a00 * a11 - a01 * a01
        if not (det > 1e-12 * (a00 * a11) and det > 0.0):
            continue
        d0 = position[i, 0] - eye[0]
        d1 = position[i, 1] - eye[1]
        d2 = position[i, 2] - eye[2]
        n0 = normal[i, 0]
        n1 = normal[i, 1]
        n2 = normal[i, 2]
        nd = n0 * d0 + n1 * d1 + n2 * d2
        dlen = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        nlen = math.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
        if not (abs(nd) >= 0.05 * dlen * nlen and dlen > 0.0):
            continue
        for axis in range(2):
            if axis == 0:
                p0, p1, p2 = dpos_dx[i, 0], dpos_dx[i, 1], dpos_dx[i, 2]
            else:
                p0, p1, p2 = dpos_dy[i, 0], dpos_dy[i, 1], dpos_dy[i, 2]
            lam = (n0 * p0 + n1 * p1 + n2 * p2) / nd
            p0 -= lam * d0
            p1 -= lam * d1
            p2 -= lam * d2
            r0 = gu0 * p0 + gu1 * p1 + gu2 * p2
            r1 = gv0 * p0 + gv1 * p1 + gv2 * p2
            du = (a11 * r0 - a01 * r1) / det
            dv = (a00 * r1 - a01 * r0) / det
            if axis == 0:
                duv_dx[i, 0] = du
                duv_dx[i, 1] = dv
            else:
                duv_dy[i, 0] = du
                duv_dy[i, 1] = dv


@banded("chunk_max")
def sample_inputs(
    lo,
    hi,
    sample,
    tri_id,
    mesh_id,
    uv,
    duv_dx,
    duv_dy,
    scale,
    charts,
    smooth,
    bary,
    faces,
    frames,
    normal,
    position,
    dpos_dx,
    dpos_dy,
    eye,
    orient,
    sym_m,
    sym,
    offset,
    group,
    shade,
    m_a,
    m_d,
    ambient,
    l_dir,
    l_color,
    l_point,
    l_pos,
    out_uv,
    out_dx,
    out_dy,
    out_scale,
    out_chart,
    out_dark,
    chunk_max,
):
    """Per-sample field inputs of the N covered samples ``sample`` (flat G-buffer indices).

    G-buffer channels come flattened to (H W, C) (tri_id, mesh_id: (H W,)) in float32 or
    float64, read as float64. Per sample: uv, flat duv_dx / duv_dy and the uv_scale of its
    object (``scale`` (objects, 2)), chart ``charts[tri]``; with ``smooth`` the derivatives of
    :func:`smooth_duv` (same arithmetic); with ``orient`` u' = M u + offset with M =
    ``sym_m[sym[tri]]`` (signed permutations) on uv, the derivatives and (|M|) the scale, and
    chart ``group[tri]``; with ``shade`` the darkness 1 - clip(Y, 0, 1) (``out_dark`` (N,)) of
    the diffuse colour m_a l_a + sum_i m_d f_d(N, L_i) l_i (lights (L, 3) directions (unit,
    directional) or positions (``l_point``), colours), Y its Rec. 709 luminance.
    ``chunk_max`` (chunks,) receives max |u' s| over each chunk.
    """
    n_samples = sample.shape[0]
    n_lights = l_color.shape[0]
    for ci in range(lo, hi):
        cmax = 0.0
        for i in range(ci * _CHUNK, min(n_samples, (ci + 1) * _CHUNK)):
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
                a00 = gu0 * gu0 + gu1 * gu1 + gu2 * gu2
                a01 = gu0 * gv0 + gu1 * gv1 + gu2 * gv2
                a11 = gv0 * gv0 + gv1 * gv1 + gv2 * gv2
                det = a00 * a11 - a01 * a01
                if det > 1e-12 * (a00 * a11) and det > 0.0:
                    d0 = np.float64(position[sp, 0]) - eye[0]
                    d1 = np.float64(position[sp, 1]) - eye[1]
                    d2 = np.float64(position[sp, 2]) - eye[2]
                    n0 = np.float64(normal[sp, 0])
                    n1 = np.float64(normal[sp, 1])
                    n2 = np.float64(normal[sp, 2])
                    nd = n0 * d0 + n1 * d1 + n2 * d2
                    dlen = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
                    nlen = math.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
                    if abs(nd) >= 0.05 * dlen * nlen and dlen > 0.0:
                        for axis in range(2):
                            if axis == 0:
                                p0 = np.float64(dpos_dx[sp, 0])
                                p1 = np.float64(dpos_dx[sp, 1])
                                p2 = np.float64(dpos_dx[sp, 2])
                            else:
                                p0 = np.float64(dpos_dy[sp, 0])
                                p1 = np.float64(dpos_dy[sp, 1])
                                p2 = np.float64(dpos_dy[sp, 2])
                            lam = (n0 * p0 + n1 * p1 + n2 * p2) / nd
                            p0 -= lam * d0
                            p1 -= lam * d1
                            p2 -= lam * d2
                            r0 = gu0 * p0 + gu1 * p1 + gu2 * p2
                            r1 = gv0 * p0 + gv1 * p1 + gv2 * p2
                            du = (a11 * r0 - a01 * r1) / det
                            dv = (a00 * r1 - a01 * r0) / det
                            if axis == 0:
                                xu = du
                                xv = dv
                            else:
                                yu = du
                                yv = dv
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
                # unit normal as refnpr.formulas._shading_checks.unit_vectors computes it
                n0 = np.float64(normal[sp, 0])
                n1 = np.float64(normal[sp, 1])
                n2 = np.float64(normal[sp, 2])
                nm = max(abs(n0), abs(n1), abs(n2))
                if nm > 0.0:
                    n0 /= nm
                    n1 /= nm
                    n2 /= nm
                nl = math.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
                if nl > 0.0:
                    n0 /= nl
                    n1 /= nl
                    n2 /= nl
                r = m_a[mi, 0] * ambient[0]  # Veryovka eq. 1: m_a l_a
                g = m_a[mi, 1] * ambient[1]
                bl = m_a[mi, 2] * ambient[2]
                for li in range(n_lights):
                    if l_point[li]:
                        e0 = l_pos[li, 0] - np.float64(position[sp, 0])
                        e1 = l_pos[li, 1] - np.float64(position[sp, 1])
                        e2 = l_pos[li, 2] - np.float64(position[sp, 2])
                        el = math.sqrt(e0 * e0 + e1 * e1 + e2 * e2)
                        if el > 0.0:
                            e0 /= el
                            e1 /= el
                            e2 /= el
                        else:
                            e0 = 0.0
                            e1 = 0.0
                            e2 = 0.0
                        em = max(abs(e0), abs(e1), abs(e2))
                        if em > 0.0:
                            e0 /= em
                            e1 /= em
                            e2 /= em
                        ell = math.sqrt(e0 * e0 + e1 * e1 + e2 * e2)
                        if ell > 0.0:
                            e0 /= ell
                            e1 /= ell
                            e2 /= ell
                    else:
                        e0 = l_dir[li, 0]
                        e1 = l_dir[li, 1]
                        e2 = l_dir[li, 2]
                    fd = n0 * e0 + n1 * e1 + n2 * e2
                    fd = fd if fd >= 0.0 else 0.0  # eq. 1: f_d = max(N.L, 0)
                    fd = fd if fd <= 1.0 else 1.0
                    r = r + m_d[mi, 0] * fd * l_color[li, 0]  # eq. 1: + m_d f_d l_i
                    g = g + m_d[mi, 1] * fd * l_color[li, 1]
                    bl = bl + m_d[mi, 2] * fd * l_color[li, 2]
                # darkness = 1 - clip(Rec. 709 luminance, 0, 1), summed r, g, then b (as
                # halftone's; a BLAS dot product may fuse or reorder, by CPU); NaN stays NaN
                lum = (r * _LUMA_R + g * _LUMA_G) + bl * _LUMA_B
                lum = 0.0 if lum < 0.0 else (1.0 if lum > 1.0 else lum)
                out_dark[i] = 1.0 - lum
        chunk_max[ci] = cmax


@njit(inline="always")
def _gather_sample(
    i,
    p,
    q,
    d_p,
    d_q,
    s,
    rho,
    chart,
    layer,
    max_level,
    lam,
    len_jit,
    hw_px,
    salt_len,
    salt_tone,
    k,
    base,
    cap,
    out_id,
    out_t,
    out_layer,
    out_level,
    out_src,
):
    """The fragments of one sample and layer: :func:`_enumerate` (end_px = 0, candidates past
    the first ``_CAP`` dropped as there) fused with the density and t tests of ``field_pass``
    (MODE_EMIT). Fragment k (counted on from ``k``) goes to ``base + k`` while k < ``cap``.
    Returns the new k."""
    if not (s == s):  # NaN scale
        return k
    big_l = math.floor(s)
    f = s - big_l
    thin = 1.0
    if big_l < 0:
        thin = math.pow(2.0, s)
        big_l = 0
        f = 0.0
    if big_l >= max_level:
        big_l = max_level
        f = 0.0
    top = big_l + 1 if f > 0.0 else big_l
    alpha = math.pow(2.0, f) - 1.0
    n = 0
    # divisions hoisted or made exact products (double division is slow): the same values
    hw_q = hw_px / d_q
    end_cells = 0.0 / d_p
    for lev in range(top + 1):
        gain = thin if lev <= big_l else alpha
        if gain * rho <= 0.0:
            continue
        limit = rho * gain
        scale = float(1 << lev)
        inv_scale = 1.0 / scale  # a power of two: x * inv_scale == x / scale, bit for bit
        rows = 7.0 * scale
        ry0 = int(math.floor((q - hw_q) * rows))
        ry1 = int(math.floor((q + hw_q) * rows)) + 1
        half_cells = 0.5 * lam * (1.0 + len_jit) + end_cells * scale
        for ry in range(ry0, ry1 + 1):
            q_row = ry / rows
            dist = abs(q - q_row) * d_q
            if dist > hw_px:
                continue
            gy = ry // 7
            r = ry - 7 * gy
            kx = _KX[r]
            kx7 = _KX7[r]
            ps = p * scale - kx7
            gx0 = int(math.floor(ps - half_cells))
            gx1 = int(math.floor(ps + half_cells)) + 1
            reach = 0.5 * lam * (1.0 + abs(len_jit)) + 1e-6 + 1e-9 * abs(ps)
            for gx in range(gx0, gx1 + 1):
                if abs(ps - gx) > reach:
                    continue  # every length puts t outside [0, 1]: rejected below anyway
                if lev > 0 and (gx & 1) == (kx & 1) and (gy & 1) == (r & 1):
                    continue  # inherited: enumerated at its birth level
                sid = _pack(chart, layer, lev, gx, gy, r)
                h = _hash01(sid, salt_len)
                length = lam * (1.0 + len_jit * (2.0 * h - 1.0)) * inv_scale
                p_start = (gx + kx7) * inv_scale - 0.5 * length
                t = (p - p_start) / length
                beyond = max(-t, t - 1.0) * length * d_p
                if beyond > 0.0:
                    continue
                if n < _CAP:
                    tau = _hash01(sid, salt_tone)
                    if tau < limit and t >= 0.0 and t <= 1.0:
                        if k < cap:
                            o = base + k
                            out_id[o] = sid
                            out_t[o] = t
                            out_layer[o] = layer
                            out_level[o] = lev
                            out_src[o] = i
                        k += 1
                    n += 1
    return k


@banded("chunks")
def field_gather(
    lo,
    hi,
    chunks,
    uv,
    duv_dx,
    duv_dy,
    uv_scale,
    darkness,
    chart,
    cos_a,
    sin_a,
    tone_lo,
    density,
    period,
    max_level,
    lam,
    len_jit,
    width_px,
    salt_tone,
    salt_len,
    dst_off,
    dst_cap,
    chunk_count,
    out_id,
    out_t,
    out_layer,
    out_level,
    out_src,
):
    """TAMISS fragments of the sample chunks ``chunks`` (``_CHUNK`` samples each) in one pass.

    The fragments of chunk ``chunks[j]`` (ordered by sample, layer, level, row, cell, as
    ``field_pass`` emits them) are written from ``dst_off[j]`` into ``out_*`` (id, t, layer,
    birth level, sample index), at most ``dst_cap[j]`` of them; ``chunk_count[j]`` receives
    their number (which may exceed the capacity: then run the chunk again with room for all).
    """
    n_samples = uv.shape[0]
    n_layers = cos_a.shape[0]
    for j in range(lo, hi):
        ci = chunks[j]
        base = dst_off[j]
        cap = dst_cap[j]
        k = 0
        for i in range(ci * _CHUNK, min(n_samples, (ci + 1) * _CHUNK)):
            su = uv_scale[i, 0]
            sv = uv_scale[i, 1]
            u = uv[i, 0] * su
            v = uv[i, 1] * sv
            ux = duv_dx[i, 0] * su
            vx = duv_dx[i, 1] * sv
            uy = duv_dy[i, 0] * su
            vy = duv_dy[i, 1] * sv
            for lay in range(n_layers):
                ca = cos_a[lay]
                sa = sin_a[lay]
                rho = (darkness[i] - tone_lo[lay]) / (1.0 - tone_lo[lay]) * density
                rho = min(max(rho, 0.0), 1.0)
                if rho <= 0.0:
                    continue
                p = ca * u + sa * v
                q = -sa * u + ca * v
                gp = math.hypot(ca * ux + sa * vx, ca * uy + sa * vy)
                gq = math.hypot(-sa * ux + ca * vx, -sa * uy + ca * vy)
                if not (gq > 0.0 and gp > 0.0 and gq < 1e30 and gp < 1e30):
                    continue
                d_p = 1.0 / gp
                d_q = 1.0 / gq
                s = math.log2(d_q / (7.0 * period))
                k = _gather_sample(
                    i, p, q, d_p, d_q, s, rho, chart[i], lay, max_level, lam, len_jit,
                    0.5 * width_px, salt_len, salt_tone, k, base, cap,
                    out_id, out_t, out_layer, out_level, out_src,
                )  # fmt: skip
        chunk_count[j] = k


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


@banded("src_off")
def finish_fragments(lo, hi, src_off, src_len, dst_off, src, sample, width, n_axis, in_id, in_t,
                     in_layer, in_level, out_id, out_t, out_layer, out_level, out_sample,
                     out_x, out_y):  # fmt: skip
    """Copy runs ``[src_off[j], + src_len[j])`` of gathered fragments to ``dst_off[j]``, with
    each fragment's flat sample index ``sample[src]`` and its centre in pixels
    ((sx + 0.5) / n_axis, (sy + 0.5) / n_axis) on a grid ``width`` samples wide."""
    for j in range(lo, hi):
        a = src_off[j]
        b = dst_off[j]
        last = -1
        px = 0.0
        py = 0.0
        for m in range(src_len[j]):
            sp = sample[src[a + m]]
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
def _pairwise(a, lo, n, c, zero):
    """numpy's pairwise summation (``add.reduce``) of ``a[lo:lo + n, c]`` in a's dtype."""
    if n < 8:
        res = zero
        for i in range(lo, lo + n):
            res += a[i, c]
        return res
    if n <= 128:
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
    n2 = n // 2
    n2 -= n2 % 8
    return _pairwise(a, lo, n2, c, zero) + _pairwise(a, lo + n2, n - n2, c, zero)


@banded(lambda perm, starts, *rest: starts.shape[0] - 1)
def group_sums(i_lo, i_hi, perm, starts, t, x, y, half_c, lo, hi, origin, moments, rows):
    """Per group g (fragments ``perm[starts[g]:starts[g + 1]]``, in that order): min and max of
    t, the centre of the (x, y) bounding box, and the sums of the 15 regressors (s^0..s^6,
    s^0..s^3 (x - o_x), s^0..s^3 (y - o_y)) with s = normalize_t(t, lo, hi), all in the dtype of
    t, x, y, ``half_c`` (a 1-array holding 0.5) and the outputs. The same arithmetic as the
    formula layer's ``normalize_t``, ``fragment_regressors`` and ``aggregate`` (``reduceat``:
    the first row plus numpy's pairwise sum of the others); ``rows`` (n, 15) is scratch."""
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
        half = (th - tl) * hc
        centre = tl + half
        lo[g] = tl
        hi[g] = th
        origin[g, 0] = ox
        origin[g, 1] = oy
        for m in range(a, b):
            i = perm[m]
            s = (t[i] - centre) / half if half > 0 else zero  # normalize_t (0 if flat)
            xr = x[i] - ox
            yr = y[i] - oy
            p2 = s * s
            p3 = p2 * s
            p4 = p3 * s
            p5 = p4 * s
            # eq. 1: t_i t_i^T (as power sums), t_i x_i, t_i y_i
            rows[m, 0] = one
            rows[m, 1] = s
            rows[m, 2] = p2
            rows[m, 3] = p3
            rows[m, 4] = p4
            rows[m, 5] = p5
            rows[m, 6] = p5 * s
            rows[m, 7] = xr
            rows[m, 8] = s * xr
            rows[m, 9] = p2 * xr
            rows[m, 10] = p3 * xr
            rows[m, 11] = yr
            rows[m, 12] = s * yr
            rows[m, 13] = p2 * yr
            rows[m, 14] = p3 * yr
        for c in range(15):  # additive blending pass
            acc = rows[a, c]
            if b - a > 1:
                acc += _pairwise(rows, a + 1, b - a - 1, c, zero)
            moments[g, c] = acc


@banded("x")
def strip_sides(lo, hi, x, y, nx, ny, h, left, right):
    """Strip vertices (P, K, 2): left = (x + h nx, y + h ny), right = (x - h nx, y - h ny), from
    (P, K) float64 centreline points, unit normals and half widths."""
    for i in range(lo, hi):
        for j in range(x.shape[1]):
            ox = h[i, j] * nx[i, j]
            oy = h[i, j] * ny[i, j]
            left[i, j, 0] = x[i, j] + ox
            left[i, j, 1] = y[i, j] + oy
            right[i, j, 0] = x[i, j] - ox
            right[i, j, 1] = y[i, j] - oy


@njit
def _pairwise_row(a, i, n):
    """numpy's pairwise summation (``add.reduce`` along a contiguous axis) of ``a[i, :n]``
    (float64), n <= 128 (one block: no recursion, which numba's cache does not reload)."""
    if n < 8:
        res = 0.0
        for j in range(n):
            res += a[i, j]
        return res
    r0 = a[i, 0]
    r1 = a[i, 1]
    r2 = a[i, 2]
    r3 = a[i, 3]
    r4 = a[i, 4]
    r5 = a[i, 5]
    r6 = a[i, 6]
    r7 = a[i, 7]
    j = 8
    while j < n - (n % 8):
        r0 += a[i, j]
        r1 += a[i, j + 1]
        r2 += a[i, j + 2]
        r3 += a[i, j + 3]
        r4 += a[i, j + 4]
        r5 += a[i, j + 5]
        r6 += a[i, j + 6]
        r7 += a[i, j + 7]
        j += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while j < n:
        res += a[i, j]
        j += 1
    return res


@banded("t")
def mean_speeds(i_lo, i_hi, t, c_x, c_y, t_min, t_max, half_c, span, seg, out):
    """Per fitted stroke i: the length of the polyline through the curve at t[i, :] (S, M),
    M <= 129, over
    ``span[i]`` (float64; 0 where span <= 0), into ``out`` (S,) float64.

    As ``strokes.mean_speed`` computes it: the centred fit parameter s = (t - (lo + h)) / h,
    h = (hi - lo) 0.5 (0 where h <= 0), the cubics ((c3 s + c2) s + c1) s + c0 in the dtype of
    ``t``, ``c_x``, ``c_y`` (S, 4), ``t_min``, ``t_max`` and ``half_c`` (a 1-array holding 0.5),
    then in float64 the segment lengths hypot(dx, dy) summed as numpy's pairwise ``sum``;
    ``seg`` (S, M - 1) float64 is scratch."""
    hc = half_c[0]
    zero = hc - hc
    m = t.shape[1]
    for i in range(i_lo, i_hi):
        lo = t_min[i]
        half = (t_max[i] - lo) * hc
        mid = lo + half
        ok = half > zero
        xp = 0.0
        yp = 0.0
        for k in range(m):
            s = (t[i, k] - mid) / half if ok else zero
            x = ((c_x[i, 3] * s + c_x[i, 2]) * s + c_x[i, 1]) * s + c_x[i, 0]
            y = ((c_y[i, 3] * s + c_y[i, 2]) * s + c_y[i, 1]) * s + c_y[i, 0]
            x64 = np.float64(x)
            y64 = np.float64(y)
            if k > 0:
                seg[i, k - 1] = math.hypot(x64 - xp, y64 - yp)
            xp = x64
            yp = y64
        arc = _pairwise_row(seg, i, m - 1)
        out[i] = arc / span[i] if span[i] > 0.0 else 0.0


@njit(inline="always")
def _cubic(c, i, s):
    """``StrokeFit._poly``: ((c3 s + c2) s + c1) s + c0 of row i of c (S, 4), in c's dtype."""
    return ((c[i, 3] * s + c[i, 2]) * s + c[i, 1]) * s + c[i, 0]


@njit(inline="always")
def _cubic_d(c, i, s, two, three, zero):
    """``StrokeFit.derivative``'s polynomial: the cubic of (c1, 2 c2, 3 c3, 0) at s."""
    return ((zero * s + three * c[i, 3]) * s + two * c[i, 2]) * s + c[i, 1]


@banded("t")
def centrelines(i_lo, i_hi, t, c_x, c_y, t_min, t_max, consts, speed, extend, tbuf, x, y, tx, ty):
    """Points x, y and unit tangents tx, ty (S, K) float64 of the drawn curves at t (S, K)
    float64 (finite), as ``strokes.centreline`` computes them with ``StrokeFit.evaluate`` and
    ``derivative`` (centred basis): t clipped to [t_min, t_max], the fit parameter
    s = (t - (lo + h)) / h, h = (hi - lo) 0.5 (0 where h <= 0), the cubic and its derivative
    (times ds/dt = 2 / (hi - lo), 0 where hi - lo <= 0) in the dtype of c_x, c_y (S, 4),
    t_min, t_max (S,) and ``consts`` (0.5, 2, 3, 0), then in float64 the unit tangent (the
    chord r(hi) - r(lo) where the derivative vanishes, as ``strokes._unit``) and, with
    ``extend`` (some t outside its row's range), the tangent line past the ends at ``speed``
    (S,) px per unit t; ``tbuf`` (S, K) in the fit's dtype is scratch."""
    c05 = consts[0]
    two = consts[1]
    three = consts[2]
    zero = consts[3]
    for i in range(i_lo, i_hi):
        lo = t_min[i]
        hi = t_max[i]
        lo64 = np.float64(lo)
        hi64 = np.float64(hi)
        half = (hi - lo) * c05
        ok = half > zero
        mid = lo + half
        width = hi - lo
        ds = two / width if width > zero else zero
        s_lo = (lo - mid) / half if ok else zero
        s_hi = (hi - mid) / half if ok else zero
        fx = np.float64(_cubic(c_x, i, s_hi)) - np.float64(_cubic(c_x, i, s_lo))
        fy = np.float64(_cubic(c_y, i, s_hi)) - np.float64(_cubic(c_y, i, s_lo))
        fn = math.hypot(fx, fy)
        fok = fn > 1e-12
        gx = fx / fn if fok else 1.0
        gy = fy / fn if fok else 0.0
        for j in range(t.shape[1]):
            tj = t[i, j]
            tc = min(max(tj, lo64), hi64)
            tbuf[i, j] = tc  # t in the fit's dtype (rounded, as astype)
            tv = tbuf[i, j]
            s = (tv - mid) / half if ok else zero
            px = np.float64(_cubic(c_x, i, s))
            py = np.float64(_cubic(c_y, i, s))
            dx = np.float64(_cubic_d(c_x, i, s, two, three, zero) * ds)
            dy = np.float64(_cubic_d(c_y, i, s, two, three, zero) * ds)
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

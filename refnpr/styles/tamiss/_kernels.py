"""numba kernels of the TAM / TAMISS styles (no validation here; see the calling modules).

* ``chart_labels``: connected components of a mesh's faces through shared vertex indices.
* ``field_pass``: per G-buffer sample, enumerate the strokes of the RPTAM field
  (``field``) that cover it, then either count/emit TAMISS fragments or accumulate the
  anti-aliased TAM/RPTAM ink.
* ``raster_strips``: anti-aliased rasterization of image-space triangle strips (supersampled
  coverage of the union of a strip's triangles), composited in order with "over".
"""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from refnpr._jit import njit, pnjit

_M1 = np.uint64(0x9E3779B97F4A7C15)
_M2 = np.uint64(0xBF58476D1CE4E5B9)
_M3 = np.uint64(0x94D049BB133111EB)
_S30 = np.uint64(30)
_S27 = np.uint64(27)
_S31 = np.uint64(31)
_S11 = np.uint64(11)
_INV53 = 1.0 / 9007199254740992.0
_KX = np.array([0, 6, 5, 1, 3, 4, 2], dtype=np.int64)
_CELL_OFF = 1 << 21

#: Fragment pass modes.
MODE_COUNT, MODE_EMIT, MODE_TAM_CLIP, MODE_TAM_FADE = 0, 1, 2, 3

_CHUNK = 512
_CAP = 256


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


@njit
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
    for lev in range(top + 1):
        gain = thin if lev <= big_l else alpha
        if gain * rho <= 0.0:
            continue
        scale = float(1 << lev)
        rows = 7.0 * scale
        hw_q = hw_px / d_q
        ry0 = int(math.floor((q - hw_q) * rows))
        ry1 = int(math.floor((q + hw_q) * rows)) + 1
        for ry in range(ry0, ry1 + 1):
            q_row = ry / rows
            dist = abs(q - q_row) * d_q
            if dist > hw_px:
                continue
            gy = ry // 7
            r = ry - 7 * gy
            kx = _KX[r]
            half_cells = 0.5 * lam * (1.0 + len_jit) + end_px / d_p * scale
            ps = p * scale - kx / 7.0
            gx0 = int(math.floor(ps - half_cells))
            gx1 = int(math.floor(ps + half_cells)) + 1
            for gx in range(gx0, gx1 + 1):
                if lev > 0 and (gx & 1) == (kx & 1) and (gy & 1) == (r & 1):
                    continue  # inherited: enumerated at its birth level
                sid = _pack(chart, layer, lev, gx, gy, r)
                h = _hash01(sid, salt_len)
                length = lam * (1.0 + len_jit * (2.0 * h - 1.0)) / scale
                p_start = (gx + kx / 7.0) / scale - 0.5 * length
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


@pnjit
def field_pass(
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
    n_chunks = (n_samples + _CHUNK - 1) // _CHUNK
    tam = mode >= 2
    for ci in prange(n_chunks):
        c_id = np.empty(_CAP, dtype=np.int64)
        c_t = np.empty(_CAP)
        c_dist = np.empty(_CAP)
        c_end = np.empty(_CAP)
        c_gain = np.empty(_CAP)
        c_level = np.empty(_CAP, dtype=np.int64)
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
                    hw = 0.5 * width_px * (1.0 + wid_jit) + 0.5
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


@pnjit
def raster_strips(
    left,
    right,
    tv,
    opacity,
    bbox,
    nh,
    nw,
    aa,
    brush,
    t_wrap,
    out_alpha,
    out_strokes,
    colors,
    out_rgb,
):
    """Rasterize strips into ``out_alpha`` (nh, nw) with "over" in piece order.

    left, right : (P, K, 2) vertices in sample units; tv : (P, K) brush u (stroke t) per vertex
    pair; opacity : (P,); bbox : (P, 4) int64 x0, y0, x1, y1 (inclusive, clipped); aa : sub-samples
    per axis (<= 8); brush : (Hb, Wb) alpha multiplier sampled at (u = t, v = across), wrapping
    in u when ``t_wrap``; out_strokes : (nh, nw) int32, number of pieces touching each sample.
    Each piece's coverage is the fraction of aa x aa sub-samples inside any of its 2 (K - 1)
    triangles (L_i, R_i, L_i+1) and (R_i, R_i+1, L_i+1). With ``colors`` (P, 3) (else (0, 3)),
    ``out_rgb`` (nh, nw, 3) accumulates premultiplied colour with the same "over".
    """
    n_pieces = left.shape[0]
    colored = colors.shape[0] == n_pieces and n_pieces > 0
    k = left.shape[1]
    band = 16
    n_bands = (nh + band - 1) // band
    inv = 1.0 / aa
    hb = brush.shape[0]
    wb = brush.shape[1]
    for bi in prange(n_bands):
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
            mask = np.zeros(h * w, dtype=np.uint64)
            best = np.full(h * w, -np.inf)
            bu = np.zeros(h * w)
            bv = np.zeros(h * w)
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
                    tx0 = max(x0, int(math.floor(min(ax, bx, cx))))
                    tx1 = min(x1, int(math.floor(max(ax, bx, cx))))
                    ty0 = max(y0, int(math.floor(min(ay, by, cy))))
                    ty1 = min(y1, int(math.floor(max(ay, by, cy))))
                    for y in range(ty0, ty1 + 1):
                        for x in range(tx0, tx1 + 1):
                            idx = (y - y0) * w + (x - x0)
                            bits = mask[idx]
                            for sj in range(aa):
                                py = y + (sj + 0.5) * inv
                                for si in range(aa):
                                    px = x + (si + 0.5) * inv
                                    e0 = _edge(bx, by, cx, cy, px, py) * sgn
                                    e1 = _edge(cx, cy, ax, ay, px, py) * sgn
                                    e2 = _edge(ax, ay, bx, by, px, py) * sgn
                                    if e0 >= 0.0 and e1 >= 0.0 and e2 >= 0.0:
                                        bits |= np.uint64(1) << np.uint64(sj * aa + si)
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
                    val = 0.0
                    for dv in range(2):
                        rr = min(max(iv + dv, 0), hb - 1)
                        wv = av if dv == 1 else 1.0 - av
                        for du in range(2):
                            cc = iu + du
                            if t_wrap:
                                cc = cc % wb
                            else:
                                cc = min(max(cc, 0), wb - 1)
                            wu = au if du == 1 else 1.0 - au
                            val += wu * wv * brush[rr, cc]
                    a = cov * opacity[pc] * val
                    out_alpha[y, x] = out_alpha[y, x] + a * (1.0 - out_alpha[y, x])
                    if colored:
                        for ch in range(3):
                            out_rgb[y, x, ch] = colors[pc, ch] * a + out_rgb[y, x, ch] * (1.0 - a)
                    out_strokes[y, x] += 1


@pnjit
def smooth_duv(tri, bary, faces, frames, normal, position, dpos_dx, dpos_dy, eye, duv_dx, duv_dy):
    """Replace ``duv_dx``, ``duv_dy`` (N, 2) in place by the smooth reconstruction.

    tri : (N,) global triangle; bary : (N, 3); faces : (T, 3) into ``frames`` (V, 3, 2), the
    per-vertex [dP/du, dP/dv]; normal, position, dpos_dx, dpos_dy : (N, 3); eye : (3,). The
    pixel footprint dP is moved along the view ray onto the plane of the shading normal,
    dP_n = dP - (n . dP) / (n . D) D with D = position - eye, and uv follows from the
    interpolated frame F by least squares, duv = (F^T F)^-1 F^T dP_n. Where the frame is
    degenerate or the view grazes (|n . D| < 0.05 |D|) the flat values are kept.
    """
    n = tri.shape[0]
    for i in prange(n):
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

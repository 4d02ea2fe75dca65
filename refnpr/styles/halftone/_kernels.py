"""numba kernels of the ``halftone`` style (private; inputs validated by :mod:`.fused`).

One banded pass over the samples of one object (bands of sample-grid rows, no reductions, so
the result does not depend on the thread count): target intensity (Veryovka
eq. 1 as luminance, DOT3 stroke lighting of Freudenberg sec. 5.2, indication of sec. 5.1), the
screen lookup at the sample's uv and LOD (sec. 3; GL's isotropic LOD or the anisotropic probes
of ``screens.screen_footprint``), the binary (sec. 3.1, mux form) or smooth (sec. 3.2)
threshold, per-level thresholding with tone LUTs, and ink/paper compositing into float32
straight-alpha RGBA. float64 arithmetic in the order of the numpy path
(``refnpr.styles.halftone.shading`` / ``screens`` and ``refnpr.formulas``); ``log2`` and ``pow``
are libm's, where numpy may use its SIMD versions (an ulp apart at most).

Speed (issue 11; same bits throughout): each row's span of the object first goes through
``_row_units``, branch-free SIMD passes for unit(N), V and each directional light's N.H (their
dependent divisions and roots were most of the per-sample time), and the screen lookup of the
colour path is written out in the loop body with the scalar ``_taps`` (a sampler that takes
arrays is a call paying NRT reference counts per sample). 1920x1080 spp 4 teapot: 218 -> 94 ms.
"""

from __future__ import annotations

import math

import numpy as np

from refnpr._jit import banded, njit, specialised

#: ``threshold`` codes.
THRESHOLD_BINARY = 0
THRESHOLD_SMOOTH = 1
#: ``show`` codes.
SHOW_COLOR = 0
SHOW_SCREEN = 1
SHOW_NORMALS = 2
SHOW_INTENSITY = 3
#: ``light_kind`` codes.
LIGHT_DIRECTIONAL = 0
LIGHT_POINT = 1
#: Rec. 709 luminance weights (``shading.LUMA``).
LUMA_R = 0.2126
LUMA_G = 0.7152
LUMA_B = 0.0722


@njit
def _wrap(i, n):
    r = i % n
    return r + n if r < 0 else r


@njit
def _unit(x, y, z):
    """``formulas._shading_checks.unit_vectors`` of one vector: max-scaling, then length."""
    m = max(abs(x), abs(y), abs(z))
    if m > 0.0:
        x = x / m
        y = y / m
        z = z / m
    length = math.sqrt((x * x + y * y) + z * z)
    if length > 0.0:
        x = x / length
        y = y / length
        z = z / length
    return x, y, z


@njit
def _taps(offset, rows, cols, u, v):
    """Texel indices and weights of a GL_LINEAR / GL_REPEAT sample of one level (rows, cols,
    at ``offset`` in the packed texels), in ``texture._kernels``' arithmetic. Scalars only, so
    that it inlines into the hot loop (a helper taking arrays is a call with NRT reference
    counts).
    GL_REPEAT by compare and subtract where the index is at most one period out (always, for a
    finite uv), the modulo otherwise."""
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
        i0 = _wrap(ix, cols)
        i1 = _wrap(ix + 1, cols)
        j0 = _wrap(iy, rows)
        j1 = _wrap(iy + 1, rows)
    w00 = (1.0 - fx) * (1.0 - fy)
    w10 = fx * (1.0 - fy)
    w01 = (1.0 - fx) * fy
    w11 = fx * fy
    r0 = offset + j0 * cols
    r1 = offset + j1 * cols
    return r0 + i0, r0 + i1, r1 + i0, r1 + i1, w00, w10, w01, w11


@njit
def _bilinear(texels, offset, rows, cols, u, v, c):
    """GL_LINEAR / GL_REPEAT sample of channel c of one level (``texture._kernels``' order)."""
    i00, i10, i01, i11, w00, w10, w01, w11 = _taps(offset, rows, cols, u, v)
    return w00 * texels[i00, c] + w10 * texels[i10, c] + w01 * texels[i01, c] + w11 * texels[i11, c]


@njit
def _level(texels, offsets, shapes, k, u, v, c):
    """Bilinear sample of integer level k (clamped to the pyramid), as ``sample_level``."""
    top = offsets.shape[0] - 1
    k = min(max(k, 0), top)
    return 0.0 + 1.0 * _bilinear(texels, offsets[k], shapes[k, 0], shapes[k, 1], u, v, c)


@njit
def _trilinear(texels, offsets, shapes, u, v, lod, c):
    """GL_LINEAR_MIPMAP_LINEAR sample, as ``texture._kernels.sample_trilinear``."""
    top = offsets.shape[0] - 1
    lam = min(max(lod, 0.0), float(top))
    k0 = np.int64(math.floor(lam))
    k1 = min(k0 + 1, top)
    f = lam - k0
    r = 0.0 + (1.0 - f) * _bilinear(texels, offsets[k0], shapes[k0, 0], shapes[k0, 1], u, v, c)
    if f > 0.0:
        r = r + f * _bilinear(texels, offsets[k1], shapes[k1, 0], shapes[k1, 1], u, v, c)
    return r


@njit
def _filtered(texels, offsets, shapes, u, v, lod, probes, ax, ay, c):
    """``screens.sample_screen``: trilinear, or the mean of ``probes`` trilinear probes at
    ``(u, v) + axis ((j + 1/2) / probes - 1/2)`` (anisotropic filtering)."""
    if probes == 0:
        return _trilinear(texels, offsets, shapes, u, v, lod, c)
    acc = 0.0
    for j in range(probes):
        t = (j + 0.5) / probes - 0.5
        acc = acc + _trilinear(texels, offsets, shapes, u + ax * t, v + ay * t, lod, c)
    return acc / probes


@njit
def _level_filtered(texels, offsets, shapes, k, u, v, probes, ax, ay):
    """``screens.sample_screen_levels``' sample of level k (mean of the probes)."""
    if probes == 0:
        return _level(texels, offsets, shapes, k, u, v, np.int64(0))
    acc = 0.0
    for j in range(probes):
        t = (j + 0.5) / probes - 0.5
        acc = acc + _level(texels, offsets, shapes, k, u + ax * t, v + ay * t, np.int64(0))
    return acc / probes


@njit
def _interp(x, xp, fp):
    """``np.interp(x, xp, fp)`` for increasing xp (numpy's branches and arithmetic)."""
    n = xp.shape[0]
    if x < xp[0]:
        return fp[0]
    if x > xp[n - 1]:
        return fp[n - 1]
    j = np.int64(x * (n - 1))  # guess, then the bracket xp[j] <= x < xp[j + 1]
    j = min(max(j, 0), n - 1)
    while j > 0 and xp[j] > x:
        j -= 1
    while j < n - 1 and xp[j + 1] <= x:
        j += 1
    if j == n - 1:
        return fp[j]
    if xp[j] == x:
        return fp[j]
    slope = (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j])
    r = slope * (x - xp[j]) + fp[j]
    if math.isnan(r):
        r = slope * (x - xp[j + 1]) + fp[j + 1]
        if math.isnan(r) and fp[j] == fp[j + 1]:
            r = fp[j]
    return r


@njit
def _threshold(s, x, mode, c, top):
    if mode == THRESHOLD_BINARY:
        tmp = s + (x - 0.5)  # sec. 3.1: add(tex, col - 0.5)
        return 1.0 if tmp > 0.5 else 0.0  # sec. 3.1: mux(tmp, 0, 1)
    tmp = (1.0 - s - x) * c  # sec. 3.2: add(1 - tex, -col) * C
    return min(max(top - tmp, 0.0), 1.0)  # sec. 3.2: 1 - tmp, clamped


@njit
def _unit_rows(ax, ay, az):
    """``_unit`` of the vectors (ax[x], ay[x], az[x]) in place (three (n,) float64 views): the
    same operations as selects, in two passes that compile to SIMD divisions and roots (loops
    from 0 over whole views: a loop from an offset, or over a 2D array, stays scalar)."""
    for x in range(ax.shape[0]):
        m = max(abs(ax[x]), abs(ay[x]), abs(az[x]))
        ok = m > 0.0
        ax[x] = ax[x] / m if ok else ax[x]
        ay[x] = ay[x] / m if ok else ay[x]
        az[x] = az[x] / m if ok else az[x]
    for x in range(ax.shape[0]):
        length = math.sqrt((ax[x] * ax[x] + ay[x] * ay[x]) + az[x] * az[x])
        ok = length > 0.0
        ax[x] = ax[x] / length if ok else ax[x]
        ay[x] = ay[x] / length if ok else ay[x]
        az[x] = az[x] / length if ok else az[x]


@njit
def _row_units(nrm, pos, eye, specular, light_kind, unit_l, scr, x0, x1):
    """The per-sample unit vectors of one row's span, branch-free over contiguous scratch
    (the per-sample loop waited on their divisions and roots): ``un`` = unit(N), and where
    ``specular`` ``v`` = unit(normalize(eye - p)) (ShadeContext.view_dir) and, per directional
    light i, ``base[i]`` = clip(N . unit(L + V), 0, 1) (``h`` scratch). The operations and
    their order are the per-sample formulas', so every value has the same bits; samples of
    other objects in the span get values nobody reads.

    nrm, pos (n * 3,) float: the span's normals and positions (n = x1 - x0). scr (9 + L, nW)
    float64 scratch, columns [x0, x1) written: un (scr 0-2), v (3-5), h (6-8), base (9 + i).
    Its rows are taken as 1D contiguous views, which LLVM vectorizes (2D or strided views
    stay scalar).
    """
    n = x1 - x0
    un0, un1, un2 = scr[0, x0:x1], scr[1, x0:x1], scr[2, x0:x1]
    for x in range(n):
        un0[x] = np.float64(nrm[3 * x])
        un1[x] = np.float64(nrm[3 * x + 1])
        un2[x] = np.float64(nrm[3 * x + 2])
    _unit_rows(un0, un1, un2)
    if not specular:
        return
    v0, v1, v2 = scr[3, x0:x1], scr[4, x0:x1], scr[5, x0:x1]
    for x in range(n):
        v0[x] = eye[0] - np.float64(pos[3 * x])
        v1[x] = eye[1] - np.float64(pos[3 * x + 1])
        v2[x] = eye[2] - np.float64(pos[3 * x + 2])
    for x in range(n):
        length = math.sqrt((v0[x] * v0[x] + v1[x] * v1[x]) + v2[x] * v2[x])
        ok = length > 0.0
        v0[x] = v0[x] / length if ok else 0.0
        v1[x] = v1[x] / length if ok else 0.0
        v2[x] = v2[x] / length if ok else 0.0
    _unit_rows(v0, v1, v2)
    h0, h1, h2 = scr[6, x0:x1], scr[7, x0:x1], scr[8, x0:x1]
    for i in range(light_kind.shape[0]):
        if light_kind[i] != LIGHT_DIRECTIONAL:
            continue
        lx = unit_l[i, 0]
        ly = unit_l[i, 1]
        lz = unit_l[i, 2]
        for x in range(n):  # Blinn-Phong: H = unit(L + V)
            h0[x] = lx + v0[x]
            h1[x] = ly + v1[x]
            h2[x] = lz + v2[x]
        _unit_rows(h0, h1, h2)
        b_i = scr[9 + i, x0:x1]
        for x in range(n):  # base = N . H, clipped
            b = (un0[x] * h0[x] + un1[x] * h1[x]) + un2[x] * h2[x]
            b_i[x] = min(max(b, 0.0), 1.0)


@specialised
def shade_object_for(show, bump):
    """:func:`shade_object` for one output ``show`` (SHOW_*) and ``bump`` (the normal map's
    DOT3 lighting, sec. 5.2): numba prunes the other outputs' branches and the tangent frame
    before typing them, so a frame compiles only the code it uses
    (:func:`refnpr._jit.specialised`). The smaller options (per-level thresholds, tone LUTs,
    the indication map, anisotropy) stay run-time arguments: as modes they saved no measurable
    compile time and would multiply the kernels a test suite compiles (21 combinations)."""

    @banded("mesh_id")
    def shade_object(
        lo,
        hi,
        obj,
        mesh_id,
        mask,
        normal,
        uv,
        duv_dx,
        duv_dy,
        position,
        dp_dx,
        dp_dy,
        scale,
        direction,
        engraving,
        texels,
        offsets,
        shapes,
        ntexels,
        noffsets,
        nshapes,
        luts,
        lut_x,
        equalize,
        per_level,
        imap,
        use_imap,
        iscale,
        ambient,
        m_diffuse,
        m_specular,
        shininess,
        specular,
        light_kind,
        light_vec,
        light_color,
        eye,
        anisotropy,
        lod_offset,
        mode,
        c,
        top,
        ink,
        paper,
        out,
        raw,
    ):
        """Shade the samples of object ``obj`` (``mesh_id == obj``) into ``out`` or ``raw``.

        Grid channels (nH, nW[, k]), any float dtype: normal, uv, duv_dx, duv_dy, position (specular
        or point lights), dp_dx, dp_dy (``bump``); mesh_id int, mask bool (covered). scale (2,):
        uv_scale; direction (2,): the engraving direction (``engraving``: coordinates (uv . d, 1/2)).
        texels, offsets, shapes: the packed screen pyramid; ntexels, noffsets, nshapes: the packed
        RGB normal map (``bump`` or show normals). luts (L, B), lut_x (B,): tone LUTs (``equalize``);
        ``per_level``: threshold the two level samples separately. imap (r, c), iscale (2,):
        indication map (``use_imap``). ambient (3,): m_a l_a; m_diffuse, m_specular (3,);
        shininess; light_kind (L,), light_vec (L, 3): unit direction or position, light_color
        (L, 3); eye (3,). anisotropy: 1 isotropic, N > 1 up to N probes; lod_offset added to the
        LOD. mode: THRESHOLD_*; c, top: the smooth ramp's slope and 1 (or 1/2, centred). show:
        SHOW_*. ink, paper (3,). out (nH, nW, 4) float32: RGBA written where mesh_id == obj
        (SHOW_COLOR); raw (nH, nW, 3) float64: the raw value or normal-map RGB otherwise.
        """
        nw = mesh_id.shape[1]
        # channel indices as int64 values, not literals: the samplers compile once, not once per
        # literal channel (four specialisations each; cold start, issue 11)
        ch0 = np.int64(0)
        ch1 = np.int64(1)
        ch2 = np.int64(2)
        n_lights = light_kind.shape[0]
        cols = np.float64(shapes[0, 1])
        rows = np.float64(shapes[0, 0])
        unit_l = np.zeros((n_lights, 3))  # unit_vectors(L) of a directional light: per frame
        for i in range(n_lights):
            unit_l[i, 0], unit_l[i, 1], unit_l[i, 2] = _unit(
                light_vec[i, 0], light_vec[i, 1], light_vec[i, 2]
            )
        lit = show == SHOW_COLOR or show == SHOW_INTENSITY
        nrm = normal.reshape(normal.shape[0], nw * 3)
        pos = position.reshape(position.shape[0], position.shape[1] * 3)
        scr = np.zeros((9 + n_lights, nw))  # _row_units' scratch: un, v, h, base per light
        for y in range(lo, hi):
            x0 = 0  # the row's span of the object's samples
            while x0 < nw and mesh_id[y, x0] != obj:
                x0 += 1
            x1 = nw
            while x1 > x0 and mesh_id[y, x1 - 1] != obj:
                x1 -= 1
            if x0 == x1:
                continue
            if lit:
                _row_units(
                    nrm[y, 3 * x0 : 3 * x1],
                    pos[y, 3 * x0 : 3 * x1] if specular else pos[0, :0],
                    eye,
                    specular,
                    light_kind,
                    unit_l,
                    scr,
                    x0,
                    x1,
                )
            for x in range(x0, x1):
                if mesh_id[y, x] != obj:
                    continue
                if show == SHOW_COLOR and not mask[y, x]:
                    out[y, x, 0] = 0.0
                    out[y, x, 1] = 0.0
                    out[y, x, 2] = 0.0
                    out[y, x, 3] = 0.0
                    continue
                u0 = np.float64(uv[y, x, 0])
                v0 = np.float64(uv[y, x, 1])
                su = u0 * scale[0]
                sv = v0 * scale[1]
                dxu = np.float64(duv_dx[y, x, 0])
                dxv = np.float64(duv_dx[y, x, 1])
                dyu = np.float64(duv_dy[y, x, 0])
                dyv = np.float64(duv_dy[y, x, 1])
                sdxu = dxu * scale[0]
                sdxv = dxv * scale[1]
                sdyu = dyu * scale[0]
                sdyv = dyv * scale[1]
                if engraving:  # sec. 4.1: t = uv . direction, along a 1D ramp
                    cu = su * direction[0] + sv * direction[1]
                    cv = 0.5
                    cdxu = sdxu * direction[0] + sdxv * direction[1]
                    cdxv = 0.0
                    cdyu = sdyu * direction[0] + sdyv * direction[1]
                    cdyv = 0.0
                else:
                    cu = su
                    cv = sv
                    cdxu = sdxu
                    cdxv = sdxv
                    cdyu = sdyu
                    cdyv = sdyv
                # LOD (GL 4.6 sec. 8.14) and anisotropic footprint (screens.screen_footprint)
                ax = cdxu * cols
                ay = cdxv * rows
                px = math.sqrt(ax * ax + ay * ay)
                bx = cdyu * cols
                by = cdyv * rows
                py = math.sqrt(bx * bx + by * by)
                p_max = max(px, py)
                probes = 0  # 0: isotropic (no footprint)
                axu = 0.0
                axv = 0.0
                if anisotropy == 1:
                    lod = math.log2(max(p_max, 1e-30))
                else:
                    p_min = min(px, py)
                    ratio = p_max / max(p_min, 1e-30)
                    probes = np.int64(min(max(math.ceil(ratio - 1e-9), 1.0), float(anisotropy)))
                    lod = math.log2(max(p_max / probes, 1e-30))
                    if px >= py:
                        axu = cdxu
                        axv = cdxv
                    else:
                        axu = cdyu
                        axv = cdyv
                lod = lod + lod_offset
                if show == SHOW_SCREEN:
                    s = _filtered(texels, offsets, shapes, cu, cv, lod, probes, axu, axv, ch0)
                    raw[y, x, 0] = s
                    raw[y, x, 1] = s
                    raw[y, x, 2] = s
                    continue
                if show == SHOW_NORMALS:
                    for k in range(3):
                        if bump:
                            raw[y, x, k] = _filtered(
                                ntexels, noffsets, nshapes, cu, cv, lod, probes, axu, axv, k
                            )
                        else:
                            raw[y, x, k] = 0.5 if k < 2 else 1.0
                    continue
                # target intensity: Veryovka eq. 1 as luminance, DOT3 stroke lighting (sec. 5.2)
                nx = np.float64(normal[y, x, 0])
                ny = np.float64(normal[y, x, 1])
                nz = np.float64(normal[y, x, 2])
                unx = scr[0, x]  # _unit(N), from _row_units
                uny = scr[1, x]
                unz = scr[2, x]
                valid = False
                tx = ty = tz = 0.0
                btx = bty = btz = 0.0
                mx = my = mz = 0.0
                if bump:  # shading.tangent_frame with the unscaled uv derivatives
                    det = dxu * dyv - dyu * dxv
                    ok = abs(det) > 1e-20
                    inv = 1.0 / det if ok else 0.0
                    qx0 = np.float64(dp_dx[y, x, 0])
                    qx1 = np.float64(dp_dx[y, x, 1])
                    qx2 = np.float64(dp_dx[y, x, 2])
                    qy0 = np.float64(dp_dy[y, x, 0])
                    qy1 = np.float64(dp_dy[y, x, 1])
                    qy2 = np.float64(dp_dy[y, x, 2])
                    pu0 = (qx0 * dyv - qy0 * dxv) * inv
                    pu1 = (qx1 * dyv - qy1 * dxv) * inv
                    pu2 = (qx2 * dyv - qy2 * dxv) * inv
                    pv0 = (qy0 * dxu - qx0 * dyu) * inv
                    pv1 = (qy1 * dxu - qx1 * dyu) * inv
                    pv2 = (qy2 * dxu - qx2 * dyu) * inv
                    d = (pu0 * nx + pu1 * ny) + pu2 * nz
                    tx = pu0 - d * nx
                    ty = pu1 - d * ny
                    tz = pu2 - d * nz
                    t_len = math.sqrt((tx * tx + ty * ty) + tz * tz)
                    if t_len > 1e-30:
                        tx = tx / t_len
                        ty = ty / t_len
                        tz = tz / t_len
                    else:
                        tx = ty = tz = 0.0
                    d1 = (pv0 * nx + pv1 * ny) + pv2 * nz
                    d2 = (pv0 * tx + pv1 * ty) + pv2 * tz
                    btx = (pv0 - d1 * nx) - d2 * tx
                    bty = (pv1 - d1 * ny) - d2 * ty
                    btz = (pv2 - d1 * nz) - d2 * tz
                    b_len = math.sqrt((btx * btx + bty * bty) + btz * btz)
                    if b_len > 1e-30:
                        btx = btx / b_len
                        bty = bty / b_len
                        btz = btz / b_len
                    else:
                        btx = bty = btz = 0.0
                    valid = ok and t_len > 1e-30 and b_len > 1e-30
                    if valid:
                        mx = _filtered(
                            ntexels, noffsets, nshapes, cu, cv, lod, probes, axu, axv, ch0
                        )
                        my = _filtered(
                            ntexels, noffsets, nshapes, cu, cv, lod, probes, axu, axv, ch1
                        )
                        mz = _filtered(
                            ntexels, noffsets, nshapes, cu, cv, lod, probes, axu, axv, ch2
                        )
                        mx, my, mz = _unit(2.0 * mx - 1.0, 2.0 * my - 1.0, 2.0 * mz - 1.0)
                vx = vy = vz = 0.0
                need_pos = specular
                for i in range(n_lights):
                    if light_kind[i] == LIGHT_POINT:
                        need_pos = True
                if need_pos:
                    ppx = np.float64(position[y, x, 0])
                    ppy = np.float64(position[y, x, 1])
                    ppz = np.float64(position[y, x, 2])
                else:
                    ppx = ppy = ppz = 0.0
                if specular:  # ShadeContext.view_dir, then unit_vectors: from _row_units
                    vx = scr[3, x]
                    vy = scr[4, x]
                    vz = scr[5, x]
                r = ambient[0]  # eq. 1: m_a l_a
                g = ambient[1]
                b = ambient[2]
                for i in range(n_lights):
                    lx = light_vec[i, 0]
                    ly = light_vec[i, 1]
                    lz = light_vec[i, 2]
                    if light_kind[i] == LIGHT_POINT:  # ShadeContext.light_dirs
                        lx = lx - ppx
                        ly = ly - ppy
                        lz = lz - ppz
                        length = math.sqrt((lx * lx + ly * ly) + lz * lz)
                        if length > 0.0:
                            lx = lx / length
                            ly = ly / length
                            lz = lz / length
                        else:
                            lx = ly = lz = 0.0
                        ulx, uly, ulz = _unit(lx, ly, lz)
                    else:
                        ulx = unit_l[i, 0]
                        uly = unit_l[i, 1]
                        ulz = unit_l[i, 2]
                    n_dot_l = (unx * ulx + uny * uly) + unz * ulz
                    f_d = max(n_dot_l, 0.0)  # eq. 1: f_d = max(N.L, 0)
                    f_d = min(f_d, 1.0)
                    if valid:  # sec. 5.2: clip(N_map . L_t, 0, 1), L_t = (L.T, L.B, L.N)
                        ltx = (lx * tx + ly * ty) + lz * tz
                        lty = (lx * btx + ly * bty) + lz * btz
                        ltz = (lx * nx + ly * ny) + lz * nz
                        ltx, lty, ltz = _unit(ltx, lty, ltz)
                        f_d = min(max((mx * ltx + my * lty) + mz * ltz, 0.0), 1.0)
                    r = r + m_diffuse[0] * f_d * light_color[i, 0]  # eq. 1: diffuse sum
                    g = g + m_diffuse[1] * f_d * light_color[i, 1]
                    b = b + m_diffuse[2] * f_d * light_color[i, 2]
                    if specular:
                        f_s = 0.0
                        if shininess > 0.0:  # Blinn-Phong: H = unit(L + V), base = N.H
                            if light_kind[i] == LIGHT_DIRECTIONAL:
                                base = scr[9 + i, x]  # from _row_units
                            else:
                                hx, hy, hz = _unit(ulx + vx, uly + vy, ulz + vz)
                                base = (unx * hx + uny * hy) + unz * hz
                                base = min(max(base, 0.0), 1.0)
                            f_s = base**shininess if n_dot_l > 0.0 else 0.0  # eq. 1: f_s
                        r = r + m_specular[0] * f_s * light_color[i, 0]  # eq. 1: specular sum
                        g = g + m_specular[1] * f_s * light_color[i, 1]
                        b = b + m_specular[2] * f_s * light_color[i, 2]
                inten = (r * LUMA_R + g * LUMA_G) + b * LUMA_B
                inten = min(max(inten, 0.0), 1.0)
                if use_imap:  # sec. 5.1: clip(I + indication, 0, 1)
                    icols = imap.shape[1]
                    irows = imap.shape[0]
                    fxi = min(max((u0 * iscale[0]) * icols - 0.5, 0.0), icols - 1.0)
                    fyi = min(max((v0 * iscale[1]) * irows - 0.5, 0.0), irows - 1.0)
                    x0 = min(np.int64(math.floor(fxi)), icols - 1)
                    y0 = min(np.int64(math.floor(fyi)), irows - 1)
                    x1 = min(x0 + 1, icols - 1)
                    y1 = min(y0 + 1, irows - 1)
                    wx = fxi - x0
                    wy = fyi - y0
                    top_i = imap[y0, x0] * (1.0 - wx) + imap[y0, x1] * wx
                    bot_i = imap[y1, x0] * (1.0 - wx) + imap[y1, x1] * wx
                    ind = top_i * (1.0 - wy) + bot_i * wy
                    inten = min(max(inten + ind, 0.0), 1.0)
                if show == SHOW_INTENSITY:
                    raw[y, x, 0] = inten
                    raw[y, x, 1] = inten
                    raw[y, x, 2] = inten
                    continue
                if not per_level:  # sec. 3: threshold the screen sampled at (uv, LOD)
                    # _filtered(texels, ..., ch0) written out (the hot lookup; see _taps)
                    n_lv = offsets.shape[0]
                    lam = min(max(lod, 0.0), n_lv - 1.0)
                    k0 = np.int64(math.floor(lam))
                    k1 = min(k0 + 1, n_lv - 1)
                    f = lam - k0
                    acc = 0.0
                    for j in range(max(probes, 1)):
                        su_ = cu
                        sv_ = cv
                        if probes > 0:
                            t = (j + 0.5) / probes - 0.5
                            su_ = cu + axu * t
                            sv_ = cv + axv * t
                        r = 0.0
                        for q in range(2 if f > 0.0 else 1):
                            k = k0 if q == 0 else k1
                            w = 1.0 - f if q == 0 else f
                            i00, i10, i01, i11, w00, w10, w01, w11 = _taps(
                                offsets[k], shapes[k, 0], shapes[k, 1], su_, sv_
                            )
                            r = r + w * (
                                w00 * texels[i00, 0]
                                + w10 * texels[i10, 0]
                                + w01 * texels[i01, 0]
                                + w11 * texels[i11, 0]
                            )
                        acc = acc + r if probes > 0 else r
                    s = acc / probes if probes > 0 else acc
                    value = _threshold(s, inten, mode, c, top)
                else:  # level_weights, then a threshold per level blended with the weight
                    n_lv = offsets.shape[0]
                    lam = min(max(lod, 0.0), n_lv - 1.0)
                    k0 = np.int64(math.floor(lam))
                    k1 = min(k0 + 1, n_lv - 1)
                    w1 = lam - k0
                    s0 = _level_filtered(texels, offsets, shapes, k0, cu, cv, probes, axu, axv)
                    s1 = _level_filtered(texels, offsets, shapes, k1, cu, cv, probes, axu, axv)
                    if equalize:
                        s0 = _interp(s0, lut_x, luts[k0])
                        s1 = _interp(s1, lut_x, luts[k1])
                    t0 = _threshold(s0, inten, mode, c, top)
                    t1 = _threshold(s1, inten, mode, c, top)
                    value = (1.0 - w1) * t0 + w1 * t1
                rem = 1.0 - value
                out[y, x, 0] = min(max(value * paper[0] + rem * ink[0], 0.0), 1.0)
                out[y, x, 1] = min(max(value * paper[1] + rem * ink[1], 0.0), 1.0)
                out[y, x, 2] = min(max(value * paper[2] + rem * ink[2], 0.0), 1.0)
                out[y, x, 3] = 1.0

    return shade_object


@banded("mesh_id")
def prepare(lo, hi, mesh_id, mask, n_objects, rgb, rows, out):
    """One pass before the objects: ``out (nH, nW, 4)`` where ``mesh_id < 0`` gets (rgb, 1) if
    covered (``mask``), else 0; ``rows (nH, n_objects) int64`` counts each object's samples per
    grid row (which objects are in view)."""
    nh, nw = mesh_id.shape
    for y in range(lo, hi):
        for k in range(n_objects):
            rows[y, k] = 0
        for x in range(nw):
            i = mesh_id[y, x]
            if i >= 0:
                if i < n_objects:
                    rows[y, i] += 1
            elif mask[y, x]:
                out[y, x, 0] = rgb[0]
                out[y, x, 1] = rgb[1]
                out[y, x, 2] = rgb[2]
                out[y, x, 3] = 1.0
            else:
                out[y, x, 0] = 0.0
                out[y, x, 1] = 0.0
                out[y, x, 2] = 0.0
                out[y, x, 3] = 0.0

"""numba kernel of the ``threshold`` style's per-sample shading (private; records built and
validated by :mod:`refnpr.styles.threshold.shading`).

One pass over the samples, banded over the rows (no reductions across samples, so the result
does not depend on the thread count). Per covered sample: its thresholds, taken once for every
term (a constant, a row of the image table, the multi-scale lines of eqs. 5-8 composed for
cross-hatching, or the stipple dots of Fig. 4, at one or several footprint offsets); Veryovka
eq. 1's diffuse and specular terms (:mod:`refnpr.formulas.lighting`); each term thresholded
(T_n of eq. 4, the PCF average of sec. 4, or the analytic box filter of the lines), blended by
the strength of sec. 5 and summed as eq. 2; stored as float32 straight-alpha RGBA clipped to
[0, 1]. Every formula is the scalar device function of :mod:`refnpr.formulas.threshold`; this
module composes them.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from refnpr._jit import banded, njit, specialised
from refnpr.device.lights import LIGHT_POINT, light_dir
from refnpr.device.scalars import clip
from refnpr.device.vectors import dot, towards, unit_scaled
from refnpr.formulas import lighting
from refnpr.formulas import threshold as thr

from .params import PARAMS

_diffuse = lighting.diffuse.scalar
_specular = lighting.specular.scalar
_illumination_term = lighting.illumination_term.scalar
_step_n = thr.step_n.scalar
_pcf_threshold = thr.pcf_threshold.scalar
_hatch_coordinate = thr.hatch_coordinate.scalar
_dyadic_scale = thr.dyadic_scale_from_gradient.scalar
_line_threshold = thr.line_threshold.scalar
_combine_thresholds = thr.combine_thresholds.scalar
_layer_white = thr.layer_whites.scalar
_line_coverage = thr.line_coverage.scalar
_stipple_threshold = thr.stipple_threshold.scalar
_facing_strength = thr.facing_strength.scalar
_tone_strength = thr.tone_strength.scalar
_strength_blend = thr.strength_blend.scalar

#: Threshold sources of :func:`shade_threshold_for` (the analytic filter is a source of its
#: own: the lines' coverage replaces the thresholds).
CONSTANT, IMAGE, LINES, STIPPLE = PARAMS.codes("source", "constant", "image", "lines", "stipple")
ANALYTIC = len(PARAMS["source"].choices)


class Tables(NamedTuple):
    """The arrays of a frame's threshold shading beside the style record (M covered samples in
    row-major mask order, O objects, K thresholds per sample, D hatching directions).

    row_start : (nH,) int64, index of each row's first covered sample
    normals : (M, 3) float64 bump-mapped normals, or (0, 3): the G-buffer's
    t, w : (M, K) image thresholds and their weights ((1, 0): unweighted), or (1, 1) unused
    offsets : (K, 2) float64 footprint offsets in pixels of the procedural thresholds
    noise : (M,) float64 line phase noise in periods, or (0,): none
    uv_scale : (O, 2) float64 per object [su, sv]; log2_sv : (O,) log2(sv)
    sin, cos : (D,) float64 of the hatching angles; channel : (D,) bool, the direction reads
        eq. 5 from the G-buffer's dyadic_scale channel (minus log2_sv)
    lam, levels : (B,), (B, D) the layer schedule (``layer_schedule``)
    cdf : (n_t, n_t, n_y) the stipple tone table, or (0, 0, 0): none
    spec_on : (O,) bool, the object's specular term is added (m_s != 0, or lights not finite)
    """

    row_start: np.ndarray
    normals: np.ndarray
    t: np.ndarray
    w: np.ndarray
    offsets: np.ndarray
    noise: np.ndarray
    uv_scale: np.ndarray
    log2_sv: np.ndarray
    sin: np.ndarray
    cos: np.ndarray
    channel: np.ndarray
    lam: np.ndarray
    levels: np.ndarray
    cdf: np.ndarray
    spec_on: np.ndarray


@njit(inline="always")
def _analytic(x, n, layers, n_sub, uniform, noise, schedule):
    """Box-filtered T_n(x, F) of the hatching ``layers = (v, dv/dx, dv/dy, s)`` (D,) over the
    sample's footprint (the pixel's derivatives divided by ``n_sub``), sec. 4: eq. 4 with
    T(Frac(x n), F) replaced by the fraction of the footprint where every layer is white,
    taken as the product of the layers' coverages (``line_coverage``) at their white fractions
    (``layer_whites``). ``noise = (on, z)``: a phase shift z = Frac(noise) held over the
    footprint, Frac(F + z) <= w on {F <= w - z} and {1 - z <= F <= w + 1 - z}."""
    lv, ldx, ldy, ls = layers
    lam_bp, lev_bp = schedule
    on, z = noise
    n_dirs = lv.shape[0]
    xn = x * n
    base = np.floor(xn)
    r = xn - base  # eq. 4: T_n = (floor(x n) + T(Frac(x n), t)) / n
    cover = 1.0
    for d in range(n_dirs):
        w = _layer_white(r, lam_bp, lev_bp, d) if n_dirs > 1 else r
        gx = ldx[d] / n_sub
        gy = ldy[d] / n_sub
        if on:
            c = (
                _line_coverage(lv[d], ls[d], w - z, gx, gy, uniform)
                + _line_coverage(lv[d], ls[d], w + 1.0 - z, gx, gy, uniform)
                - _line_coverage(lv[d], ls[d], 1.0 - z, gx, gy, uniform)
            )
        else:
            c = _line_coverage(lv[d], ls[d], w, gx, gy, uniform)
        cover = cover * c  # white: F_i <= w_i(x) in every layer
    cover = 1.0 if r >= 1.0 else clip(cover, 0.0, 1.0)
    top = np.ceil(xn)
    lvl = base + cover
    return (lvl if lvl <= top else top) / n


@njit(inline="always")
def _stipple_at(u, v, dots, cdf):
    """The stipple threshold at (u, v); ``dots = (s_u, s_v, seed, jitter)``."""
    s_u, s_v, seed, jitter = dots
    return _stipple_threshold(u, v, s_u, s_v, seed, jitter, cdf)


@njit(inline="always")
def _uv_at(frame_uv, y, x, scale):
    """``(u, v)`` of a G-buffer sample times the object's ``scale = (su, sv)``."""
    return np.float64(frame_uv[y, x, 0]) * scale[0], np.float64(frame_uv[y, x, 1]) * scale[1]


@specialised
def shade_threshold_for(src, cross, filtered):
    """:func:`shade_threshold` for one threshold source ``src`` (CONSTANT, IMAGE, LINES,
    ANALYTIC, STIPPLE), ``cross`` (more than one hatching direction, composed by the layer
    schedule) and ``filtered`` (several or weighted thresholds per sample: the PCF average of
    sec. 4). numba prunes the other sources' branches, the layer composition of a single
    direction and the PCF sums of one threshold before typing them, so a frame compiles only
    what it uses (:func:`refnpr._jit.specialised`)."""
    lines = src == LINES or src == ANALYTIC

    @banded("out")
    def shade_threshold(lo, hi, frame, style, tables, out, kept):
        """Shade rows ``lo..hi - 1`` of ``out (nH, nW, 4)`` float32 (written in full; zero
        where empty) from the :class:`refnpr.styles._frame.Frame` ``frame``, the style record
        ``style`` (``PARAMS.Record``) and the :class:`Tables` ``tables``. ``kept (nH, nW, 2)``
        float64: each sample's tone (f_d of the first light) and threshold (the mean of its
        thresholds, weighted as the PCF weighs them; the analytic filter: the lines' threshold
        at the sample itself), 0 where empty; or a ``(0, 0, 2)`` stand-in where nobody reads
        them."""
        # the records' arrays as locals, taken once (read from a record inside the loops, each
        # access takes and drops a reference to the array)
        cover, mesh_id, normal, position = frame.cover, frame.mesh_id, frame.normal, frame.position
        uv, duv_dx, duv_dy, dyadic = frame.uv, frame.duv_dx, frame.duv_dy, frame.dyadic_scale
        eye = (frame.eye[0], frame.eye[1], frame.eye[2])
        m = frame.materials
        m_ambient, m_diffuse, m_specular, shininess = m.ambient, m.diffuse, m.specular, m.shininess
        lt = frame.lights
        light_kind, light_vec, light_unit, light_color = lt.kind, lt.vec, lt.unit, lt.color
        row_start, normals, t_tab, w_tab = tables.row_start, tables.normals, tables.t, tables.w
        offsets, noise_tab, uv_scale = tables.offsets, tables.noise, tables.uv_scale
        log2_sv = tables.log2_sv
        dir_sin, dir_cos, dir_channel = tables.sin, tables.cos, tables.channel
        schedule = (tables.lam, tables.levels)
        cdf, spec_on = tables.cdf, tables.spec_on
        steps, uniform, specular, spec_t = style.n, style.uniform, style.specular, style.spec_t
        fade, n_sub = style.facing_fade, style.n_sub
        nh, nw = cover.shape
        has_position = position.shape[0] == nh and position.shape[1] == nw  # else a stand-in
        points = False
        for i in range(light_kind.shape[0]):
            points = points or light_kind[i] == LIGHT_POINT
        n_lights = light_kind.shape[0]
        n_dirs = dir_sin.shape[0]
        has_noise = noise_tab.shape[0] > 0
        has_w = src == IMAGE and w_tab.shape[1] > 0
        if src == IMAGE:
            kk = t_tab.shape[1]
        elif src == LINES or src == STIPPLE:
            kk = max(offsets.shape[0], 1)
        else:
            kk = 1
        tk = np.empty(kk)  # the sample's thresholds, and their weights
        wk = np.empty(kk if has_w else 0)
        fk = np.empty((kk, n_dirs))  # per threshold, one value per hatching layer
        lv = np.empty(n_dirs)  # the layers: coordinate, its derivatives, eq. 5's scale
        ldx = np.empty(n_dirs)
        ldy = np.empty(n_dirs)
        ls = np.empty(n_dirs)
        layers = (lv, ldx, ldy, ls)
        keep = kept.shape[0] == nh
        for y in range(lo, hi):
            idx = row_start[y]
            for x in range(nw):
                if cover[y, x] < 0:
                    for c in range(4):
                        out[y, x, c] = 0.0
                    if keep:
                        kept[y, x, 0] = 0.0
                        kept[y, x, 1] = 0.0
                    continue
                mi = max(mesh_id[y, x], 0)
                # ---- the sample's thresholds (taken once, used by every term)
                noise = (False, 0.0)
                if src == CONSTANT:
                    tk[0] = style.t
                elif src == IMAGE:
                    for j in range(kk):
                        tk[j] = t_tab[idx, j]
                    if has_w:
                        for j in range(kk):
                            wk[j] = w_tab[idx, j]
                elif src == STIPPLE:
                    scale = (uv_scale[mi, 0], uv_scale[mi, 1])
                    u0, v0 = _uv_at(uv, y, x, scale)
                    gxu, gxv = _uv_at(duv_dx, y, x, scale)
                    gyu, gyv = _uv_at(duv_dy, y, x, scale)
                    s_u = _dyadic_scale(gxu, gyu, style.log2_w)  # eq. 5 per texture axis
                    s_v = _dyadic_scale(gxv, gyv, style.log2_w)
                    if not style.multiscale:
                        s_u = np.floor(s_u)
                        s_v = np.floor(s_v)
                    dots = (s_u, s_v, style.seed, style.jitter)
                    if offsets.shape[0] == 0:  # one threshold at uv itself
                        tk[0] = _stipple_at(u0, v0, dots, cdf)
                    for j in range(offsets.shape[0]):  # pcf: over the footprint
                        uj = u0 + offsets[j, 0] * gxu + offsets[j, 1] * gyu
                        vj = v0 + offsets[j, 0] * gxv + offsets[j, 1] * gyv
                        tk[j] = _stipple_at(uj, vj, dots, cdf)
                elif lines:
                    scale = (uv_scale[mi, 0], uv_scale[mi, 1])
                    u0, v0 = _uv_at(uv, y, x, scale)
                    gxu = gxv = gyu = gyv = 0.0
                    if style.has_grad:
                        gxu, gxv = _uv_at(duv_dx, y, x, scale)
                        gyu, gyv = _uv_at(duv_dy, y, x, scale)
                    nz = noise_tab[idx] if has_noise else 0.0
                    if src == ANALYTIC:  # the phase shift, held over the footprint
                        noise = (has_noise, nz - np.floor(nz))
                    for d in range(n_dirs):
                        sa = dir_sin[d]
                        ca = dir_cos[d]
                        v = _hatch_coordinate(u0, v0, sa, ca)
                        dvx = _hatch_coordinate(gxu, gxv, sa, ca)
                        dvy = _hatch_coordinate(gyu, gyv, sa, ca)
                        if dir_channel[d]:
                            s = np.float64(dyadic[y, x]) - log2_sv[mi]  # eq. 5 (G-buffer)
                        else:
                            s = _dyadic_scale(dvx, dvy, style.log2_w)  # eq. 5
                        s = s if style.multiscale else np.floor(s)  # else eq. 6 alone
                        if src == ANALYTIC:  # the layers, box-filtered per term
                            lv[d] = v
                            ldx[d] = dvx
                            ldy[d] = dvy
                            ls[d] = s
                        else:
                            for j in range(kk):
                                vj = v + offsets[j, 0] * dvx + offsets[j, 1] * dvy
                                f = _line_threshold(vj, s, uniform, nz)  # eqs. 6-8
                                if cross:
                                    fk[j, d] = f
                                else:
                                    tk[j] = f
                    if src == LINES and cross:  # the union of the layers' dark lines
                        for j in range(kk):
                            tk[j] = _combine_thresholds(fk[j], schedule[0], schedule[1])
                    if src == ANALYTIC and keep:  # the lines' threshold at the sample
                        for d in range(n_dirs):
                            fk[0, d] = _line_threshold(lv[d], ls[d], uniform, nz)
                        tk[0] = fk[0, 0]
                        if cross:
                            tk[0] = _combine_thresholds(fk[0], schedule[0], schedule[1])
                if keep:  # the sample's threshold: its thresholds' (weighted) mean
                    t_sum = 0.0
                    w_sum = 0.0
                    for j in range(kk if src != ANALYTIC else 1):
                        wj = wk[j] if has_w else 1.0
                        t_sum += wj * tk[j]
                        w_sum += wj
                    kept[y, x, 1] = t_sum / w_sum if w_sum > 0.0 else tk[0]
                    kept[y, x, 0] = 0.0  # the first light's f_d, below
                # ---- eq. 1's vectors
                if normals.shape[0] > 0:
                    n = (normals[idx, 0], normals[idx, 1], normals[idx, 2])
                else:
                    n = (
                        np.float64(normal[y, x, 0]),
                        np.float64(normal[y, x, 1]),
                        np.float64(normal[y, x, 2]),
                    )
                un = unit_scaled(n)  # f_d's N
                p = (0.0, 0.0, 0.0)
                v = (0.0, 0.0, 0.0)
                spec = specular and spec_on[mi]
                if has_position and (spec or fade > 0.0 or points):
                    p = (
                        np.float64(position[y, x, 0]),
                        np.float64(position[y, x, 1]),
                        np.float64(position[y, x, 2]),
                    )
                if spec or fade > 0.0:
                    v = towards(eye, p)  # V
                st0 = style.strength * 1.0
                if fade > 0.0:  # sec. 5: orientation
                    st0 = style.strength * _facing_strength(dot(n, v), fade, style.facing_power)
                r = m_ambient[mi, 0]  # eq. 2: m_a l_a kept
                g = m_ambient[mi, 1]
                b = m_ambient[mi, 2]
                for i in range(n_lights):
                    point = light_kind[i] == LIGHT_POINT
                    vec = (light_vec[i, 0], light_vec[i, 1], light_vec[i, 2])
                    l = light_dir(point, vec, p)  # L
                    if point:
                        q = unit_scaled(l)  # f_d's L
                    else:
                        q = (light_unit[i, 0], light_unit[i, 1], light_unit[i, 2])
                    f_d = _diffuse(un, q, False)  # eq. 1: f_d = max(N.L, 0) of unit vectors
                    f_d = f_d if f_d <= 1.0 else 1.0  # (<= 1 up to rounding)
                    if keep and i == 0:
                        kept[y, x, 0] = f_d
                    if src == ANALYTIC:
                        tx = _analytic(f_d, steps, layers, n_sub, uniform, noise, schedule)
                    elif filtered:
                        tx = _pcf_threshold(f_d, tk, wk, steps)  # sec. 4
                    else:
                        tx = _step_n(f_d, tk[0], steps)  # eq. 4 (eq. 3 for n = 1)
                    st = st0 * _tone_strength(f_d, style.dark, style.bright)  # sec. 5
                    term = _strength_blend(f_d, tx, st)
                    r = _illumination_term(r, m_diffuse[mi, 0], term, light_color[i, 0])  # eq. 2
                    g = _illumination_term(g, m_diffuse[mi, 1], term, light_color[i, 1])
                    b = _illumination_term(b, m_diffuse[mi, 2], term, light_color[i, 2])
                    if not spec:
                        continue
                    f_s = 0.0
                    if shininess[mi] > 0.0:  # eq. 1: f_s, Blinn-Phong, N as given
                        f_s = _specular(n, l, v, shininess[mi], False, False)
                    if spec_t >= 0.0:
                        tx = _step_n(f_s, spec_t, steps)  # a constant threshold
                    elif src == ANALYTIC:
                        tx = _analytic(f_s, steps, layers, n_sub, uniform, noise, schedule)
                    elif filtered:
                        tx = _pcf_threshold(f_s, tk, wk, steps)
                    else:
                        tx = _step_n(f_s, tk[0], steps)
                    st = st0 * _tone_strength(f_s, style.dark, style.bright)
                    term = _strength_blend(f_s, tx, st)
                    r = _illumination_term(r, m_specular[mi, 0], term, light_color[i, 0])
                    g = _illumination_term(g, m_specular[mi, 1], term, light_color[i, 1])
                    b = _illumination_term(b, m_specular[mi, 2], term, light_color[i, 2])
                out[y, x, 0] = min(max(r, 0.0), 1.0)
                out[y, x, 1] = min(max(g, 0.0), 1.0)
                out[y, x, 2] = min(max(b, 0.0), 1.0)
                out[y, x, 3] = 1.0
                idx += 1

    return shade_threshold

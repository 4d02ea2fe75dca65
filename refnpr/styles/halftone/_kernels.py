"""numba kernels of the ``halftone`` style (private; inputs built and validated by
:mod:`.shading`).

One banded pass over the samples of one object (no reductions, so the result does not depend on
the thread count): the target intensity (Veryovka eq. 1 as luminance, the DOT3 stroke lighting of
sec. 5.2, the indication map of sec. 5.1), the screen lookup at the sample's uv and LOD (sec. 3),
the binary (sec. 3.1) or smooth (sec. 3.2) threshold, per level with tone LUTs or not, and
ink/paper compositing into float32 straight-alpha RGBA.

Speed: the lighting of a row's samples of the object is computed first, in passes over rows
of scratch (the samples packed), one loop per light (:func:`lit_row`), which LLVM vectorizes:
the normalizations' divisions and roots are most of a sample's work. Then each sample sums the
lights' terms, looks the screen up and thresholds. The lighting formulas are inline copies
(:func:`refnpr._jit.inline_copy`) of the formulas themselves: called, they would not
vectorize. The hot screen lookup (:func:`screen_value`) sums :func:`~refnpr.device.sampling
.bilinear` samples as :func:`~refnpr.device.sampling.probes` does, with the pyramid's arrays as
the kernel's locals: ``probes`` takes the packed pyramid, whose texels it takes and drops a
reference to per sample (atomic operations that cost 5 % of a frame).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from refnpr._jit import banded, inline_copy, njit, specialised
from refnpr.device import vectors
from refnpr.device.lights import LIGHT_POINT, light_dir
from refnpr.device.sampling import bilinear, footprint, level_probes, level_weights, probes
from refnpr.device.scalars import clip01, interp
from refnpr.device.vectors import dot, towards
from refnpr.formulas import halftone, lighting

from .params import PARAMS

#: Small functions of numbers that the inline copies call (LLVM inlines them itself).
_SMALL = (vectors.dot, vectors.unit, vectors.unit_scaled, vectors.reflect, clip01)

_binary_threshold = halftone.binary_threshold.scalar
_smooth_threshold = halftone.smooth_threshold.scalar
_apply_indication = halftone.apply_indication.scalar
_sample_indication = halftone.sample_indication.scalar
_tangent_frame = halftone.tangent_frame.scalar
_stroke_lighting = inline_copy(halftone.stroke_lighting.scalar, _SMALL)
_diffuse = inline_copy(lighting.diffuse.scalar, _SMALL)
_specular = inline_copy(lighting.specular.scalar, _SMALL)
_term = lighting.illumination_term.scalar
_luminance = lighting.luminance.scalar
_light_dir = inline_copy(light_dir, _SMALL)
_towards = inline_copy(towards, _SMALL)
_bilinear = inline_copy(bilinear)

#: Codes of the style record (the declaration's choices).
BINARY = PARAMS.code("threshold", "binary")
SHOW_COLOR, SHOW_SCREEN, SHOW_NORMALS, SHOW_INTENSITY = PARAMS.codes(
    "show", "color", "screen", "normals", "intensity"
)

#: Rows of a band's scratch (each (nW,) float64): a row's samples of the object, packed; then
#: f_d and f_s of each light (rows _F + 2 i, _F + 2 i + 1).
_N, _P, _VALID, _T, _B, _NM, _F = 0, 3, 6, 7, 10, 13, 16


class ObjectValues(NamedTuple):
    """The numbers of one object's shading.

    index : the object (``mesh_id``) the kernel shades
    scale : (su, sv), multiplies uv before the screen lookup
    engraving : whether the screen is a 1D engraving ramp along ``t = uv . direction`` (sec. 4.1)
    direction : (2,) the engraving direction
    anisotropy : largest anisotropic ratio (1: the isotropic LOD)
    indicated : whether the indication map applies (sec. 5.1)
    indication_scale : (2,) multiplies uv before the indication lookup
    per_level : threshold the two level samples separately
    equalize : map each level sample through its tone LUT first
    """

    index: int
    scale: tuple
    engraving: bool
    direction: tuple
    anisotropy: int
    indicated: bool
    indication_scale: tuple
    per_level: bool
    equalize: bool


class Tables(NamedTuple):
    """The tables of one object's shading (stand-ins where its modes do not read them).

    screen : the packed screen pyramid ``(texels (N, 1) float32, offsets, shapes)``
    normals : the packed RGB normal-map pyramid (``(N, 3)`` texels)
    luts : (L, B) float64 tone LUTs, one row per level; lut_x : (B,) their abscissae
    indication : (rows, cols) float64 indication map
    values : :class:`ObjectValues`
    """

    screen: tuple
    normals: tuple
    luts: np.ndarray
    lut_x: np.ndarray
    indication: np.ndarray
    values: ObjectValues


@njit(inline="always")
def screen_at(ov, lod_offset, uv, dx, dy, rows, cols):
    """Where the screen is read for a sample at ``uv`` with derivatives ``dx``, ``dy``: the
    screen coordinates of the scaled uv (themselves, or along the engraving direction ``(t,
    1/2)``, sec. 4.1), their derivatives, and the footprint's ``lod`` (plus ``lod_offset``),
    probe count and axis (:func:`refnpr.device.sampling.footprint`)."""
    s0, s1 = ov.scale
    coords = (uv[0] * s0, uv[1] * s1)
    cdx = (dx[0] * s0, dx[1] * s1)
    cdy = (dy[0] * s0, dy[1] * s1)
    if ov.engraving:
        d0, d1 = ov.direction
        coords = (coords[0] * d0 + coords[1] * d1, 0.5)
        cdx = (cdx[0] * d0 + cdx[1] * d1, 0.0)
        cdy = (cdy[0] * d0 + cdy[1] * d1, 0.0)
    lod, n, axis = footprint(cdx, cdy, rows, cols, ov.anisotropy)
    return coords, cdx, cdy, lod + lod_offset, n, axis


@njit
def threshold(binary, s, x, c, centred):
    """The output at screen value ``s`` and intensity ``x``: sec. 3.1 or sec. 3.2."""
    if binary:
        return _binary_threshold(s, x)
    return _smooth_threshold(s, x, c, centred)


@njit(inline="always")
def screen_value(texels, offsets, shapes, coords, lod, n, axis):
    """Channel 0 of :func:`refnpr.device.sampling.probes` of the packed pyramid ``(texels,
    offsets, shapes)`` at ``coords``, the same sums from its :func:`~refnpr.device.sampling
    .bilinear` samples, for the hot loop: the pyramid's arrays as the kernel's locals."""
    k0, k1, f = level_weights(offsets.shape[0], lod)
    acc = 0.0
    for j in range(max(n, 1)):
        u, v = coords
        if n > 0:  # probe j along the footprint's major axis
            t = (j + 0.5) / n - 0.5
            u = u + axis[0] * t
            v = v + axis[1] * t
        c = np.int64(0)
        r = 0.0 + (1.0 - f) * _bilinear(texels, offsets[k0], shapes[k0, 0], shapes[k0, 1], u, v, c)
        if f > 0.0:
            r = r + f * _bilinear(texels, offsets[k1], shapes[k1, 0], shapes[k1, 1], u, v, c)
        acc = acc + r
    return acc / n if n > 0 else acc


@njit
def fwidth_slope(pyr, coords, d, lod, n, axis):
    """``c = 1 / fwidth(screen)`` (``c = "auto"``): the central differences of the filtered
    screen over one sample step ``d = (dx, dy)`` (the screen derivatives times 1/n pixel),
    halved and summed over x and y."""
    fw = 0.0
    for du, dv in d:
        plus = probes(pyr, coords[0] + du, coords[1] + dv, lod, n, axis, np.int64(0))
        minus = probes(pyr, coords[0] - du, coords[1] - dv, lod, n, axis, np.int64(0))
        fw = fw + abs(plus - minus) / 2
    return 1.0 / max(fw, 1e-6)


# ---------------------------------------------------------------------- a row's lighting


@njit
def gather(grid, y, at, out, m):
    """``out = (o0, o1, o2)`` (scratch rows) ``[:m]`` = ``grid[y, at[:m], :]`` in float64."""
    o0, o1, o2 = out
    for i in range(m):
        x = at[i]
        o0[i] = np.float64(grid[y, x, 0])
        o1[i] = np.float64(grid[y, x, 1])
        o2[i] = np.float64(grid[y, x, 2])


@njit
def diffuse_row(light, geo, out, m):
    """``out[:m]`` = f_d of Veryovka eq. 1 for ``light = (point, vec)`` (a light's kind and
    row of ``Lights.vec``) at the first m samples of ``geo`` (the rows of the G-buffer normal
    and the position)."""
    point, lv = light
    n0, n1, n2, p0, p1, p2 = geo
    if point:
        for i in range(m):
            l = _light_dir(True, lv, (p0[i], p1[i], p2[i]))
            out[i] = _diffuse((n0[i], n1[i], n2[i]), l, True)  # eq. 1: max(N.L, 0)
    else:
        for i in range(m):
            out[i] = _diffuse((n0[i], n1[i], n2[i]), lv, True)


@njit
def stroke_row(light, geo, bump, out, m):
    """``out[i]`` = the DOT3 stroke lighting of sec. 5.2, ``clip(N_map . L_t, 0, 1)`` with
    ``L_t = (L.T, L.B, L.N)``, where sample i's tangent frame is valid (``bump = (valid, t,
    b, nm)``, rows), i < m."""
    point, lv = light
    n0, n1, n2, p0, p1, p2 = geo
    valid, t0, t1, t2, b0, b1, b2, m0, m1, m2 = bump
    for i in range(m):
        if valid[i] > 0.0:
            n = (n0[i], n1[i], n2[i])
            l = _light_dir(point, lv, (p0[i], p1[i], p2[i]))
            lt = (dot(l, (t0[i], t1[i], t2[i])), dot(l, (b0[i], b1[i], b2[i])), dot(l, n))
            out[i] = _stroke_lighting((m0[i], m1[i], m2[i]), lt, True, True)


@njit
def lit_row(light, shininess, geo, eye, f_d, f_s, m):
    """``f_d[:m]`` and ``f_s[:m]``: f_d and f_s (Blinn-Phong) of Veryovka eq. 1 for ``light =
    (point, vec)`` with V towards ``eye``. One loop, so that the two terms share their
    normalizations."""
    point, lv = light
    n0, n1, n2, p0, p1, p2 = geo
    if point:
        for i in range(m):
            n = (n0[i], n1[i], n2[i])
            p = (p0[i], p1[i], p2[i])
            l = _light_dir(True, lv, p)
            f_d[i] = _diffuse(n, l, True)  # eq. 1: max(N.L, 0)
            f_s[i] = _specular(n, l, _towards(eye, p), shininess, False, True)
    else:
        for i in range(m):
            n = (n0[i], n1[i], n2[i])
            f_d[i] = _diffuse(n, lv, True)
            f_s[i] = _specular(n, lv, _towards(eye, (p0[i], p1[i], p2[i])), shininess, False, True)


@njit
def _row3(a, i):
    return (a[i, 0], a[i, 1], a[i, 2])


@njit
def _vec3(a, y, x):
    return np.float64(a[y, x, 0]), np.float64(a[y, x, 1]), np.float64(a[y, x, 2])


@njit
def _vec2(a, y, x):
    return np.float64(a[y, x, 0]), np.float64(a[y, x, 1])


@specialised
def shade_object_for(show, bump, fwidth, per_level):
    """:func:`shade_object` for one output ``show`` (the record's code), ``bump`` (the screen
    has a normal map: the DOT3 lighting of sec. 5.2), ``fwidth`` (``c = "auto"``: the smooth
    ramp's slope from the screen's change across the sample) and ``per_level`` (a threshold
    per mip level, with tone LUTs): numba prunes the other modes' branches before typing them,
    so a frame compiles only the code it uses (:func:`refnpr._jit.specialised`; the sampling
    and LUT functions those branches call are not compiled either). The smaller options (the
    indication map, anisotropy) are run-time values."""

    @banded(lambda frame, style, tables, out, raw: frame.mesh_id.shape[0])
    def shade_object(lo, hi, frame, style, tables, out, raw):
        """Shade the samples of object ``tables.values.index`` into ``out (nH, nW, 4)``
        float32 (``show`` color: RGBA, zero where not covered) or ``raw (nH, nW, 3)`` float64
        (the raw value, or the normal map's RGB). With ``show`` color, a full-size ``raw``
        also gets each sample's intensity (channel 0) and trilinear screen value (channel 1),
        the values ``show`` intensity and screen draw; a (0, 0, 3) stand-in gets nothing."""
        # the records' arrays as locals, taken once (reading them from a record inside the
        # loops takes and drops a reference to each array per sample)
        mesh_id, cover, normal, position = frame.mesh_id, frame.cover, frame.normal, frame.position
        uv, duv_dx, duv_dy = frame.uv, frame.duv_dx, frame.duv_dy
        dp_dx, dp_dy = frame.dposition_dx, frame.dposition_dy
        eye = (frame.eye[0], frame.eye[1], frame.eye[2])
        kind, light_vec, light_color = frame.lights.kind, frame.lights.vec, frame.lights.color
        materials = frame.materials
        pyr, npyr, luts, lut_x, imap, ov = tables
        texels, offsets, shapes = pyr
        obj = ov.index
        ambient = _row3(materials.ambient, obj)  # eq. 1: m_a l_a
        m_d = _row3(materials.diffuse, obj)
        m_s = _row3(materials.specular, obj)
        shininess = materials.shininess[obj]
        n_levels = pyr[1].shape[0]
        rows = np.float64(pyr[2][0, 0])
        cols = np.float64(pyr[2][0, 1])
        binary = style.threshold == BINARY
        specular = style.specular
        centred = style.centred or fwidth
        ink = style.ink_rgb
        paper = style.paper_rgb
        need_pos = specular
        for i in range(kind.shape[0]):
            if kind[i] == LIGHT_POINT:
                need_pos = True
        lit = show == SHOW_COLOR or show == SHOW_INTENSITY
        keep = show == SHOW_COLOR and raw.shape[0] == mesh_id.shape[0]  # the intermediates
        nw = mesh_id.shape[1]
        scr = np.empty((_F + 2 * kind.shape[0], nw))  # each row written before it is read
        at = np.empty(nw, dtype=np.int64)  # the packed samples' columns
        nr = (scr[_N], scr[_N + 1], scr[_N + 2])
        pr = (scr[_P], scr[_P + 1], scr[_P + 2])
        tr = (scr[_T], scr[_T + 1], scr[_T + 2])
        br = (scr[_B], scr[_B + 1], scr[_B + 2])
        mr = (scr[_NM], scr[_NM + 1], scr[_NM + 2])
        valid_r = scr[_VALID]
        if not need_pos:  # no point light, no specular term: positions are not read
            for k in range(3):
                pr[k][:] = 0.0
        geo = (nr[0], nr[1], nr[2], pr[0], pr[1], pr[2])
        bumps = (valid_r, tr[0], tr[1], tr[2], br[0], br[1], br[2], mr[0], mr[1], mr[2])
        for y in range(lo, hi):
            x0 = 0  # the row's span of the object's samples
            while x0 < nw and mesh_id[y, x0] != obj:
                x0 += 1
            x1 = nw
            while x1 > x0 and mesh_id[y, x1 - 1] != obj:
                x1 -= 1
            if x0 == x1:
                continue
            m = np.int64(0)  # the object's samples of the span, packed into the scratch rows
            if lit:  # their target intensity
                for x in range(x0, x1):
                    if mesh_id[y, x] == obj:
                        at[m] = x
                        m += 1
                gather(normal, y, at, nr, m)
                if need_pos:
                    gather(position, y, at, pr, m)
                if bump:  # the tangent frame of the unscaled uv, the normal map (sec. 5.2)
                    for i in range(m):
                        x = at[i]
                        valid_r[i] = 0.0
                        dx = _vec2(duv_dx, y, x)
                        dy = _vec2(duv_dy, y, x)
                        nrm = (nr[0][i], nr[1][i], nr[2][i])
                        dpx = _vec3(dp_dx, y, x)
                        t, bt, valid = _tangent_frame(nrm, dpx, _vec3(dp_dy, y, x), dx, dy)
                        if not valid:
                            continue
                        coords, _, _, lod, n, axis = screen_at(
                            ov, style.lod_offset, _vec2(uv, y, x), dx, dy, rows, cols
                        )
                        valid_r[i] = 1.0
                        for k in range(3):
                            tr[k][i] = t[k]
                            br[k][i] = bt[k]
                            mr[k][i] = probes(npyr, coords[0], coords[1], lod, n, axis, k)
                shiny = specular and shininess > 0.0
                for i in range(kind.shape[0]):  # f_d and f_s of each light (eq. 1)
                    light = (kind[i] == LIGHT_POINT, _row3(light_vec, i))
                    fd = scr[_F + 2 * i]
                    fs = scr[_F + 2 * i + 1]
                    if shiny:
                        lit_row(light, shininess, geo, eye, fd, fs, m)
                    else:
                        diffuse_row(light, geo, fd, m)
                        fs[:m] = 0.0  # f_s of a material whose shininess is not > 0
                    if bump:
                        stroke_row(light, geo, bumps, fd, m)
            i = -1  # the sample's place in the packed rows
            for x in range(x0, x1):
                if mesh_id[y, x] != obj:
                    continue
                i += 1
                if show == SHOW_COLOR and cover[y, x] < 0:
                    for ch in range(4):
                        out[y, x, ch] = 0.0
                    continue
                u, v = _vec2(uv, y, x)
                dx = _vec2(duv_dx, y, x)
                dy = _vec2(duv_dy, y, x)
                coords, cdx, cdy, lod, n, axis = screen_at(
                    ov, style.lod_offset, (u, v), dx, dy, rows, cols
                )
                cu, cv = coords
                if show == SHOW_SCREEN:
                    s = probes(pyr, cu, cv, lod, n, axis, np.int64(0))
                    for ch in range(3):
                        raw[y, x, ch] = s
                    continue
                if show == SHOW_NORMALS:
                    for ch in range(3):
                        if bump:
                            raw[y, x, ch] = probes(npyr, cu, cv, lod, n, axis, np.int64(ch))
                        else:
                            raw[y, x, ch] = 0.5 if ch < 2 else 1.0
                    continue
                # the target intensity: Veryovka eq. 1 as Rec. 709 luminance, clipped
                r, g, b = ambient  # eq. 1: m_a l_a
                for k in range(kind.shape[0]):  # each light's diffuse, then specular term
                    col = (light_color[k, 0], light_color[k, 1], light_color[k, 2])
                    f = scr[_F + 2 * k, i]
                    r = _term(r, m_d[0], f, col[0])
                    g = _term(g, m_d[1], f, col[1])
                    b = _term(b, m_d[2], f, col[2])
                    if specular:
                        f = scr[_F + 2 * k + 1, i]
                        r = _term(r, m_s[0], f, col[0])
                        g = _term(g, m_s[1], f, col[1])
                        b = _term(b, m_s[2], f, col[2])
                inten = clip01(_luminance(r, g, b))
                if ov.indicated:  # sec. 5.1
                    s0, s1 = ov.indication_scale
                    inten = _apply_indication(inten, _sample_indication(imap, u * s0, v * s1))
                if show == SHOW_INTENSITY:
                    for ch in range(3):
                        raw[y, x, ch] = inten
                    continue
                if keep:
                    raw[y, x, 0] = inten
                    raw[y, x, 1] = probes(pyr, cu, cv, lod, n, axis, np.int64(0))
                c = style.slope
                if fwidth:
                    step = style.step
                    d = ((cdx[0] * step, cdx[1] * step), (cdy[0] * step, cdy[1] * step))
                    c = fwidth_slope(pyr, coords, d, lod, n, axis)
                if not per_level:  # sec. 3: threshold the screen sampled at (uv, LOD)
                    s = screen_value(texels, offsets, shapes, coords, lod, n, axis)
                    value = threshold(binary, s, inten, c, centred)
                else:  # a threshold per level, blended with the trilinear weight
                    k0, k1, w1 = level_weights(n_levels, lod)
                    s0 = level_probes(pyr, k0, cu, cv, n, axis)
                    s1 = level_probes(pyr, k1, cu, cv, n, axis)
                    if ov.equalize:  # the level's tone LUT
                        s0 = interp(s0, lut_x, luts[k0])
                        s1 = interp(s1, lut_x, luts[k1])
                    t0 = threshold(binary, s0, inten, c, centred)
                    t1 = threshold(binary, s1, inten, c, centred)
                    value = (1.0 - w1) * t0 + w1 * t1
                rem = 1.0 - value
                for ch in range(3):
                    out[y, x, ch] = clip01(value * paper[ch] + rem * ink[ch])
                out[y, x, 3] = 1.0

    return shade_object


@banded(lambda frame, rgb, rows, out: frame.mesh_id.shape[0])
def prepare(lo, hi, frame, rgb, rows, out):
    """One pass before the objects: ``out (nH, nW, 4)`` where ``mesh_id < 0`` gets (rgb, 1) if
    covered, else 0; ``rows (nH, n_objects) int64`` counts each object's samples per grid row
    (which objects are in view)."""
    mesh_id = frame.mesh_id
    cover = frame.cover
    n_objects = rows.shape[1]
    nw = mesh_id.shape[1]
    for y in range(lo, hi):
        for k in range(n_objects):
            rows[y, k] = 0
        for x in range(nw):
            i = mesh_id[y, x]
            if i >= 0:
                if i < n_objects:
                    rows[y, i] += 1
            elif cover[y, x] >= 0:
                for ch in range(3):
                    out[y, x, ch] = rgb[ch]
                out[y, x, 3] = 1.0
            else:
                for ch in range(4):
                    out[y, x, ch] = 0.0

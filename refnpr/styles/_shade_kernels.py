"""numba kernels of toon and smooth shading (private; inputs validated by ``_common.lit_rgba``).

One parallel pass over the sample rows (a row per task, no reductions, so the result does not
depend on the thread count): per covered sample, Veryovka eq. 1's ambient + diffuse + specular
sums (``smooth``), or their multi-tone steps of eqs. 2-4 and Lake et al.'s ramp (``toon``), in
float64 with the operations in the order of the numpy formulas in ``refnpr.formulas`` (dot
products summed x + y, then + z; Blinn-Phong's half vector through ``unit_vectors``' max-scaling),
stored as float32 straight-alpha RGBA clipped to [0, 1].

Each row first goes through branch-free passes over contiguous float64 scratch rows (V, L, N.L,
the specular base, T_n of the diffuse term: ``_row_terms``, ``_row_step_tones``) that LLVM
compiles to SIMD divisions, square roots and roundings; the per-sample loop then only selects
and sums. IEEE division and square root are correctly rounded in SIMD as in scalar code, so the
values are the same bits (tests/styles/test_shade_kernels.py checks the float64 arithmetic); on
the 1920x1080 teapot this took smooth shading from 55 to 37 ms and toon from 44 to 32-40 ms
(2 threads, ``benchmarks/README.md``).
"""

from __future__ import annotations

import math

import numpy as np

from refnpr._jit import banded, njit

#: ``mode`` codes of :func:`shade_lit`.
MODE_SMOOTH = 0
MODE_STEP = 1
MODE_LAKE = 2
#: ``light_kind`` codes.
LIGHT_DIRECTIONAL = 0
LIGHT_POINT = 1


@njit(inline="always")
def _step_n(x, t, n):
    """T_n(x, t) of Veryovka eq. 4 as ``threshold.step_n_kernel`` computes it (float64)."""
    xn = x * n
    whole = math.floor(xn)
    levels = whole + (1.0 if xn - whole >= t else 0.0)  # eq. 4: floor(x n) + T(Frac(x n), t)
    top = math.ceil(xn)
    return (levels if levels <= top else top) / n  # eq. 4, divided by n


@njit
def _row_terms(
    cover, y, nrm, pos, eye, light_kind, light_vec, specular, phong, v, lt, n_dot_l, base
):
    """N.L and the specular base of every light at samples ``x0..x1 - 1`` of row y, its covered
    span (``_covered_span``; nothing where the row is empty), returned as ``(x0, x1)``; in
    branch-free passes over contiguous rows (they compile to SIMD divisions and square roots:
    double division is what the per-sample loop waited on). The operations are the per-sample
    formulas', in their order, so every value has the same bits; uncovered samples inside the
    span get values nobody reads. The passes get views of the span and loop from 0: a loop from
    x0 (a signed start) compiled without SIMD.

    cover (nH, nW) int: covered where >= 0. nrm, pos (nH, nW * 3) float: normals, positions (pos unread unless ``specular`` or a point
    light); v, lt (3, nW) float64 scratch: V and the current light's L; n_dot_l, base (L, nW)
    float64, written: N.L, and max(R.V, 0) (``phong``) or max(N.H, 0) with H = unit_vectors(L +
    V) (where ``specular``). The passes take 1D row views (``_unit_towards_row``,
    ``_row_light``): LLVM vectorized only some of the same loops over 2D indexing (``v[0, x]``;
    6 of 9 divisions as ``vdivpd ymm``, all 9 now)."""
    x0, x1 = _covered_span(cover, y, cover.shape[1])
    if x0 == x1:
        return x0, x1
    nw = x1 - x0
    nrow = nrm[y, 3 * x0 : 3 * x1]
    prow = pos[y, 3 * x0 : 3 * x1] if pos.shape[0] > y else pos[0]
    v0, v1, v2 = v[0, x0:x1], v[1, x0:x1], v[2, x0:x1]
    l0, l1, l2 = lt[0, x0:x1], lt[1, x0:x1], lt[2, x0:x1]
    if specular:  # V: unit vector towards the eye (ShadeContext.view_dir)
        _unit_towards_row(eye[0], eye[1], eye[2], prow, nw, v0, v1, v2)
    for i in range(light_kind.shape[0]):
        point = light_kind[i] == LIGHT_POINT
        if point:  # ShadeContext.light_dirs
            _unit_towards_row(
                light_vec[i, 0], light_vec[i, 1], light_vec[i, 2], prow, nw, l0, l1, l2
            )
        _row_light(
            nw, nrow, point, light_vec[i, 0], light_vec[i, 1], light_vec[i, 2], specular, phong,
            v0, v1, v2, l0, l1, l2, n_dot_l[i, x0:x1], base[i, x0:x1],
        )  # fmt: skip
    return x0, x1


@njit
def _unit_towards_row(px, py, pz, prow, nw, ox, oy, oz):
    """``o[x] = unit(p - position[x])`` over one row (1D views: prow (nW * 3,), o* (nW,))."""
    for x in range(nw):
        ox[x] = px - np.float64(prow[3 * x])
        oy[x] = py - np.float64(prow[3 * x + 1])
        oz[x] = pz - np.float64(prow[3 * x + 2])
    for x in range(nw):
        length = math.sqrt(ox[x] * ox[x] + oy[x] * oy[x] + oz[x] * oz[x])
        ok = length > 0.0
        ox[x] = ox[x] / length if ok else 0.0
        oy[x] = oy[x] / length if ok else 0.0
        oz[x] = oz[x] / length if ok else 0.0


@njit
def _row_light(nw, nrow, point, cx, cy, cz, specular, phong, v0, v1, v2, l0, l1, l2, ndl, bs):
    """One light's N.L and specular base over one row, on 1D views (they vectorize)."""
    for x in range(nw):
        lx = l0[x] if point else cx
        ly = l1[x] if point else cy
        lz = l2[x] if point else cz
        ndl[x] = (
            np.float64(nrow[3 * x]) * lx
            + np.float64(nrow[3 * x + 1]) * ly
            + np.float64(nrow[3 * x + 2]) * lz
        )
    if not specular:
        return
    if phong:  # R = 2 (N.L) N - L; base = R.V
        for x in range(nw):
            lx = l0[x] if point else cx
            ly = l1[x] if point else cy
            lz = l2[x] if point else cz
            two = 2.0 * ndl[x]
            rx = two * np.float64(nrow[3 * x]) - lx
            ry = two * np.float64(nrow[3 * x + 1]) - ly
            rz = two * np.float64(nrow[3 * x + 2]) - lz
            b = rx * v0[x] + ry * v1[x] + rz * v2[x]
            bs[x] = b if b >= 0.0 else 0.0
        return
    for x in range(nw):  # H = unit_vectors(L + V), scaled by its largest component first
        hx = (l0[x] if point else cx) + v0[x]
        hy = (l1[x] if point else cy) + v1[x]
        hz = (l2[x] if point else cz) + v2[x]
        m = max(abs(hx), abs(hy), abs(hz))
        ok = m > 0.0
        l0[x] = hx / m if ok else hx  # l* is free once N.L is known: it holds H
        l1[x] = hy / m if ok else hy
        l2[x] = hz / m if ok else hz
    for x in range(nw):
        hx = l0[x]
        hy = l1[x]
        hz = l2[x]
        length = math.sqrt(hx * hx + hy * hy + hz * hz)
        ok = length > 0.0
        hx = hx / length if ok else hx
        hy = hy / length if ok else hy
        hz = hz / length if ok else hz
        b = (
            np.float64(nrow[3 * x]) * hx
            + np.float64(nrow[3 * x + 1]) * hy
            + np.float64(nrow[3 * x + 2]) * hz
        )
        bs[x] = b if b >= 0.0 else 0.0


@njit(inline="always")
def _covered_span(cover, y, nw):
    """``(x0, x1)``: row y's covered samples (``cover >= 0``) lie in ``[x0, x1)``; x0 == x1
    where the row has none. The row passes run over that span only (a fifth of the teapot
    scene's rows are empty)."""
    x0 = 0
    while x0 < nw and cover[y, x0] < 0:
        x0 += 1
    x1 = nw
    while x1 > x0 and cover[y, x1 - 1] < 0:
        x1 -= 1
    return x0, x1


@njit
def _row_step_tones(nw, n_dot_l, t, steps, tone):
    """``tone[x] = T_n(max(N.L, 0), t)`` (eq. 4 in eq. 2) for one light over ``nw`` samples of
    a row, in a pass that vectorizes (floor, ceil and the division by n as SIMD): n_dot_l, tone
    (nw,) float64 views."""
    for x in range(nw):
        n_dot_l_x = n_dot_l[x]
        f_d = n_dot_l_x if n_dot_l_x >= 0.0 else 0.0  # eq. 1: f_d = max(N.L, 0)
        tone[x] = _step_n(f_d, t, steps)


@njit(inline="always")
def _spec_term(nonzero, r, g, b):
    """Whether the specular term must be added to the colour sums ``(r, g, b)``.

    ``nonzero`` is False where, in every channel, the object's m_s or the light's colour is
    zero (no specular colour, as the teapot's floor): then the term m_s f_s l_i is a signed zero
    for any finite f_s (f_s <= base ** shininess with base <= 1 + 1e-6: finite below a
    shininess of ~1e9), and adding it changes no sum unless the sum is itself zero (-0 + +0 =
    +0), where it is added as the formula does. Skipping it gives the same bits.
    """
    return nonzero or r == 0.0 or g == 0.0 or b == 0.0


@banded("cover")
def shade_lit(
    lo,
    hi,
    cover,
    mesh_id,
    normal,
    position,
    m_ambient,
    m_diffuse,
    m_specular,
    shininess,
    spec_on,
    light_kind,
    light_vec,
    light_color,
    eye,
    mode,
    steps,
    t,
    ramp,
    specular,
    phong,
    edge_lo,
    edge_hi,
    tones,
    out,
):
    """Shade every sample of ``out (nH, nW, 4) float32`` (written in full; zero where empty).

    cover (nH, nW) int: a sample is covered where ``cover >= 0`` (tri_id, else mesh_id).
    mesh_id (nH, nW) int: object index (clamped to >= 0, as ``material_field`` does).
    normal (nH, nW, 3) float: unit normals; position (nH, nW, 3) float (any shape when neither
    ``specular`` nor a point light needs it). m_ambient (O, 3) float64: m_a * l_a per object;
    m_diffuse, m_specular (O, 3) float64; shininess (O,) float64; spec_on (O, L) bool: m_s and
    the light's colour both nonzero in some channel (else the term is skipped, ``_spec_term``).
    light_kind (L,) int64;
    light_vec (L, 3) float64: unit direction for directional lights, position for point
    lights; light_color (L, 3) float64; eye (3,) float64. mode: MODE_SMOOTH / MODE_STEP /
    MODE_LAKE; steps, t: eq. 4's n and t; ramp (K,) float64: Lake's texture (MODE_LAKE);
    specular: add the specular sum; phong: Phong instead of Blinn-Phong.

    edge_lo, edge_hi (O, B) float64, tones (B + 1,) float64 (MODE_STEP with ``specular``; else
    any shape, unused): T_n(f_s) without ``pow`` where the tone is certain. B breakpoints c_j of
    T_n in f_s (ascending), mapped to base = f_s ** (1 / shininess) and widened to
    [edge_lo, edge_hi] per object; a base in [edge_hi[j - 1], edge_lo[j]] has f_s strictly
    inside (c_{j - 1}, c_j), far (relative 1e-11 or more) from both, so T_n(f_s) = tones[j];
    elsewhere, or where tones[j] < 0, pow is evaluated as the formula does.
    """
    nh, nw = cover.shape
    n_lights = light_kind.shape[0]
    k_ramp = ramp.shape[0]
    n_edges = edge_lo.shape[1]
    nrm = normal.reshape(nh, nw * 3)
    pos = position.reshape(position.shape[0], position.shape[1] * 3)
    v = np.zeros((3, nw))
    lt = np.empty((3, nw))
    n_dot_ls = np.empty((n_lights, nw))
    bases = np.zeros((n_lights, nw))
    step_tones = np.empty((n_lights, nw))
    for y in range(lo, hi):
        x0, x1 = _row_terms(
            cover, y, nrm, pos, eye, light_kind, light_vec, specular, phong, v, lt, n_dot_ls, bases
        )
        if mode == MODE_STEP:
            for i in range(n_lights):
                _row_step_tones(x1 - x0, n_dot_ls[i, x0:x1], t, steps, step_tones[i, x0:x1])
        for x in range(nw):
            if cover[y, x] < 0:
                out[y, x, 0] = 0.0
                out[y, x, 1] = 0.0
                out[y, x, 2] = 0.0
                out[y, x, 3] = 0.0
                continue
            mi = max(mesh_id[y, x], 0)
            r = m_ambient[mi, 0]  # eq. 1: m_a l_a
            g = m_ambient[mi, 1]
            b = m_ambient[mi, 2]
            p = shininess[mi]
            for i in range(n_lights):
                n_dot_l = n_dot_ls[i, x]  # N.L, and the specular base, from _row_terms
                f_d = n_dot_l if n_dot_l >= 0.0 else 0.0  # eq. 1: f_d = max(N.L, 0)
                if mode == MODE_LAKE:  # Lake et al.: nearest texel of clip(N.L, 0, 1)
                    c = f_d if f_d <= 1.0 else 1.0
                    j = math.floor(c * k_ramp)
                    tone = ramp[int(j) if j < k_ramp - 1 else k_ramp - 1]
                elif mode == MODE_STEP:
                    tone = step_tones[i, x]  # eq. 4 in eq. 2, from _row_step_tones
                else:
                    tone = f_d
                r = r + m_diffuse[mi, 0] * tone * light_color[i, 0]
                g = g + m_diffuse[mi, 1] * tone * light_color[i, 1]
                b = b + m_diffuse[mi, 2] * tone * light_color[i, 2]
                if specular and p > 0.0 and _spec_term(spec_on[mi, i], r, g, b):
                    base = bases[i, x]  # max(R.V, 0) or max(N.H, 0)
                    if mode != MODE_STEP:
                        f_s = base**p if n_dot_l > 0.0 else 0.0  # eq. 1: f_s
                    elif n_dot_l > 0.0:
                        j = 0
                        while j < n_edges and base >= edge_hi[mi, j]:
                            j += 1
                        if (j < n_edges and base > edge_lo[mi, j]) or tones[j] < 0.0:
                            f_s = _step_n(base**p, t, steps)  # eq. 4 of eq. 1's f_s
                        else:
                            f_s = tones[j]  # the same: T_n is constant around base**p
                    else:
                        f_s = _step_n(0.0, t, steps)
                    r = r + m_specular[mi, 0] * f_s * light_color[i, 0]
                    g = g + m_specular[mi, 1] * f_s * light_color[i, 1]
                    b = b + m_specular[mi, 2] * f_s * light_color[i, 2]
            out[y, x, 0] = min(max(r, 0.0), 1.0)
            out[y, x, 1] = min(max(g, 0.0), 1.0)
            out[y, x, 2] = min(max(b, 0.0), 1.0)
            out[y, x, 3] = 1.0


#: Relative error of f_s by repeated multiplication, per unit of the exponent (u = 2^-53 with
#: a margin; x^k by any multiplication chain is within (k - 1) u of the true power, and libm's
#: pow within an ulp of it).
_POW_REL = 1.2e-16
#: Absolute error allowed on top (intermediate powers below 1e-280 may be subnormal).
_POW_ABS = 1e-280
#: Bound of the rounding of one float64 operation relative to the magnitudes summed (2^-52).
_ULP = 2.3e-16


@njit(inline="always")
def _int_pow(base, k):
    """base ** k for an integer k >= 1 by binary exponentiation (no libm pow)."""
    result = 1.0
    b = base
    e = k
    while e > 0:
        if e & 1:
            result = result * b
        e = e >> 1
        if e > 0:
            b = b * b
    return result


@njit(inline="always")
def _same_float32(v, e):
    """Whether every value within ``e`` of ``v`` stores as the same clipped float32."""
    lo = np.float32(min(max(v - e, 0.0), 1.0))
    hi = np.float32(min(max(v + e, 0.0), 1.0))
    return lo == hi


@banded("cover")
def shade_smooth(
    lo,
    hi,
    cover,
    mesh_id,
    normal,
    position,
    m_ambient,
    m_diffuse,
    m_specular,
    shininess,
    pow_int,
    spec_mag,
    spec_on,
    light_kind,
    light_vec,
    light_color,
    eye,
    specular,
    phong,
    out,
):
    """``shade_lit``'s MODE_SMOOTH (Veryovka eq. 1), in a kernel of its own (arguments as
    there), with f_s = base ** shininess by multiplications where ``pow_int (O,) int64`` holds
    the object's integer shininess k >= 1 (0: pow); spec_mag (O, L) float64: 1.01 times
    sum_c |m_s[o, c] light_color[l, c]|, the weight of an error in f_s; spec_on (O, L) bool as
    in ``shade_lit``.
    A sample whose N.L <= 0 has f_s = 0 (eq. 1) whatever the base, and an object without a
    specular colour (``spec_on``) a zero term: there the term is a signed zero, added only to a
    zero sum (where it can turn -0 into +0, as the formula does; ``_spec_term``).

    Such a sample's colour carries a bound on its distance from the colour with libm's pow
    (relative (k + 3) u on f_s, then the rounding of the operations that follow); where the
    bound leaves the clipped float32 value in doubt the sample is shaded again with pow, so the
    stored result is the pow one, bit for bit. ``out`` must be float32, and every material
    and light colour non-negative (the terms summed then bound the rounding), where any k > 0.
    """
    nh, nw = cover.shape
    n_lights = light_kind.shape[0]
    nrm = normal.reshape(nh, nw * 3)
    pos = position.reshape(position.shape[0], position.shape[1] * 3)
    v = np.zeros((3, nw))
    lt = np.empty((3, nw))
    n_dot_ls = np.empty((n_lights, nw))
    bases = np.zeros((n_lights, nw))
    for y in range(lo, hi):
        _row_terms(
            cover, y, nrm, pos, eye, light_kind, light_vec, specular, phong, v, lt, n_dot_ls, bases
        )
        for x in range(nw):
            if cover[y, x] < 0:
                out[y, x, 0] = 0.0
                out[y, x, 1] = 0.0
                out[y, x, 2] = 0.0
                out[y, x, 3] = 0.0
                continue
            mi = max(mesh_id[y, x], 0)
            p = shininess[mi]
            k = pow_int[mi]
            while True:  # with f_s by multiplications (k > 0), then with pow if in doubt
                r = m_ambient[mi, 0]  # eq. 1: m_a l_a
                g = m_ambient[mi, 1]
                b = m_ambient[mi, 2]
                err = 0.0  # bound of the pow replacement, summed over the terms
                for i in range(n_lights):
                    n_dot_l = n_dot_ls[i, x]  # N.L, and the specular base, from _row_terms
                    f_d = n_dot_l if n_dot_l >= 0.0 else 0.0  # eq. 1: f_d = max(N.L, 0)
                    dr = m_diffuse[mi, 0] * f_d * light_color[i, 0]
                    dg = m_diffuse[mi, 1] * f_d * light_color[i, 1]
                    db = m_diffuse[mi, 2] * f_d * light_color[i, 2]
                    r = r + dr
                    g = g + dg
                    b = b + db
                    if not (specular and p > 0.0):
                        continue
                    if n_dot_l > 0.0 and spec_on[mi, i]:
                        base = bases[i, x]  # max(R.V, 0) or max(N.H, 0)
                        if k > 0:  # base ** p within e_s (checked below)
                            f_s = _int_pow(base, k)
                            err = err + spec_mag[mi, i] * (abs(f_s) * (k + 3) * _POW_REL + _POW_ABS)
                        else:
                            f_s = base**p  # eq. 1: f_s
                        sr = m_specular[mi, 0] * f_s * light_color[i, 0]
                        sg = m_specular[mi, 1] * f_s * light_color[i, 1]
                        sb = m_specular[mi, 2] * f_s * light_color[i, 2]
                        r = r + sr
                        g = g + sg
                        b = b + sb
                    elif r == 0.0 or g == 0.0 or b == 0.0:
                        # f_s = 0 (eq. 1: N.L <= 0), or m_s l_i zero channel by channel: the
                        # term is the signed zero m_s 0 l_i, which changes only a zero sum
                        # (-0 + +0 = +0; see _spec_term); elsewhere it is skipped
                        r = r + m_specular[mi, 0] * 0.0 * light_color[i, 0]
                        g = g + m_specular[mi, 1] * 0.0 * light_color[i, 1]
                        b = b + m_specular[mi, 2] * 0.0 * light_color[i, 2]
                if k == 0 or err == 0.0:
                    break
                # and the rounding differences of the operations after a replaced pow, at most
                # an ulp of the (non-negative) terms summed, r + g + b
                err = err + (4 * n_lights + 4) * _ULP * (abs(r) + abs(g) + abs(b))
                if _same_float32(r, err) and _same_float32(g, err) and _same_float32(b, err):
                    break
                k = 0
            out[y, x, 0] = min(max(r, 0.0), 1.0)
            out[y, x, 1] = min(max(g, 0.0), 1.0)
            out[y, x, 2] = min(max(b, 0.0), 1.0)
            out[y, x, 3] = 1.0

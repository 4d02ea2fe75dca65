"""numba kernels of toon and smooth shading (private; inputs validated by ``shading.lit_rgba``).

Banded over the sample rows (a row per task, no reductions, so the result does not depend on
the thread count): per covered sample, Veryovka eq. 1's ambient + diffuse + specular sums
(``shade_smooth_for``), or their multi-tone steps of eqs. 2-4 and Lake et al.'s ramp
(``shade_toon_for``), from the formulas of :mod:`refnpr.formulas.lighting` and
:mod:`refnpr.formulas.threshold`, stored as float32 straight-alpha RGBA clipped to [0, 1].

Each row first goes through branch-free passes over contiguous float64 scratch rows (V, each
light's L, f_d and the specular base, T_n of f_d: ``_row_terms``, ``_row_step_tones``) that LLVM
compiles to SIMD divisions, square roots and roundings; the per-sample loop then only selects
and sums. IEEE division and square root are correctly rounded in SIMD as in scalar code, so the
values are the same bits (tests/styles/test_shade_kernels.py checks the float64 arithmetic).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from refnpr._jit import banded, njit, specialised
from refnpr.device.lights import LIGHT_POINT
from refnpr.device.vectors import towards
from refnpr.formulas.lighting import diffuse, illumination_term, specular_base, toon_ramp
from refnpr.formulas.threshold import step_n

from .params import SMOOTH, TOON

_diffuse = diffuse.scalar
_specular_base = specular_base.scalar
_term = illumination_term.scalar
_toon_ramp = toon_ramp.scalar
_step_n = step_n.scalar


class Tables(NamedTuple):
    """What the lit kernels read beside the frame and style records.

    ramp : (K,) float64, Lake's ramp (toon ``mode="lake"``), else any
    edge_lo, edge_hi : (O, B) float64, tones : (B + 1,) float64: T_n of the specular term
        without ``pow`` where the tone is certain (toon step with specular; see
        ``shading._step_edges``), else any
    spec_on : (O, L) bool, m_s and the light's colour both nonzero in some channel (else the
        specular term, a signed zero, is skipped: ``_spec_term``)
    pow_int : (O,) int64, the integer shininess k >= 1 whose f_s the smooth kernel forms by
        multiplications (0: pow)
    spec_mag : (O, L) float64, 1.01 sum_c |m_s l_c|: the weight of an error in f_s
    albedo : (nH, nW, 3) float64, the colour map's factor a of each sample, multiplying m_a and
        m_d (``refnpr.styles.albedo``), or a (0, 0, 3) stand-in: a = 1
    """

    ramp: np.ndarray
    edge_lo: np.ndarray
    edge_hi: np.ndarray
    tones: np.ndarray
    spec_on: np.ndarray
    pow_int: np.ndarray
    spec_mag: np.ndarray
    albedo: np.ndarray


class Row(NamedTuple):
    """Per-row float64 scratch of the lit kernels, over the sample columns."""

    v: np.ndarray  # (3, nW)
    l: np.ndarray  # (3, nW)
    f_d: np.ndarray  # (L, nW)
    base: np.ndarray  # (L, nW)
    tone: np.ndarray  # (L, nW)


@njit
def _scratch(n_lights, nw):
    return Row(
        np.zeros((3, nw)),
        np.empty((3, nw)),
        np.empty((n_lights, nw)),
        np.zeros((n_lights, nw)),
        np.empty((n_lights, nw)),
    )


@njit
def _covered_span(cover_row):
    """``(x0, x1)`` enclosing the row's covered samples (``cover >= 0``); x0 == x1 if none."""
    nw = cover_row.shape[0]
    x0 = 0
    while x0 < nw and cover_row[x0] < 0:
        x0 += 1
    x1 = nw
    while x1 > x0 and cover_row[x1 - 1] < 0:
        x1 -= 1
    return x0, x1


@njit
def _towards_row(target, prow, o):
    """``o[:, x] = towards(target, position[x])`` for the positions ``prow (n * 3,)``."""
    ox, oy, oz = o
    for x in range(ox.shape[0]):
        p = (np.float64(prow[3 * x]), np.float64(prow[3 * x + 1]), np.float64(prow[3 * x + 2]))
        ox[x], oy[x], oz[x] = towards(target, p)


@njit
def _light_row(nrow, light, flags, v, l, out):
    """One light ``(point, vec)``'s ``out = (f_d, base)`` over one row span, on 1D views (they
    vectorize); ``flags = (specular, phong)``, ``v``, ``l``: V and a point light's L."""
    point, vec = light
    specular, phong = flags
    f_d, base = out
    for x in range(f_d.shape[0]):
        n = (np.float64(nrow[3 * x]), np.float64(nrow[3 * x + 1]), np.float64(nrow[3 * x + 2]))
        lx = (l[0][x], l[1][x], l[2][x]) if point else vec
        f_d[x] = _diffuse(n, lx, False)  # eq. 1: f_d = max(N.L, 0)
    if not specular:
        return
    for x in range(f_d.shape[0]):
        n = (np.float64(nrow[3 * x]), np.float64(nrow[3 * x + 1]), np.float64(nrow[3 * x + 2]))
        lx = (l[0][x], l[1][x], l[2][x]) if point else vec
        vx = (v[0][x], v[1][x], v[2][x])
        base[x] = _specular_base(n, lx, vx, phong, False)  # max(N.H, 0) or max(R.V, 0)


# Once per row, not per sample: a call, compiled once for both kernels (inlined, each kernel
# typed it again). It takes the frame's lights and eye, not the frame record: a numba function
# taking the frame record compiles in 0.3-0.5 s more (its many arrays as arguments).
@njit
def _row_terms(lights, eye, arrays, y, flags, row):
    """f_d and the specular base of every light over row y's covered span ``(x0, x1)``
    (returned) into ``row``; ``lights``, ``eye``: the frame's; ``arrays``: :func:`_grids`. The
    passes get views of the span and loop from 0 (a loop from x0, a signed start, compiled
    without SIMD)."""
    cover, nrm, pos = arrays
    specular = flags[0]
    kind = lights.kind
    vec = lights.vec
    x0, x1 = _covered_span(cover[y])
    if x0 == x1:
        return x0, x1
    nrow = nrm[y, 3 * x0 : 3 * x1]
    prow = pos[y, 3 * x0 : 3 * x1] if pos.shape[0] > y else pos[0]
    v = (row.v[0, x0:x1], row.v[1, x0:x1], row.v[2, x0:x1])
    l = (row.l[0, x0:x1], row.l[1, x0:x1], row.l[2, x0:x1])
    if specular:  # V: the unit vector towards the eye
        _towards_row(eye, prow, v)
    for i in range(kind.shape[0]):
        point = kind[i] == LIGHT_POINT
        target = (vec[i, 0], vec[i, 1], vec[i, 2])
        if point:  # L = towards(light, p)
            _towards_row(target, prow, l)
        out = (row.f_d[i, x0:x1], row.base[i, x0:x1])
        _light_row(nrow, (point, target), flags, v, l, out)
    return x0, x1


@njit
def _row_step_tones(f_d, t, n, tone):
    """``tone[x] = T_n(f_d[x], t)`` (eq. 4 in eq. 2) over a row span, vectorized."""
    for x in range(f_d.shape[0]):
        tone[x] = _step_n(f_d[x], t, n)


@njit
def _spec_term(nonzero, rgb):
    """Whether the specular term must be added to the colour sums ``rgb``.

    ``nonzero`` is False where, in every channel, the object's m_s or the light's colour is
    zero (no specular colour, as the teapot's floor): then the term m_s f_s l_i is a signed zero
    for any finite f_s (f_s <= base ** shininess with base <= 1 + 1e-6: finite below a
    shininess of ~1e9), and adding it changes no sum unless the sum is itself zero (-0 + +0 =
    +0), where it is added as the formula does. Skipping it gives the same bits.
    """
    return nonzero or rgb[0] == 0.0 or rgb[1] == 0.0 or rgb[2] == 0.0


@njit
def _add(rgb, m, mi, f, color, i):
    """``rgb`` plus light i's term m f l (eq. 1) for object mi, channel by channel."""
    return (
        _term(rgb[0], m[mi, 0], f, color[i, 0]),
        _term(rgb[1], m[mi, 1], f, color[i, 1]),
        _term(rgb[2], m[mi, 2], f, color[i, 2]),
    )


@njit
def _add_mapped(rgb, m, mi, a, f, color, i):
    """:func:`_add` of the term (m a) f l: m times the colour map's factor ``a`` (a separate
    function: an unused ``a`` argument of ``_add`` cost 6 % of the smooth kernel)."""
    return (
        _term(rgb[0], m[mi, 0] * a[0], f, color[i, 0]),
        _term(rgb[1], m[mi, 1] * a[1], f, color[i, 1]),
        _term(rgb[2], m[mi, 2] * a[2], f, color[i, 2]),
    )


#: The colour map factor of a sample without one (m a is m exactly).
_ONE = (1.0, 1.0, 1.0)


@njit
def _store(out, y, x, rgb):
    out[y, x, 0] = min(max(rgb[0], 0.0), 1.0)
    out[y, x, 1] = min(max(rgb[1], 0.0), 1.0)
    out[y, x, 2] = min(max(rgb[2], 0.0), 1.0)
    out[y, x, 3] = 1.0


@njit
def _clear(out, kept, y, x, keep):
    """Empty sample (y, x): RGBA 0 and, where ``keep``, its two intermediates 0."""
    for c in range(4):
        out[y, x, c] = 0.0
    if keep:
        kept[y, x, 0] = 0.0
        kept[y, x, 1] = 0.0


@njit(inline="always")  # a call taking the frame record compiles in 0.3-0.5 s more
def _grids(frame):
    """``(cover, nrm, pos)``: the frame's coverage, normals and positions as (nH, nW * 3) views."""
    nh, nw = frame.cover.shape
    pos = frame.position
    return (
        frame.cover,
        frame.normal.reshape(nh, nw * 3),
        pos.reshape(pos.shape[0], pos.shape[1] * 3),
    )


@njit(inline="always")  # as _grids
def _locals(frame):
    """What the lit kernels read of the frame record, taken once as locals (read from a record
    inside the loops, each access takes and drops a reference to the array): ``(mesh_id,
    (ambient, m_d, m_s, shininess), lights, eye, _grids(frame))``."""
    m = frame.materials
    eye = (frame.eye[0], frame.eye[1], frame.eye[2])
    return (
        frame.mesh_id,
        (m.ambient, m.diffuse, m.specular, m.shininess),
        frame.lights,
        eye,
        _grids(frame),
    )


#: Codes of the toon and smooth records (their declarations' choices).
LAKE = TOON.code("mode", "lake")
PHONG = SMOOTH.code("model", "phong")


@specialised
def shade_toon_for(mapped, keep):
    """:func:`shade_toon` with (``mapped``) or without the colour maps' factors
    (``tables.albedo``) and with (``keep``) or without the intermediates (``kept``): numba
    prunes the other branches, so a frame without them runs the code it ran before."""

    @banded("out")
    def shade_toon(lo, hi, frame, style, tables, out, kept):
        """Toon shading of rows ``lo..hi - 1`` of ``out (nH, nW, 4)`` (written in full; zero
        where empty): eq. 2 with both terms through T_n(., t, n) of eq. 4 (``style.mode``
        STEP), or ``m_a l_a + sum m_d ramp(N.L) l_i`` (LAKE, Lake et al. 2000, nearest texel),
        from the frame record (cover, mesh_id, normal, position where read, eye, lights,
        materials), the toon style record (n, t, mode, specular) and :class:`Tables`. The
        specular T_n takes ``tables.tones[j]`` where the base lies in [edge_hi[j - 1],
        edge_lo[j]] (its tone is certain there, see ``shading._step_edges``), elsewhere pow as
        the formula does. ``kept (nH, nW, 2)`` float64 (``keep``): the first light's f_d and its
        toon tone (T_n or the ramp), 0 where empty.
        """
        mesh_id, (ambient, m_d, m_s, shininess), lights, eye, arrays = _locals(frame)
        color, cover, albedo = lights.color, arrays[0], tables.albedo
        n_lights, nw = color.shape[0], cover.shape[1]
        ramp, edge_lo, edge_hi = tables.ramp, tables.edge_lo, tables.edge_hi
        tones, spec_on = tables.tones, tables.spec_on
        steps = style.n
        t = style.t
        specular = style.specular
        lake = style.mode == LAKE
        k_ramp = ramp.shape[0]
        n_edges = edge_lo.shape[1]
        row = _scratch(n_lights, nw)
        for y in range(lo, hi):
            # phong as a bool, not the literal False: _light_row and _specular_base then compile
            # once for both kernels
            x0, x1 = _row_terms(lights, eye, arrays, y, (specular, np.bool_(False)), row)
            if not lake:
                for i in range(n_lights):
                    _row_step_tones(row.f_d[i, x0:x1], t, steps, row.tone[i, x0:x1])
            for x in range(nw):
                if cover[y, x] < 0:
                    _clear(out, kept, y, x, keep)
                    continue
                mi = max(mesh_id[y, x], 0)
                a = _ONE
                if mapped:  # the colour map's factor
                    a = (albedo[y, x, 0], albedo[y, x, 1], albedo[y, x, 2])
                rgb = (ambient[mi, 0] * a[0], ambient[mi, 1] * a[1], ambient[mi, 2] * a[2])
                p = shininess[mi]
                if keep:
                    kept[y, x, 0] = 0.0
                    kept[y, x, 1] = 0.0
                for i in range(n_lights):
                    f_d = row.f_d[i, x]
                    if lake:  # Lake et al.: nearest texel of clip(N.L, 0, 1)
                        tone = ramp[_toon_ramp(f_d, k_ramp)]
                    else:
                        tone = row.tone[i, x]  # eq. 4 in eq. 2, from _row_step_tones
                    if keep and i == 0:
                        kept[y, x, 0] = f_d
                        kept[y, x, 1] = tone
                    if mapped:
                        rgb = _add_mapped(rgb, m_d, mi, a, tone, color, i)
                    else:
                        rgb = _add(rgb, m_d, mi, tone, color, i)
                    if specular and p > 0.0 and _spec_term(spec_on[mi, i], rgb):
                        base = row.base[i, x]  # max(N.H, 0)
                        if f_d > 0.0:
                            j = 0
                            while j < n_edges and base >= edge_hi[mi, j]:
                                j += 1
                            if (j < n_edges and base > edge_lo[mi, j]) or tones[j] < 0.0:
                                f_s = _step_n(base**p, t, steps)  # eq. 4 of eq. 1's f_s
                            else:
                                f_s = tones[j]  # the same: T_n is constant around base**p
                        else:
                            f_s = _step_n(0.0, t, steps)  # eq. 1: f_s = 0 where N.L <= 0
                        rgb = _add(rgb, m_s, mi, f_s, color, i)
                _store(out, y, x, rgb)

    return shade_toon


#: Relative error of f_s by repeated multiplication, per unit of the exponent (u = 2^-53 with
#: a margin; x^k by any multiplication chain is within (k - 1) u of the true power, and libm's
#: pow within an ulp of it).
_POW_REL = 1.2e-16
#: Absolute error allowed on top (intermediate powers below 1e-280 may be subnormal).
_POW_ABS = 1e-280
#: Bound of the rounding of one float64 operation relative to the magnitudes summed (2^-52).
_ULP = 2.3e-16


@njit
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


@njit
def _same_float32(v, e):
    """Whether every value within ``e`` of ``v`` stores as the same clipped float32."""
    lo = np.float32(min(max(v - e, 0.0), 1.0))
    hi = np.float32(min(max(v + e, 0.0), 1.0))
    return lo == hi


@specialised
def shade_smooth_for(mapped, keep):
    """:func:`shade_smooth` with (``mapped``) or without the colour maps' factors
    (``tables.albedo``) and with (``keep``) or without the intermediates (``kept``), as
    :func:`shade_toon_for`."""

    @banded("out")
    def shade_smooth(lo, hi, frame, style, tables, out, kept):
        """Smooth shading (Veryovka eq. 1) of rows ``lo..hi - 1`` of ``out (nH, nW, 4)`` from
        the frame record, the smooth style record (specular, model) and :class:`Tables`, with
        f_s = base ** shininess by multiplications where ``tables.pow_int`` holds the object's
        integer shininess k >= 1 (0: pow). A sample whose N.L <= 0 has f_s = 0 (eq. 1)
        whatever the base, and an object without a specular colour (``tables.spec_on``) a zero
        term: there the term is a signed zero, added only to a zero sum (where it can turn -0
        into +0, as the formula does; ``_spec_term``).

        Such a sample's colour carries a bound on its distance from the colour with libm's pow
        (relative (k + 3) u on f_s, then the rounding of the operations that follow); where the
        bound leaves the clipped float32 value in doubt the sample is shaded again with pow, so
        the stored result is the pow one, bit for bit. ``out`` must be float32, and every
        material and light colour non-negative (the terms summed then bound the rounding),
        where any k > 0. ``kept (nH, nW, 2)`` float64 (``keep``): the first light's f_d twice,
        0 where empty.
        """
        mesh_id, (ambient, m_d, m_s, shininess), lights, eye, arrays = _locals(frame)
        color, cover, albedo = lights.color, arrays[0], tables.albedo
        n_lights, nw = color.shape[0], cover.shape[1]
        pow_int, spec_mag, spec_on = tables.pow_int, tables.spec_mag, tables.spec_on
        specular = style.specular
        row = _scratch(n_lights, nw)
        for y in range(lo, hi):
            _row_terms(lights, eye, arrays, y, (specular, style.model == PHONG), row)
            for x in range(nw):
                if cover[y, x] < 0:
                    _clear(out, kept, y, x, keep)
                    continue
                mi = max(mesh_id[y, x], 0)
                p = shininess[mi]
                k = pow_int[mi]
                if keep:
                    f_0 = row.f_d[0, x] if n_lights > 0 else 0.0
                    kept[y, x, 0] = f_0
                    kept[y, x, 1] = f_0
                a = _ONE
                if mapped:  # the colour map's factor
                    a = (albedo[y, x, 0], albedo[y, x, 1], albedo[y, x, 2])
                m_a = (ambient[mi, 0] * a[0], ambient[mi, 1] * a[1], ambient[mi, 2] * a[2])
                while True:  # with f_s by multiplications (k > 0), then with pow if in doubt
                    rgb = m_a  # eq. 1: m_a l_a
                    err = 0.0  # bound of the pow replacement, summed over the terms
                    for i in range(n_lights):
                        f_d = row.f_d[i, x]
                        if mapped:  # eq. 1: diffuse sum
                            rgb = _add_mapped(rgb, m_d, mi, a, f_d, color, i)
                        else:
                            rgb = _add(rgb, m_d, mi, f_d, color, i)
                        if not (specular and p > 0.0):
                            continue
                        if f_d > 0.0 and spec_on[mi, i]:
                            base = row.base[i, x]  # max(R.V, 0) or max(N.H, 0)
                            if k > 0:  # base ** p within e_s (checked below)
                                f_s = _int_pow(base, k)
                                err = err + spec_mag[mi, i] * (
                                    abs(f_s) * (k + 3) * _POW_REL + _POW_ABS
                                )
                            else:
                                f_s = base**p  # eq. 1: f_s
                            rgb = _add(rgb, m_s, mi, f_s, color, i)  # eq. 1: specular sum
                        elif rgb[0] == 0.0 or rgb[1] == 0.0 or rgb[2] == 0.0:
                            # f_s = 0 (eq. 1: N.L <= 0), or m_s l_i zero channel by channel: the
                            # term is the signed zero m_s 0 l_i, which changes only a zero sum
                            # (-0 + +0 = +0; see _spec_term); elsewhere it is skipped
                            rgb = _add(rgb, m_s, mi, 0.0, color, i)
                    if k == 0 or err == 0.0:
                        break
                    # and the rounding differences of the operations after a replaced pow, at most
                    # an ulp of the (non-negative) terms summed, r + g + b
                    err = err + (4 * n_lights + 4) * _ULP * (
                        abs(rgb[0]) + abs(rgb[1]) + abs(rgb[2])
                    )
                    if (
                        _same_float32(rgb[0], err)
                        and _same_float32(rgb[1], err)
                        and _same_float32(rgb[2], err)
                    ):
                        break
                    k = 0
                _store(out, y, x, rgb)

    return shade_smooth

"""numba kernels of X-Toon shading (private; inputs validated by ``shading.shade_rgba``).

Per covered sample (``mesh_id >= 0``): the unit shading normal, the tone n . l (sec. 3) and the
detail D of an attribute map (sec. 3.1, 3.2) -- :func:`sample_terms`, composing the formulas of
:mod:`refnpr.formulas.xtoon` -- then, over the row's covered span, the bilinear edge-clamped
lookup in the 2D toon texture (``toon_lookup.scalar``) and the straight-alpha RGBA, or the grey
attribute images of ``show``. The lookup runs as a second, branch-free pass over each row's span
(without the first pass's branches and calls it took the 1080p kernel from 12.8 to 8.6 ms).

Where the normals or D come from elsewhere (shape abstraction, per-vertex detail, flow, a user
map) the caller gives the tone and D of the covered samples (:class:`Tables`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from refnpr._jit import banded, njit
from refnpr.device.color import srgb_to_linear
from refnpr.device.lights import LIGHT_POINT, light_dir
from refnpr.device.scalars import clip01
from refnpr.device.vectors import dot, reflect, unit
from refnpr.formulas.xtoon import (
    TINY,
    detail_depth,
    detail_focus,
    detail_highlight,
    detail_orientation,
    tone,
    toon_lookup,
)

from .params import PARAMS

_detail_depth, _detail_focus = detail_depth.scalar, detail_focus.scalar
_detail_orientation, _detail_highlight = detail_orientation.scalar, detail_highlight.scalar
_tone, _toon_lookup = tone.scalar, toon_lookup.scalar

#: Codes of the style record (the declaration's choices).
DEPTH, FOCUS, ORIENTATION, HIGHLIGHT = (
    PARAMS.code("detail", c) for c in ("depth", "focus", "orientation", "highlight")
)
AXIS = PARAMS.code("distance", "axis")
HALF_LAMBERT = PARAMS.code("tone", "half_lambert")
COLOR, DETAIL, INVERSE = (PARAMS.code("show", c) for c in ("color", "detail", "inverse_detail"))


class Tables(NamedTuple):
    """The arrays of a frame's X-Toon shading beside the style record (which holds numbers
    only: a record passed per sample must hold no array, whose reference count each call
    would take and drop).

    texels : (rows * cols * 4,) float64, the toon texture ``(rows, cols, 4)`` flat
    given : whether tone and D of the covered samples were computed before the kernel
    offsets : (nH + 1,) int64, row y's first sample in row-major mask order (``given``)
    tone, detail : (K,) float64 (``given``)
    """

    texels: np.ndarray
    given: bool
    offsets: np.ndarray
    tone: np.ndarray
    detail: np.ndarray


@njit(inline="always")
def detail_at(style, eye, p, n, l, z_axis):
    """D of the attribute maps a sample's geometry gives (sec. 3.1, 3.2): ``p`` the world
    position, ``n`` the unit shading normal, ``l`` the unit direction towards the light,
    ``z_axis`` the view-axis distance (G-buffer ``depth``); 1 for any other map."""
    kind = style.detail
    if kind == DEPTH or kind == FOCUS:
        if style.distance == AXIS:
            z = z_axis  # Fig. 2b
        else:  # Fig. 2a: |p - eye|
            z = math.sqrt(
                (p[0] - eye[0]) * (p[0] - eye[0])
                + (p[1] - eye[1]) * (p[1] - eye[1])
                + (p[2] - eye[2]) * (p[2] - eye[2])
            )
        if kind == DEPTH:
            return _detail_depth(z, style.z_min, style.log_r)  # sec. 3.1
        return _detail_focus(z, style.focus)  # sec. 3.1, depth of field
    if kind == ORIENTATION or kind == HIGHLIGHT:
        vx = eye[0] - p[0]  # v: unit vector towards the eye
        vy = eye[1] - p[1]
        vz = eye[2] - p[2]
        length = max(math.sqrt(vx * vx + vy * vy + vz * vz), TINY)
        v = (vx / length, vy / length, vz / length)
        if kind == ORIENTATION:
            return _detail_orientation(dot(n, v), style.r)  # sec. 3.2: |n.v|^r
        refl = reflect(l, n, dot(n, l))  # r = 2 (n.l) n - l
        return _detail_highlight(dot(v, refl), style.s, style.one_sided)  # sec. 3.2
    return 1.0


@njit(inline="always")
def sample_terms(style, eye, light, p, n, z_axis):
    """``(tone, D)`` of a sample at world position ``p`` with the (any length) normal ``n``;
    ``light = (point, vec)``: the style's light (``Lights.kind == LIGHT_POINT`` and its
    ``Lights.vec`` row)."""
    n = unit(n)
    l = light_dir(light[0], light[1], p)
    t = _tone(dot(n, l), style.tone == HALF_LAMBERT)  # sec. 3
    return t, detail_at(style, eye, p, n, l, z_axis)


@njit
def _vec3(a, y, x):
    return np.float64(a[y, x, 0]), np.float64(a[y, x, 1]), np.float64(a[y, x, 2])


@njit
def _shown(show, t, d):
    """The grey of a ``show`` view: the quantity as the displayed (sRGB) value."""
    value = d if show == DETAIL else (1.0 - d if show == INVERSE else t)
    return clip01(srgb_to_linear(clip01(value)))


@njit
def _lookup_row(tex, texels, rows, mrow, diffuse, orow, span):
    """The RGBA of the toon ``texels`` (``tex = (rows, cols, modulate)`` of the style record)
    at ``(tone, D) = rows[0][x], rows[1][x]`` (times the diffuse colour with ``modulate``) for
    ``x`` in ``span = (xs, xe)`` into ``orow``, the row's ``(nW * 4,)`` view; 0 where ``mrow <
    0`` (branch-free: that lookup is dropped). Takes three numbers of the record, not the
    record: it compiles faster."""
    tone_row, d_row = rows
    tex_rows, tex_cols, modulate = tex
    for x in range(span[0], span[1]):
        mi = mrow[x]
        covered = mi >= 0
        m = max(mi, 0)
        rgba = _toon_lookup(texels, tex_rows, tex_cols, tone_row[x], d_row[x])
        for ch in range(4):
            v = rgba[ch]
            if modulate and ch < 3:
                v = v * diffuse[m, ch]
            orow[4 * x + ch] = clip01(v) if covered else 0.0


@banded("out")
def shade_xtoon(lo, hi, frame, style, tables, out, bad_rows, kept):
    """Shade rows ``lo..hi - 1`` of ``out (nH, nW, 4)`` float32 (written in full; zero where
    empty) from the :class:`refnpr.styles._frame.Frame` ``frame`` (mesh_id; normal, position and
    depth as the style reads them), the style record ``style`` (``PARAMS.Record``) and the
    :class:`Tables` (the texture, and tone and D where given). ``bad_rows (nH,)`` uint8: set to
    1 where a tone or D is NaN. ``kept (nH, nW, 2)`` float64: each sample's tone and D (0 where
    empty), or a ``(0, 0, 2)`` stand-in where nobody reads them.
    """
    # the records' arrays as locals, taken once: read from a record inside the loops, each
    # access takes and drops a reference to the array (atomic operations, per sample)
    mesh_id = frame.mesh_id
    normal = frame.normal
    position = frame.position
    depth = frame.depth
    diffuse = frame.materials.diffuse
    texels = tables.texels
    given = tables.given
    offsets = tables.offsets
    given_tone = tables.tone
    given_detail = tables.detail
    nh, nw = mesh_id.shape
    eye = (frame.eye[0], frame.eye[1], frame.eye[2])
    vec = frame.lights.vec
    i = style.light
    light = (frame.lights.kind[i] == LIGHT_POINT, (vec[i, 0], vec[i, 1], vec[i, 2]))
    has_position = position.shape[0] == nh and position.shape[1] == nw  # else a stand-in
    has_depth = depth.shape[0] == nh and depth.shape[1] == nw
    color = style.show == COLOR
    keep = kept.shape[0] == nh
    # a row in two passes (colour): tone and D of each sample into the row's scratch, and the
    # span of covered samples; then the lookup over that span (_lookup_row), zeros around
    tone_row = np.empty(nw)
    d_row = np.empty(nw)
    for y in range(lo, hi):
        k = offsets[y] if given else 0
        bad_rows[y] = 0
        xs = nw  # covered span [xs, xe)
        xe = 0
        for x in range(nw):
            if mesh_id[y, x] < 0:
                tone_row[x] = 0.0
                d_row[x] = 0.0
                if keep:
                    kept[y, x, 0] = 0.0
                    kept[y, x, 1] = 0.0
                if not color:
                    for ch in range(4):
                        out[y, x, ch] = 0.0
                continue
            xs = min(xs, x)
            xe = x + 1
            if given:
                t = given_tone[k]
                d = given_detail[k]
                k += 1
            else:
                p = _vec3(position, y, x) if has_position else (0.0, 0.0, 0.0)
                z = np.float64(depth[y, x]) if has_depth else 0.0
                t, d = sample_terms(style, eye, light, p, _vec3(normal, y, x), z)
            if t != t or d != d:
                bad_rows[y] = 1
                t = 0.0
                d = 0.0
            if keep:
                kept[y, x, 0] = t
                kept[y, x, 1] = d
            if not color:
                grey = _shown(style.show, t, d)
                out[y, x, 0] = grey
                out[y, x, 1] = grey
                out[y, x, 2] = grey
                out[y, x, 3] = 1.0
                continue
            tone_row[x] = t
            d_row[x] = d
        if color:
            orow = out[y].reshape(-1)
            for i in range(4 * xs):
                orow[i] = 0.0
            for i in range(4 * max(xe, xs), 4 * nw):
                orow[i] = 0.0
            if xe > xs:
                # max(): an int64 span as numba first types it (xe alone starts as the
                # literal 0, which compiled _lookup_row a second time)
                span = (xs, max(xe, xs))
                tex = (style.rows, style.cols, style.modulate)
                _lookup_row(tex, texels, (tone_row, d_row), mesh_id[y], diffuse, orow, span)

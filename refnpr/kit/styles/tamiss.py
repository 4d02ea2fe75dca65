"""Kit export of the ``tamiss`` style (Szécsi, Szirányi, Kacsó: TAMISS).

Every parameter is resolved by the style's own code: its declaration's resolved values
(``PARAMS.resolved``: ``directions`` as angles in degrees, ``layer_tones`` as numbers),
``visibility_threshold`` from the formula's default 1 / (2 (1 + prior_weight)), and the brush
as a texture file. What TAMISS derives from the
mesh topology (uv charts, their orientation, offset and id group, the smooth per-vertex tangent
frames) is exported per vertex, computed by refnpr's own functions
(:func:`refnpr.styles.tamiss.charts.chart_layout`,
:func:`~refnpr.styles.tamiss.charts.vertex_frames`), so that a backend needs no mesh analysis.

Params layout (``case.json`` ``style.params``): the declared parameters in their order
(directions, layer_tones, period, length, length_jitter, width_jitter, density, max_level,
gather_width, aggregation, ..., smooth, ``ink``, ``paper``, ``base``), with

* ``brush``: ``{"name": <refnpr's brush name or "solid">, "role": "brush", "wrap_t": bool}``
  (texture ``brush``: (Hb, Wb) float32 alpha, rows across the stroke, columns along t);
* ``visibility_threshold``: the number used;
* ``constants``: the integers of the stroke field and its hashes (KX, salts, bit layout), so that
  the backend does not hard-code refnpr's values.

Per-vertex attributes (.glb, float32): ``_TAMISS_FRAME_U``, ``_TAMISS_FRAME_V`` (VEC3, dP/du
and dP/dv) and ``_TAMISS_FRAME_U_LO``, ``_TAMISS_FRAME_V_LO`` (the float64 residual, so hi + lo
is the float64 frame to ~1e-14), ``_TAMISS_CHART`` (SCALAR, the chart number over the scene),
``_TAMISS_CHART_MAP`` (VEC4: M00, M01, M10, M11 of the chart's signed permutation u' = M u +
offset), ``_TAMISS_CHART_OFFSET`` (VEC2), ``_TAMISS_CHART_GROUP`` (SCALAR, the chart number
stroke ids use when ``orient_charts``).
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from refnpr.styles.tamiss import field as F
from refnpr.styles.tamiss import strokes as ST
from refnpr.styles.tamiss.charts import SYMMETRIES, chart_layout, vertex_frames
from refnpr.styles.tamiss.gather import chart_meshes
from refnpr.styles.tamiss.params import PARAMS
from refnpr.styles.tamiss.raster import brush_texture
from refnpr.styles.tamiss.show import LEVEL_COLORS

from .._json import jsonable
from ..textures import ORIENTATION_ROW0_TOP, write_texture_levels
from ._export import StyleExport

__all__ = ["export", "derived", "vertex_data", "DERIVED"]

#: hash01 of the TAMISS texts (salts are small integers here, multiplied by M1).
_HASH01 = (
    "hash01(id, salt) = (splitmix64((uint64(id) + salt * M1) mod 2^64) >> 11) / 2^53 with "
    "splitmix64(z): z = z + M1; z = (z ^ (z >> 30)) * M2; z = (z ^ (z >> 27)) * M3; return z ^ "
    "(z >> 31), uint64 modulo 2^64, (M1, M2, M3) = params.constants.splitmix64"
)
_FIT_TYPE = (
    "in params.dtype (F: float32 by default; every operation rounded to F unless said otherwise)"
)

DERIVED = {
    "tamiss-inputs": (
        "Per covered sample (tri_id >= 0; o = mesh_id; V_0, V_1, V_2 the triangle's vertices in "
        "index-buffer order, per tri_id and objects[o].first_tri_id), in float64 (the G-buffer is "
        "float64: raster_options.dtype): uv, duv_dx, duv_dy from the channels (per image pixel), "
        "(su, sv) = objects[o].material.uv_scale. params.derivatives 'smooth': the vertex frame "
        "g_u(V) = _TAMISS_FRAME_U + _TAMISS_FRAME_U_LO (added in float64; g_v(V) = "
        "_TAMISS_FRAME_V + _TAMISS_FRAME_V_LO alike), g_u = sum_c bary_c g_u(V_c), g_v alike (c = "
        "0, 1, 2 in order), a00 = g_u . g_u, a01 = g_u . g_v, a11 = g_v . g_v, det = a00 a11 - "
        "a01^2; D = position - camera.eye, n = the normal channel; where det > 1e-12 (a00 a11) "
        "and det > 0 and |n . D| >= 0.05 |D| |n| and |D| > 0, for each of dP = dposition_dx, "
        "dposition_dy: lam = (n . dP) / (n . D), dP_n = dP - lam D, r0 = g_u . dP_n, r1 = g_v . "
        "dP_n, du = (a11 r0 - a01 r1) / det, dv = (a00 r1 - a01 r0) / det (these replace duv_dx, "
        "duv_dy); elsewhere the channels' values stay. params.orient_charts: with M = "
        "_TAMISS_CHART_MAP (M00, M01, M10, M11, row-major) and (o_0, o_1) = _TAMISS_CHART_OFFSET "
        "of V_0 (equal on the three vertices): uv = (M00 u + M01 v + o_0, M10 u + M11 v + o_1), "
        "each derivative d = (M00 d_u + M01 d_v, M10 d_u + M11 d_v), (su, sv) = (|M00| su + |M01| "
        "sv, |M10| su + |M11| sv), chart = _TAMISS_CHART_GROUP(V_0); else chart = "
        "_TAMISS_CHART(V_0) and uv, the derivatives and (su, sv) as they are. Darkness: "
        "params.constant_tone when not null, else 1 - clip((r 0.2126 + g 0.7152) + b 0.0722, 0, "
        "1) of rgb = m.ambient * ambient + sum over lights i in order of m.diffuse * "
        "min(max(normalize(n) . L_i, 0), 1) * lights[i].color (m = objects[o].material; L_i = "
        "lights[i].direction, or normalize(lights[i].position - P) with P the position channel; "
        "normalize(v) = v / |v|)."
    ),
    "tamiss-field": (
        "Fragment gathering (TAMISS sec. 3.1, the RPTAM stroke field) per covered sample, in "
        "sample order (row-major on the n W x n H grid), then layer k, level, row, cell: rho = "
        "clip((darkness - params.layer_tones[k]) / (1 - params.layer_tones[k]) * params.density, "
        "0, 1), the layer skipped when rho <= 0; a_k = radians(params.directions[k]), c = cos "
        "a_k, s = sin a_k (float64); u = uv_0 su, v = uv_1 sv (derivatives alike), p = c u + s v, "
        "q = -s u + c v, gp = hypot(c du/dx + s dv/dx, c du/dy + s dv/dy), gq = hypot(-s du/dx + "
        "c dv/dx, -s du/dy + c dv/dy); the layer is skipped unless 0 < gp < 1e30 and 0 < gq < "
        "1e30; d_p = 1 / gp, d_q = 1 / gq; S = log2(d_q / (7 params.period)) (skipped if NaN). L "
        "= floor(S), f = S - L, thin = 1; if L < 0: thin = 2^S, L = 0, f = 0; if L >= "
        "params.max_level: L = params.max_level, f = 0; levels lev = 0 .. L, plus L + 1 when f > "
        "0, gain = thin for lev <= L and 2^f - 1 for L + 1; limit = rho gain, a level skipped "
        "when limit <= 0. hw = params.gather_width / 2, hw_q = hw / d_q, KX = "
        "params.constants.KX. Per level: R = 7 2^lev; rows ry = floor((q - hw_q) R) .. floor((q + "
        "hw_q) R) + 1 in order, dist = |q - ry / R| d_q, the row skipped when dist > hw; gy = "
        "floor(ry / 7), r = ry - 7 gy, kx = KX[r], ps = p 2^lev - kx / 7, hc = params.length (1 + "
        "params.length_jitter) / 2; cells gx = floor(ps - hc) .. floor(ps + hc) + 1 in order; a "
        "seed of level lev > 0 is skipped (inherited) when ((gx & 1) == (kx & 1)) and ((gy & 1) "
        "== (r & 1)) (& the bitwise AND of two's-complement integers, before ==). id = ((((chart "
        "* 4 + k) * 16 + lev) * 2^22 + (gx + 2^21)) * 2^22 + (gy + 2^21)) * 8 + r as int64; "
        + _HASH01
        + "; the salts tone, length, width = params.constants.salt_tone, salt_length, salt_width. "
        "lam = params.length (1 + params.length_jitter (2 hash01(id, salt_length) - 1)) / 2^lev, "
        "p_start = (gx + kx / 7) / 2^lev - lam / 2, t = (p - p_start) / lam, beyond = max(-t, t - "
        "1) lam d_p; skipped when beyond > 0. The first 256 strokes per sample and layer that "
        "pass (in this order) are candidates, later ones emit nothing; a candidate emits the "
        "fragment (x, y, t, id, layer k, level lev) when hash01(id, salt_tone) < limit and 0 <= t "
        "<= 1, with (x, y) = ((sx + 0.5) / n, (sy + 0.5) / n) the sample's centre in image PIXELS "
        "(n = sqrt(spp)). With params.gather_scale = g not null and g^2 != spp, the fragments are "
        "gathered from the scene rasterized again at g x g samples per pixel (the same channels, "
        "float64) and n = g here and in tamiss-fit; the ink is still drawn on the case's n W x n "
        "H grid, and the 'ids' view takes per case sample the first fragment with (floor(x "
        "sqrt(spp)), floor(y sqrt(spp))) on it."
    ),
    "tamiss-aggregate": (
        "Aggregation, params.aggregation 'exact' (sec. 3.1 summation): fragments grouped by id, "
        "strokes in ascending id; per stroke, "
        + _FIT_TYPE
        + ", with its fragments in gathering order and t, x, y rounded to F: count = the number "
        "of fragments; t_min = min t, t_max = max t; origin o = ((min x + max x) * 0.5, (min y + "
        "max y) * 0.5); per fragment s = (t - (t_min + h)) / h with h = (t_max - t_min) * 0.5 (s "
        "= 0 where h = 0; [t_min, t_max] maps to [-1, 1]), X = x - o_0, Y = y - o_1, and the 15 "
        "regressors (1, s, s2, s3, s4, s5, s6, X, s X, s2 X, s3 X, Y, s Y, s2 Y, s3 Y) with s2 = "
        "s s, s3 = s2 s, s4 = s3 s, s5 = s4 s, s6 = s5 s; each column summed as the first "
        "fragment's value plus numpy's pairwise sum of the others (blocks of up to 128 terms: "
        "below 8 terms a plain sum, else 8 accumulators r_0..r_7 taking terms 0..7, then each "
        "term i into r_(i mod 8) while a whole group of 8 remains, combined ((r0 + r1) + (r2 + "
        "r3)) + ((r4 + r5) + (r6 + r7)), then the rest added in order; above 128 terms split in "
        "halves, the first half a multiple of 8)."
    ),
    "tamiss-aggregate-hashed": (
        "Aggregation, params.aggregation 'hashed' (the paper's double-hashed table, sec. 4): "
        "key(id) = (splitmix64(uint64(id)) >> 32), 0xFFFFFFFF replaced by 0xFFFFFFFE; table of m "
        "= params.table_size uint32 slots, empty = 0xFFFFFFFF; slot_j(key) = (h1 + j h2) mod 2^32 "
        "mod m with h1 = lowbias32(key), h2 = lowbias32(key ^ 0x9E3779B9) | 1, lowbias32(x): x ^= "
        "x >> 16; x = x * 0x7FEB352D mod 2^32; x ^= x >> 15; x = x * 0x846CA68B mod 2^32; x ^= x "
        ">> 16. Routing one frame of the distinct keys K: each probes the read table at j = 0 .. "
        "params.max_probes - 1 until the slot holds its key (found) or is empty (claim), else it "
        "is lost; the next table holds the found keys at their slots and, per claimed slot, the "
        "smallest claiming key (the others delayed). A still starts from an empty table routed "
        "params.warmup_frames times with the frame's own keys, then routes them once more: each "
        "fragment goes to its key's slot (lost: dropped), fragments are summed per slot as "
        "tamiss-aggregate sums them per id (in gathering order); a slot is kept only when one "
        "distinct id of the frame routed to it and the minimum and maximum key it received are "
        "equal; its stroke id is its first fragment's id; kept strokes in ascending id."
    ),
    "tamiss-fit": (
        "Fit (sec. 3.2, eq. 1), per stroke "
        + _FIT_TYPE
        + ": A[i][j] = M[i + j] (i, j = 0 .. 3, M the 15 sums), b_x = M[7..10], b_y = M[11..14]; "
        "c_x = solve(A, b_x) + (o_0, 0, 0, 0), c_y = solve(A, b_y) + (o_1, 0, 0, 0) (o the "
        "stroke's origin of tamiss-aggregate); visibility with the zero prior: n_p = M[0] * "
        "params.prior_weight, P = n_p * [[1, 0, 1/3, 0], [0, 1/3, 0, 1/5], [1/3, 0, 1/5, 0], [0, "
        "1/5, 0, 1/7]] (each entry n_p * (mean of s^(i+j) over [-1, 1]), the mean rounded to F "
        "first), c_v = solve(A + P, M[0..3]). solve(A, b): in the Legendre basis Lg = [[1, 0, 0, "
        "0], [0, 1, 0, 0], [-0.5, 0, 1.5, 0], [0, -1.5, 0, 2.5]]: A_L = Lg A Lg^T, A_L = (A_L + "
        "A_L^T) * 0.5, b_L = Lg b, d_i = 1 / sqrt(A_L[i][i]) where A_L[i][i] > 0 (else 0), A_s = "
        "d_i A_L[i][j] d_j, then params.iterations conjugate-gradient steps on A_s y = d b_L from "
        "y = 0: r = d b_L, p = r, rr = r . r, stop = (8 eps_F)^2 rr (eps_F the machine epsilon of "
        "F); per step: Ap = A_s p, pAp = p . Ap, ok = rr > stop and rr > 0 and pAp > 0, alpha = "
        "rr / pAp if ok else 0, y = y + alpha p, r = r - alpha Ap, rr' = r . r, beta = rr' / rr "
        "if ok else 0, p = r + beta p if ok (else p stays), rr = rr' if ok; the coefficients in "
        "monomials of s: c = Lg^T (d y). The curve: x(s) = ((c_3 s + c_2) s + c_1) s + c_0 "
        "(Horner, in F), y(s) and v(s) alike, s = (t - (t_min + h)) / h as in tamiss-aggregate. "
        "Mean speed (px per unit t): the 17 parameters t_m = t_min + (t_max - t_min) m / 16 "
        "(float64, then rounded to F), the curve there in F, widened to float64, the 16 chord "
        "lengths hypot(dx, dy) summed as in tamiss-aggregate (8 accumulators), divided by span = "
        "t_max - t_min (float64; speed 0 where span <= 0). Drop rule: a stroke is drawn only when "
        "count >= max(params.min_fragments, 4), span >= params.min_t_span, c_x and c_y are finite "
        "and, with params.max_stretch not null, speed * span <= params.max_stretch * count / "
        "(params.gather_width n^2) + 4 (n = sqrt(spp))."
    ),
    "tamiss-extent": (
        "Drawn t intervals per drawn stroke (params.extent): 'range': [t_min, t_max]; 'stroke': "
        "[0, 1]; 'visible': the parts of [-1, 1] (in s) where v(s) >= tau, tau = "
        "params.visibility_threshold, at most two, in float64: c = c_v widened to float64, c_0 -= "
        "tau, c divided by max_i |c_i| (when > 0); the roots of v' = 3 c_3 s^2 + 2 c_2 s + c_1 (q "
        "= -(B + sign(B) sqrt(B^2 - 4 A C)) / 2 with A = 3 c_3, B = 2 c_2, C = c_1, sign(0) = +1, "
        "roots q / A and C / q; A = 0: -C / B; none where B^2 - 4 A C < 0) strictly inside (-1, "
        "1) cut [-1, 1] into monotone pieces; a piece whose end values differ in sign (< 0 "
        "against >= 0) holds one crossing, found by 64 bisection steps on [l, r] (mid = (l + r) / "
        "2 replaces l when v(mid) - tau and v(l) - tau are both < 0 or both >= 0, else r; the "
        "root is the final (l + r) / 2). The crossings sorted, with -1 and 1, bound "
        "sub-intervals; one of positive length whose midpoint has v - tau >= 0 opens or extends a "
        "visible interval, one where it is < 0 closes it (at most two intervals). Each end s maps "
        "to t = (t_min + h) + s h, with t_min + h and h in F, s h and the sum in float64, the "
        "result rounded to F. 'overdraw': the 'visible' intervals, the first start moved to "
        "max(0, start - params.overdraw / speed) and the last end to min(1, end + params.overdraw "
        "/ speed) (no change where speed = 0)."
    ),
    "tamiss-extrude": (
        "Extrusion (sec. 4) of each drawn interval (a piece), in float64. End jitter "
        "(params.end_jitter > 0), before the pieces are formed: span = last end - first start of "
        "the stroke's intervals; ja = params.end_jitter (2 hash01(id, "
        "params.constants.salt_end_a) - 1) * 0.5 * span, jb likewise with salt_end_b; the first "
        "start becomes min(start - ja, its interval's end - 1e-6), then the last end becomes "
        "max(end + jb, its interval's start + 1e-6) (that start as just updated when the stroke "
        "has one interval). Per piece: K = params.samples, u_m = m / (K - 1), t_m = t0 + (t1 - "
        "t0) u_m. Centreline at t: t_c = clip(t, t_min, t_max) rounded to F, s as in "
        "tamiss-aggregate, r = (x(s), y(s)) in F widened to float64; tangent (x'(s) * ds, y'(s) * "
        "ds) in F (x'(s) = ((0 s + 3 c_3) s + 2 c_2) s + c_1 in Horner form, ds = 2 / (t_max - "
        "t_min) in F, 0 when t_max = t_min), widened to float64, unit tangent T = tangent / "
        "|tangent| where |tangent| > 1e-12, else the unit chord r(t_max) - r(t_min) (where its "
        "length > 1e-12, else (1, 0)); outside [t_min, t_max] the point moves on along T: r + (t "
        "- t_min) speed T for t < t_min, r + (t - t_max) speed T for t > t_max. Left normal N = "
        "(-T_y, T_x). Width w = params.width (1 + params.width_jitter (2 hash01(id, "
        "params.constants.salt_width) - 1)); half width h_m = 0.5 w min(1, min(u_m, 1 - u_m) / "
        "params.taper) (params.taper = 0: 0.5 w). Wobble (params.wobble > 0): amp = params.wobble "
        "(0.5 + hash01(id, salt_wobble_amp)), phi = hash01(id, salt_wobble_phase), r += amp sin(2 "
        "pi (params.wobble_frequency t_m + phi)) N. Vertices left_m = r + h_m N, right_m = r - "
        "h_m N (pixels). Pieces in ascending stroke id, then interval."
    ),
    "tamiss-raster": (
        "Each piece's 2 (K - 1) triangles (L_m, R_m, L_m+1) with stroke t (t_m, t_m, t_m+1) and "
        "across (0, 1, 0), and (R_m, R_m+1, L_m+1) with t (t_m, t_m+1, t_m+1) and across (1, 1, "
        "0), vertices times n (sample units of the n W x n H grid); triangles with |area| < 1e-12 "
        "skipped; a piece with a non-finite vertex is skipped. Coverage of sample (x, y) (its "
        "square [x, x + 1] x [y, y + 1]): the fraction of the aa x aa sub-samples (x + (i + 0.5) "
        "/ aa, y + (j + 0.5) / aa), aa = params.aa, inside ANY triangle of the piece: inside when "
        "each edge value ((b_x - a_x)(p_y - a_y) - (b_y - a_y)(p_x - a_x)) * sgn >= 0 for the "
        "edges b -> c, c -> a, a -> b (sgn the sign of the triangle's doubled area). Brush "
        "coordinates of the sample: among the piece's triangles whose bounding box of integer "
        "cells (floor of the vertex extremes) holds the sample, the one with the largest min(w0, "
        "w1, w2) at the sample centre (x + 0.5, y + 0.5), w0 = edge(b, c, p) / area, w1 = edge(c, "
        "a, p) / area, w2 = 1 - w0 - w1 (the first on ties), and with the negative weights set to "
        "0 and the rest renormalized: bt = the weighted t, bv = the weighted across. Brush "
        "(texture role params.brush.role, Hb x Wb, rows across, columns along t): fu = bt Wb - "
        "0.5, fv = clip(bv, 0, 1) Hb - 0.5, i = floor(fu), j = floor(fv), a_u = fu - i, a_v = fv "
        "- j, columns i, i + 1 wrapped modulo Wb (params.brush.wrap_t) or clamped to [0, Wb - 1], "
        "rows j, j + 1 clamped; value = sum over the two rows of (1 - a_u) w_r tex[row][i] + a_u "
        "w_r tex[row][i + 1] (w_r = 1 - a_v, a_v). a = coverage * params.opacity * value; per "
        "sample A = A + a (1 - A), pieces in their order (A starts at 0)."
    ),
    "tamiss-composite": (
        "params.show 'color': the ink A over the paper, as tam-composite: a = clip(A, 0, 1); "
        "under = (paper, 1) on covered samples (tri_id >= 0) when params.paper is not null "
        "(clipped to [0, 1], rounded to float32), else (0, 0, 0, 0); k = a_under (1 - a), alpha = "
        "a + k, rgb = clip((params.ink a + under_rgb k) / alpha, 0, 1) where alpha > 0, else 0 "
        "(float64, stored as float32). The other views replace params.ink by a colour per sample: "
        "'ids': A = 1 and the colour of the first fragment gathered at the sample (0 where none); "
        "'strokes' and 'levels': the pieces of 'color' rasterized with the solid brush (value 1) "
        "and opacity 1, each with a colour c_p, premultiplied rgb = c_p a + rgb (1 - a) alongside "
        "A, colour = rgb / A where A > 0 (else 0); 'fits': likewise, the pieces of the extent "
        "'range' of the drawn strokes with params.width replaced by 1 (the width factor kept), no "
        "taper, no wobble, no end jitter. Colours: 'levels': "
        "params.constants.level_colors[min(lev, 6)] with lev = (id >> 47) & 15 the birth level; "
        "otherwise the id's colour: h = 6 hash01(id, 11), per channel c = 0, 1, 2: k = ((5, 3, "
        "1)[c] + h) mod 6 (a float modulo), colour[c] = 0.7 (1 - 0.9 clip(min(k, 4 - k), 0, 1)) "
        "(linear RGB)."
    ),
}

_ALWAYS = (
    "tamiss-inputs",
    "tamiss-field",
    "tamiss-fit",
    "tamiss-extent",
    "tamiss-extrude",
    "tamiss-raster",
    "tamiss-composite",
)


def derived(style: Any, scene: Any, *, width: int, height: int, spp: int) -> dict[str, str]:
    """The derived texts of a ``tamiss`` case: the pipeline's stages, with the aggregation the
    case uses."""
    hashed = style.pipeline_params.aggregation == "hashed"
    names = {*_ALWAYS, "tamiss-aggregate-hashed" if hashed else "tamiss-aggregate"}
    return {k: v for k, v in DERIVED.items() if k in names}


def chart_vertices(scene: Any, style: str) -> Iterator[tuple]:
    """Per object of ``scene``: its index, vertex tangent frames (V, 3, 2) float64, chart per
    vertex (V,) int64, :class:`~refnpr.styles.tamiss.charts.ChartLayout` and the number of its
    first chart over the scene; an object without uv is an error naming ``style``."""
    for k, mesh, labels, c_off in chart_meshes(scene):
        if mesh.uv is None:
            raise ValueError(
                f"scene: object {k} ({mesh.name!r}) has no uv; the {style} style needs uv (the "
                "hatching direction)"
            )
        v_chart = np.zeros(mesh.positions.shape[0], dtype=np.int64)
        v_chart[np.asarray(mesh.faces, dtype=np.int64).ravel()] = np.repeat(labels, 3)
        yield k, vertex_frames(mesh), v_chart, chart_layout(mesh, labels), c_off


def vertex_data(scene: Any) -> dict[int, dict[str, np.ndarray]]:
    """Per object index: the per-vertex TAMISS attributes (see the module docstring).

    Parameters
    ----------
    scene : refnpr.scenes.Scene

    Returns
    -------
    dict
        ``{object_index: {name: (V, C) float32 array}}`` with names tamiss_frame_u,
        tamiss_frame_v, tamiss_frame_u_lo, tamiss_frame_v_lo, tamiss_chart, tamiss_chart_map,
        tamiss_chart_offset, tamiss_chart_group.
    """
    out: dict[int, dict[str, np.ndarray]] = {}
    for k, frames, v_chart, layout, c_off in chart_vertices(scene, "tamiss"):
        hi_u = frames[:, :, 0].astype(np.float32)
        hi_v = frames[:, :, 1].astype(np.float32)
        out[k] = {
            "tamiss_frame_u": hi_u,
            "tamiss_frame_v": hi_v,
            "tamiss_frame_u_lo": (frames[:, :, 0] - hi_u).astype(np.float32),
            "tamiss_frame_v_lo": (frames[:, :, 1] - hi_v).astype(np.float32),
            "tamiss_chart": (v_chart + c_off).astype(np.float32),
            "tamiss_chart_map": SYMMETRIES[layout.symmetry[v_chart]]
            .reshape(-1, 4)
            .astype(np.float32),
            "tamiss_chart_offset": layout.offset[v_chart].astype(np.float32),
            "tamiss_chart_group": (layout.group[v_chart] + c_off).astype(np.float32),
        }
        if np.any(out[k]["tamiss_chart_offset"] != layout.offset[v_chart]):
            raise ValueError(
                f"scene: object {k}: chart offsets {layout.offset} are not exact in float32"
            )
    return out


def _constants() -> dict[str, Any]:
    return {
        "KX": [int(v) for v in F.KX],
        "rows_per_cell": F.N_ROWS,
        "cell_bits": 22,
        "cell_offset": 1 << 21,
        "salt_tone": F.SALT_TONE,
        "salt_length": F.SALT_LENGTH,
        "salt_width": F.SALT_WIDTH,
        "salt_wobble_amp": ST.SALT_WOBBLE_AMP,
        "salt_wobble_phase": ST.SALT_WOBBLE_PHASE,
        "salt_end_a": ST.SALT_END_A,
        "salt_end_b": ST.SALT_END_B,
        "salt_rgb": [11, 12, 13],
        "splitmix64": ["0x9E3779B97F4A7C15", "0xBF58476D1CE4E5B9", "0x94D049BB133111EB"],
        "level_colors": LEVEL_COLORS.tolist(),
    }


def export(
    style: Any, scene: Any, case_dir: Path, *, width: int, height: int, spp: int
) -> StyleExport:
    """Resolved params, the brush texture and per-vertex chart data of a ``tamiss`` style.

    Parameters
    ----------
    style : TamissStyle
        (a ``contoured`` wrapper is unwrapped by :func:`refnpr.kit.styles.export_style`)
    scene : refnpr.scenes.Scene
    case_dir : Path
        The case directory; the brush goes to ``case_dir/textures/brush/``.
    width, height, spp : int
        The case's image size and samples per pixel (unused: nothing depends on them).

    Returns
    -------
    StyleExport
    """
    if getattr(style, "name", None) != "tamiss":
        raise TypeError(f"style: expected a tamiss style, got {type(style).__name__}")
    if style.base is not None:
        raise ValueError(
            "style: base is set; the kit exports the tamiss style without a base style only "
            f"(got base={style.base.name!r})"
        )
    p = style.pipeline_params
    threshold = (
        p.visibility_threshold
        if p.visibility_threshold is not None
        else 0.5 / (1.0 + p.prior_weight)
    )
    tex, wrap = brush_texture(p.brush)
    resolved = PARAMS.resolved(
        p.values,
        visibility_threshold=float(threshold),
        brush={"name": p.brush or "solid", "role": "brush", "wrap_t": bool(wrap)},
        constants=_constants(),
    )
    params = jsonable(resolved, where="style 'tamiss' params")
    textures = {
        "brush": write_texture_levels(
            Path(case_dir),
            "brush",
            [np.asarray(tex, dtype=np.float32)],
            encoding="linear",
            wrap="repeat" if wrap else "clamp",
            filter="linear",
            orientation=ORIENTATION_ROW0_TOP
            + "; rows = across the stroke (row 0 at the left edge, v = 0), columns = along t "
            "(u = t); texel centres at (i + 0.5) / size",
            used_for="tamiss brush: alpha multiplier of each stroke sample (bilinear)",
        )
    }
    return StyleExport(
        params=params,
        textures=textures,
        derived=derived(style, scene, width=width, height=height, spp=spp),
        vertex_attributes=vertex_data(scene),
    )

"""Kit export of the ``threshold`` style (Veryovka 2002): every parameter resolved, every table
and texture the style samples written as files (interface A of the conformance kit).

What a backend receives, beyond every parameter of the style's declaration
(:data:`refnpr.styles.threshold.params.PARAMS`, in its order, None as null; ``pyramid``, a
Python object, left out; the deprecated ``scale`` after ``tone_fade``):

- ``uv_scales``: per object index ``[su, sv]`` multiplying uv (the style's ``uv_scale`` or the
  material's, times the deprecated ``scale``), as :meth:`ThresholdStyle.uv_scales` resolves it.
- ``channel_scale``: whether single unfiltered lines read eq. 5 from the G-buffer's
  ``dyadic_scale`` channel (rasterized with ``raster_options.line_period``) minus log2(sv).
- source "image": ``object_textures`` (per object index the role of its threshold pyramid, or
  null for the constant ``t``) and, per role ``threshold_<g>``, every mip level of the pyramid
  the style built (CLAHE per level, rank-equalized, as :class:`PyramidCache` makes it); with
  ``tone_correct`` the role ``tone_map_<g>``: one row per level of 1025 interpolant quantiles
  (``ToneMaps``), applied as ``np.interp(t, q, linspace(0, 1, 1025))``.
- several line directions: ``layer_schedule`` (``lam`` and ``levels`` of
  :func:`refnpr.formulas.threshold.layer_schedule`, the water-filling breakpoints).
- source "stipple" with ``uniform``: the role ``stipple_tone``, the (n_t * n_t, n_y) CDF table of
  :func:`stipple_tone_table` (row ``a * n_t + b`` for (t_u, t_v) = (a, b) / (n_t - 1)).
- ``bump``: the role ``bump`` with the box-filtered height pyramid.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from refnpr.formulas import threshold as thr
from refnpr.kit.textures import write_pyramid, write_table
from refnpr.styles.threshold.shading import uv_scale_table

from ._export import StyleExport

__all__ = ["export", "derived", "unresolved"]

#: Shared definitions of the texts below.
_TN = (
    "T_n(x, t) = min(floor(x n) + (1 if x n - floor(x n) >= t else 0), ceil(x n)) / n with "
    "n = params.n (Veryovka eq. 4, bounded by ceil(x n) / n)"
)
_FRAC = "Frac(x) = x - floor(x), at most the largest float64 below 1"
_SPLITMIX = (
    "uint64 arithmetic modulo 2^64 with M1 = 0x9E3779B97F4A7C15, M2 = 0xBF58476D1CE4E5B9, "
    "M3 = 0x94D049BB133111EB"
)
_MIX = "mix(h): h ^= h >> 30; h *= M2; h ^= h >> 27; h *= M3; h ^= h >> 31"
_OFFSETS = (
    "k = sqrt(params.samples) and the k x k footprint offsets (o_x, o_y) = (((a + 0.5) / k - "
    "0.5) / n_s, ((b + 0.5) / k - 0.5) / n_s) image pixels, n_s = params.spp_n, for j = b k + "
    "a (b outer, a inner)"
)

#: The texts of every threshold case.
SHADING = (
    "Per covered sample (mesh_id >= 0; m = objects[mesh_id].material, o = mesh_id), in "
    "float64: uv' = uv * params.uv_scales[o] and duv_dx' = duv_dx * params.uv_scales[o], "
    "duv_dy' likewise (per component; the derivatives stay per IMAGE pixel: a sample's "
    "footprint is 1 / n_s of them per axis, n_s = params.spp_n = sqrt(spp)). N = the normal "
    "channel as stored (or the bumped normal of threshold_bump), P = the position channel, V = "
    "normalize(camera.eye - P), normalize(v) = v / |v| (zero stays zero). rgb = m.ambient * "
    "ambient; for each light i in the order of case.lights, with L = lights[i].direction "
    "(directional) or normalize(lights[i].position - P) (point): f_d = min(max(normalize(N) . "
    "L, 0), 1), rgb += m.diffuse * (f_d + st(f_d) (T(f_d) - f_d)) * lights[i].color; then, "
    "when params.specular: f_s = max(N . normalize(L + V), 0)^m.shininess where N . L > 0 and "
    "m.shininess > 0, else 0 (Blinn-Phong; N not renormalized, base not clamped above), rgb "
    "+= m.specular * (f_s + st(f_s) (T_s(f_s) - f_s)) * lights[i].color (Veryovka eqs. 1-2 "
    "with the strength blend of sec. 5). Output (clip(rgb, 0, 1), 1); empty samples (0, 0, "
    "0, 0). Strength: st(x) = params.strength * s_o * s_i(x), s_o = 1 - params.facing_fade "
    "|N . V|^params.facing_power (1 when facing_fade = 0), s_i(x) = S(x / dark) * S((1 - x) / "
    "bright) with [dark, bright] = params.tone_fade, a factor left out (1) where its width is "
    "0, S(y) = c^2 (3 - 2 c), c = clip(y, 0, 1). " + _TN + ". T is the case's thresholding "
    '(the threshold_* texts); T_s = T when params.specular_threshold is "texture" (the same '
    "thresholds of the sample), else T_s(x) = T_n(x, params.specular_threshold) whatever the "
    "filter."
)
CONSTANT = "Source 'constant': T(x) = T_n(x, params.t) (the toon step)."
IMAGE = (
    "Source 'image' (Veryovka sec. 3.1): object o samples the threshold pyramid of the "
    "texture role params.object_textures[o] (null: T(x) = T_n(x, params.t), no texture), its "
    "levels 0 .. M - 1 as exported (level 0 W0 x H0 texels; do not regenerate them). LOD from "
    "the PER-PIXEL derivatives (not divided by n_s, whatever the filter): rho = "
    "max(hypot(du'/dx W0, dv'/dx H0), hypot(du'/dy W0, dv'/dy H0)), lambda = log2(max(rho, "
    "2^-64)) + params.lod_bias, clamped to [0, M - 1]; k0 = floor(lambda), k1 = min(k0 + 1, M "
    "- 1), f = lambda - k0. B_k(u, v) = GL_LINEAR / GL_REPEAT sample of level k (cols x rows): "
    "x = (u - floor(u)) cols - 0.5, y = (v - floor(v)) rows - 0.5, i = floor(x), j = "
    "floor(y), f_x = x - i, f_y = y - j, columns i, i + 1 and rows j, j + 1 taken modulo "
    "cols / rows, B = (1 - f_x)(1 - f_y) t[j][i] + f_x (1 - f_y) t[j][i+1] + (1 - f_x) f_y "
    "t[j+1][i] + f_x f_y t[j+1][i+1] (summed in that order). With params.tone_correct every "
    "B_k is first mapped through row k of the texture role params.tone_maps[o] (1025 "
    "quantiles q): B' = interp(B, q, linspace(0, 1, 1025)) (piecewise linear, clamped to 0 "
    "and 1 outside [q_0, q_1024]; a row with q_1024 <= q_0 maps to 0.5). The threshold at a "
    "position is the trilinear one, (1 - f) B_k0 + f B_k1. Filter 'none': T(x) = T_n(x, t) "
    "with t the threshold at uv'."
)
IMAGE_PCF = (
    "Filter 'pcf' on source 'image' (Veryovka sec. 4): with " + _OFFSETS + ", K = k^2 "
    "positions uv'_j = uv' + o_x duv_dx' + o_y duv_dy', all at the sample's lambda. "
    "params.mip 'per_level': 2 K thresholds, B_k0 at each uv'_j with weight (1 - f) / K and "
    "B_k1 at each uv'_j with weight f / K (tone-corrected B' with params.tone_correct); "
    "params.mip 'trilinear': the K trilinear thresholds, weight 1 / K each. T(x) = (sum_j w_j "
    "T_n(x, t_j)) / (sum_j w_j), both sums over j in order (B_k0 terms first). Objects "
    "without a texture: every t_j = params.t."
)
LINES = (
    "Source 'lines' (Veryovka sec. 3.2): per hatching layer d, a_d = radians("
    "params.directions[d]), v_d = -u' sin a_d + v' cos a_d, dv_d/dx = -du'/dx sin a_d + "
    "dv'/dx cos a_d, dv_d/dy likewise (per image pixel). Eq. 5: s = -(log2(max(hypot(dv_d/dx, "
    "dv_d/dy), 2^-1022)) + log2(params.period))"
)
LINES_CHANNEL = (
    "; here params.channel_scale is true: s = the dyadic_scale channel (rasterized with "
    "raster_options.line_period = params.period) - log2(params.uv_scales[o][1]) instead"
)
LINES_REST = (
    "; s = floor(s) when params.multiscale is false. Line function (eqs. 6-8): K = "
    "clip(floor(s), -1100, 1100), p = v 2^K (an exact product; 0 where it overflows), r = "
    "Frac(p), t = s - floor(s); paper's blend (params.uniform false): r1 = 2 r if r < 0.5 "
    "else 2 r - 1, F = (1 - t) r + t r1; params.uniform true, the paper's F composed with its "
    "own CDF G(y, t) (G = y / (1 + t) below (1 - t) / 2, (2 y - (1 - t) / 2) / (1 + t) up to "
    "(1 + t) / 2, (y + t) / (1 + t) above), i.e. with a = (1 - t) / (2 (1 + t)), b = 1 - a: F "
    "= r if r < a, 2 r - a if r < 0.5, 2 r - b if r < b, else r; F is then clamped to [0, "
    "largest float64 below 1]. " + _FRAC + "."
)
LINES_NONE = (
    " Filter 'none': one threshold per sample, t = F(v_d, s) (several layers: combined as "
    "threshold_layers says); T(x) = T_n(x, t)."
)
LINES_PCF = (
    " Filter 'pcf' (Veryovka sec. 4): with " + _OFFSETS + ", K = k^2 thresholds t_j = "
    "F(v_d + o_x dv_d/dx + o_y dv_d/dy, s) (s and the noise held at the sample centre; "
    "several layers combined per j); T(x) = (sum_j T_n(x, t_j)) / K, summed over j in order."
)
NOISE = (
    "Line noise (sec. 3.2: the lines' phase modulated), params.noise != 0: per sample z_s = "
    "params.noise * N(params.noise_scale u', params.noise_scale v') (u', v' the scaled uv of "
    "the sample centre), N the two-octave value noise in [-1, 1]: N(p) = ((O(p, e) + 0.5 O(2 "
    "p + 17, e + 1)) / 1.5) * 2 - 1 with e = params.noise_seed. O(p, e): (i, j) = "
    "(floor(p_x), floor(p_y)) as int64, (f_x, f_y) = (p_x - i, p_y - j), w_x = fade(f_x), w_y "
    "= fade(f_y), fade(x) = x * x * x * (x * (6 x - 15) + 10); h00 = H(i, j), h10 = H(i + 1, "
    "j), h01 = H(i, j + 1), h11 = H(i + 1, j + 1); top = h00 + w_x (h10 - h00), bottom = h01 + "
    "w_x (h11 - h01), O = top + w_y (bottom - top) (so O is in [0, 1)). H(i, j), in "
    + _SPLITMIX
    + " (i, j as two's-complement 64-bit): h = i * M1; h ^= j * M2 + (e & 0xFFFFFFFF) * M3 "
    "(the sum first); h ^= h >> 30; h *= M2; h ^= h >> 27; h *= M3; h ^= h >> 31; H = (h >> "
    "11) / 2^53. Filters 'none' and 'pcf': F is replaced by Frac(F + z_s) in every layer. "
    "Filter 'analytic': the phase z = Frac(z_s) is held over the footprint (threshold_analytic)."
)
LAYERS = (
    "Several directions (cross-hatching): the layers combine as the union of their dark "
    "lines, tone preserving, under the water-filling schedule params.layer_schedule = {lam: "
    "(B,), levels: (B, D)} (D layers): lam[b] is the total darkness Lambda = -ln(x) at "
    "breakpoint b (lam[0] = 0, increasing), levels[b][d] the darkness -ln(w_d) of layer d there "
    "(the row sums to lam[b]); between breakpoints each layer's darkness is piecewise linear in "
    "Lambda, and past the last breakpoint every layer gains 1 / D per unit of Lambda. (Layer d "
    "appears below the intensity params.onsets_resolved[d]; each increment of darkness goes to "
    "the active layers of least darkness.) White fraction of layer d at intensity x: c = "
    "clip(x, 0, 1), Lambda = -ln(c) (+inf at c = 0), lambda_d = interp(Lambda, lam, "
    "levels[:, d]) (piecewise linear, held constant outside [lam[0], lam[B - 1]]), and where "
    "Lambda > lam[B - 1]: lambda_d = levels[B - 1][d] + (Lambda - lam[B - 1]) / D; w_d(x) = "
    "exp(-lambda_d). Combined threshold (filters 'none' and 'pcf') of the layer values F_d: "
    "q_d = -ln(clip(F_d, 0, 1)) (+inf at 0); c_d = the number of b with levels[b][d] <= q_d; "
    "if c_d = B: Lambda*_d = lam[B - 1] + (q_d - levels[B - 1][d]) D; else hi = min(max(c_d, "
    "1), B - 1) (hi = 0 when B = 1), lo = max(hi - 1, 0), Lambda*_d = lam[lo] + (q_d - "
    "levels[lo][d]) (lam[hi] - lam[lo]) / g with g = levels[hi][d] - levels[lo][d] (g <= 0: "
    "g = 1); t = exp(-min_d Lambda*_d), clamped to [0, largest float64 below 1] (black where "
    "x < t: black where any layer is black)."
)
ANALYTIC = (
    "Filter 'analytic' (Veryovka sec. 4, the exact box filter of the thresholded lines over the "
    "SAMPLE's square footprint): T(x) = min(floor(x n) + C, ceil(x n)) / n (n = params.n), with r "
    "= x n - floor(x n) and C = 1 if r >= 1, else clip(prod_d C_d(w_d), 0, 1), w_d = w_d(r) of "
    "threshold_layers (one layer: w = r). C_d(y) is the fraction of the footprint where layer d "
    "is white, F_d <= y, with v linear over it and s held: v(X, Y) = v_d + X g_x + Y g_y for (X, "
    "Y) uniform on [-1/2, 1/2]^2, (g_x, g_y) = (dv_d/dx, dv_d/dy) / n_s (the per-pixel "
    "derivatives divided by n_s; s is the per-pixel scale). In line periods: K = clip(floor(s), "
    "-1100, 1100), t = s - floor(s), u0 = Frac(v_d 2^K) (0 where the product overflows), a = "
    "max(|g_x|, |g_y|) 2^K, b = min(|g_x|, |g_y|) 2^K; u = u0 + a X + b Y has a trapezoid density "
    "(a box of width a convolved with a box of width b: the square footprint projected on v). The "
    "white set of one period is a union of intervals [c_i, c_i + l_i]: paper's F: [0, clip(y / (1 "
    "+ t), 0, 1/2)] and [1/2, 1/2 + clip((y + t) / (1 + t) - 1/2, 0, 1/2)]; params.uniform, with "
    "ca = (1 - t) / (2 (1 + t)), cb = 1 - ca: [0, clip(y, 0, ca)], [ca, ca + clip((y - ca) / 2, "
    "0, 1/2 - ca)], [1/2, 1/2 + clip((y + cb) / 2 - 1/2, 0, cb - 1/2)], [cb, cb + clip(y - cb, 0, "
    "1 - cb)]. C_d(y) = sum_i E[1{Frac(u - c_i) < l_i}], each term the exact integral of the "
    "periodic pulse train against the trapezoid: for b > 0, l + (D(z + (a + b) / 2) - D(z + (a - "
    "b) / 2) - D(z - (a - b) / 2) + D(z - (a + b) / 2)) / (a b) with z = u0 - c_i, l = l_i, D(x) "
    "= m - l f^2 / 2 - l (1 - l) f / 2, f = Frac(x), m = f^2 / 2 if f <= l else l f - l^2 / 2 "
    "(exact for b >= 1; for 0 < b < 1 the same integral without cancellation: (l (a - b) + J(z + "
    "(a - b) / 2) - J(z - (a - b) / 2)) / a + (R(z - (a + b) / 2, 1) + R(z + (a + b) / 2, -1)) / "
    "(a b) with J(x) = min(Frac(x), l) - l Frac(x) and R(z0, sg) = the sum over the integers m of "
    "(h - g)(h + g) / 2, [g, h] the part in [0, b] of the w with z0 + sg w in [m, m + l]); for b "
    "= 0 the box of width a, l + (J(z + a / 2) - J(z - a / 2)) / a. Limits: a < 1e-100: the point "
    "sample 1{F(u0, t) <= y}; a >= 1e15 (or not finite): the tone sum_i l_i; b < 1e-200: b = 0. "
    "C_d(y) = 1 for y >= 1, 0 for y < 0, else clipped to [0, 1]. With line noise (params.noise != "
    "0, z = Frac(z_s)): C_d(y) is replaced by C_d(y - z) + C_d(y + 1 - z) - C_d(1 - z)."
)
STIPPLE = (
    "Source 'stipple' (Veryovka Fig. 4 with screen-round, jittered dots): per texture axis "
    "eq. 5, s_u = -(log2(max(hypot(du'/dx, du'/dy), 2^-1022)) + log2(params.period)) and s_v "
    "likewise from dv'/dx, dv'/dy (per image pixel), floored when params.multiscale is false; "
    "k_u = clip(floor(s_u), -1100, 1100), t_u = s_u - floor(s_u) (v alike), A_u = 2^t_u, A_v = "
    "2^t_v. F(u, v) = sum over (b_u, b_v) in the order (0, 0), (0, 1), (1, 0), (1, 1) of "
    "(W(b_u, t_u) W(b_v, t_v)) Dot(u, v; k_u + b_u, k_v + b_v, A_u / (1 + b_u), A_v / (1 + "
    "b_v)), W(0, t) = 1 - t, W(1, t) = t. Dot(u, v; K_u, K_v, a_u, a_v): V = v 2^K_v, j = "
    "floor(V + 0.5), dv = V - j, v_row = j 2^-K_v (powers of two exact); phase = U(mix(bits("
    "v_row) M1 + e M3)) if params.jitter > 0 else 0; Uu = (u - phase) 2^K_u, i = floor(Uu + "
    "0.5), du = Uu - i; offsets o_u = o_v = 0, or with params.jitter > 0: h = mix(bits(v_row) "
    "M1 + e M3 + 1), h = mix(h XOR (bits(i 2^-K_u) M2)), g = mix(h + M1), o_u = params.jitter "
    "(2 U(h) - 1), o_v = params.jitter (2 U(g) - 1); r = hypot((du - o_u) a_u, (dv - o_v) "
    "a_v); area = Q(r, xl, yl) + Q(r, xr, yl) + Q(r, xl, yr) + Q(r, xr, yr) with xl = (0.5 + "
    "o_u) a_u, xr = (0.5 - o_u) a_u, yl = (0.5 + o_v) a_v, yr = (0.5 - o_v) a_v; Dot = clip(1 - "
    "area / (a_u a_v), 0, 1). Q(r, X, Y), the area of {0 <= x <= X, 0 <= y <= Y, x^2 + y^2 <= "
    "r^2}: m = min(X, r), xc = min(sqrt(max(r^2 - Y^2, 0)), m), Q = Y xc + P(m) - P(xc), P(x) = "
    "(x R + r^2 atan2(x, R)) / 2 with R = sqrt(max(r^2 - x^2, 0)). Hashes in "
    + _SPLITMIX
    + "; e = params.noise_seed & 0xFFFFFFFF; bits(x) = the IEEE-754 bits of the float64 x + "
    "0.0 (-0 folded onto +0) as a uint64; " + _MIX + "; U(h) = (h >> 11) / 2^53. Without "
    "params.uniform the threshold is clip(F, 0, 1)."
)
STIPPLE_UNIFORM = (
    " With params.uniform, F is mapped through the tone CDF table (texture role "
    "params.stipple_tone, params.stipple_tone_shape = [n_t, n_t, n_y], cdf[a][b][i] stored as "
    "row a n_t + b, column i): split(x, N) = (i, f) with c = clip(x, 0, 1) N, i = clip(floor(c), "
    "0, N - 1), f = c - i; (a, f_a) = split(t_u, n_t - 1), (b, f_b) = split(t_v, n_t - 1), (i, "
    "f_i) = split(F, n_y - 1); F' = sum over (da, db) in the order (0, 0), (0, 1), (1, 0), (1, "
    "1) of W(da, f_a) W(db, f_b) (cdf[a + da][b + db][i] (1 - f_i) + cdf[a + da][b + db][i + 1] "
    "f_i); the threshold is clip(F', 0, 1)."
)
STIPPLE_NONE = " Filter 'none': t = the threshold at (u', v'); T(x) = T_n(x, t)."
STIPPLE_PCF = (
    " Filter 'pcf' (Veryovka sec. 4): with " + _OFFSETS + ", K = k^2 thresholds at uv'_j = "
    "uv' + o_x duv_dx' + o_y duv_dy' (s_u, s_v held at the sample centre); T(x) = (sum_j "
    "T_n(x, t_j)) / K, summed over j in order."
)
BUMP = (
    "Bump mapping (Veryovka Fig. 2, params.bump = the texture role 'bump': the box-filtered "
    "height pyramid of params.bump_source, levels 0 .. M - 1 as exported, level 0 W0 x H0, "
    "GL_REPEAT): h(uv) = params.bump_height * ((1 - f) B_k0(uv) + f B_k1(uv)) (the second term "
    "only where f > 0) with B_k the GL_LINEAR / GL_REPEAT level sample (as threshold_image "
    "defines it) and lambda_b = log2(max(rho, 1e-12)) clamped to [0, M - 1], k0 = "
    "floor(lambda_b), k1 = min(k0 + 1, M - 1), f = lambda_b - k0, rho = max(hypot(du'/dx W0, "
    "dv'/dx H0), hypot(du'/dy W0, dv'/dy H0)) (per-pixel uv' derivatives, no lod_bias). Height "
    "derivatives per image pixel by central differences over half a pixel, all at the same "
    "lambda_b: dh/dx = h(uv' + duv_dx' / 2) - h(uv' - duv_dx' / 2), dh/dy = h(uv' + duv_dy' / "
    "2) - h(uv' - duv_dy' / 2). Surface-gradient perturbation (Mikkelsen 2010) with n = the "
    "normal channel, s_x = dposition_dx, s_y = dposition_dy (per image pixel): R1 = cross(s_y, "
    "n), R2 = cross(n, s_x), det = s_x . R1, n' = |det| n - sign(det) (dh/dx R1 + dh/dy R2) "
    "(sign(0) = 0), normalized (n' = n where its length is 0). n' replaces the normal channel "
    "everywhere in threshold_shading (f_d, f_s and the facing fade)."
)


def derived(style: Any, scene: Any, *, width: int, height: int, spp: int) -> dict[str, str]:
    """The derived texts of a ``threshold`` case: the shading, and a paragraph for each part
    the case uses (its source, noise, layers, filter, bump), none for the parts it does not.

    Parameters
    ----------
    style : refnpr.styles.threshold.ThresholdStyle
    scene : refnpr.scenes.Scene
    width, height, spp : int
        The case's image size and samples per pixel (the texts name params.spp_n for them).

    Returns
    -------
    dict
        name -> paragraph.
    """
    p = style.p
    out = {"threshold_shading": SHADING}
    if p.source == "constant":
        out["threshold_constant"] = CONSTANT
    elif p.source == "image":
        out["threshold_image"] = IMAGE
        if p.filter == "pcf":
            out["threshold_pcf"] = IMAGE_PCF
    elif p.source == "lines":
        text = LINES + (LINES_CHANNEL if style._channel_scale() else "") + LINES_REST
        if p.filter == "none":
            text += LINES_NONE
        elif p.filter == "pcf":
            text += LINES_PCF
        out["threshold_lines"] = text
        if p.noise != 0.0:
            out["threshold_noise"] = NOISE
        if len(p.directions) > 1:
            out["threshold_layers"] = LAYERS
        if p.filter == "analytic":
            out["threshold_analytic"] = ANALYTIC
    elif p.source == "stipple":
        text = STIPPLE + (STIPPLE_UNIFORM if p.uniform else "")
        out["threshold_stipple"] = text + (STIPPLE_PCF if p.filter == "pcf" else STIPPLE_NONE)
    if p.bump is not None:
        out["threshold_bump"] = BUMP
    return out


def _params(style: Any) -> dict[str, Any]:
    """Every declared parameter (None as null) but the Python-only ``pyramid``, the deprecated
    ``scale`` after ``uv_scale`` (both shown, as params() shows them)."""
    out = {}
    for name, value in style.p.as_dict(keep_none=True).items():
        if name != "pyramid":
            out[name] = value
        if name == "uv_scale":
            out["scale"] = style.scale
    return out


def _image_textures(style: Any, scene: Any, case_dir: Path, params: dict, textures: dict) -> None:
    """Threshold pyramids (and tone maps) per distinct texture, as the style groups objects
    (refnpr/styles/threshold/style.py ``image_thresholds``)."""
    p = style.p
    roles: dict[Any, str | None] = {}
    per_object = []
    for obj in scene.objects:
        tex = p.texture if p.texture is not None else obj.material.texture
        key = "<prebuilt>" if style.pyramid is not None else tex
        if key not in roles and key is None:
            roles[key] = None
        elif key not in roles:
            pyr = style.pyramid
            if pyr is None:
                pyr = style.pyramids.get(tex, p, tiling=p.tiling)
            g = sum(r is not None for r in roles.values())
            role = roles[key] = f"threshold_{g}"
            textures[role] = write_pyramid(
                case_dir,
                role,
                pyr.levels,
                filter=(
                    "per_level"
                    if (p.filter == "pcf" and p.mip == "per_level") or p.tone_correct
                    else "linear_mipmap_linear"
                ),
                used_for=(
                    f"threshold pyramid of {key!r} (clahe_levels={p.clahe_levels!r}), "
                    "sampled bilinearly at levels floor/ceil of the GL LOD"
                ),
            )
            if p.tone_correct:
                textures[f"tone_map_{g}"] = write_table(
                    case_dir,
                    f"tone_map_{g}",
                    np.stack(style.pyramids.tone_maps(pyr).quantiles),
                    orientation="row k = mip level k; column i = quantile i / 1024",
                    used_for=(
                        "tone_correct: per level, bilinear threshold t -> "
                        "interp(t, row k, linspace(0, 1, 1025)); a row with "
                        "q[-1] <= q[0] maps to 0.5"
                    ),
                )
        per_object.append(roles[key])
    params["object_textures"] = per_object
    params["tone_maps"] = [
        None if r is None or not p.tone_correct else r.replace("threshold_", "tone_map_")
        for r in per_object
    ]


def export(style: Any, scene: Any, case_dir: Path, *, width: int, height: int, spp: int):
    """Resolved parameters, textures and derivation notes of a ``threshold`` style for
    ``scene`` (what the module docstring lists)."""
    if getattr(style, "name", "") != "threshold":
        raise TypeError(
            f"style: expected a 'threshold' style, got {getattr(style, 'name', style)!r}"
        )
    case_dir = Path(case_dir)
    p = style.p
    params = _params(style)
    params["uv_scales"] = uv_scale_table(style, scene).tolist()  # as the kernel reads them
    params["channel_scale"] = bool(style._channel_scale())
    params["spp_n"] = int(round(math.sqrt(spp)))
    textures: dict[str, Any] = {}
    if p.source == "image":
        _image_textures(style, scene, case_dir, params, textures)
    if p.source == "lines":
        onsets = p.onsets if p.onsets is not None else (1.0,) * len(p.directions)
        params["onsets_resolved"] = [float(o) for o in onsets]
        lam, levels = thr.layer_schedule(onsets)
        params["layer_schedule"] = {"lam": lam.tolist(), "levels": levels.tolist()}
    if p.source == "stipple" and p.uniform:
        c = style.stipple_tone_table().cdf  # the style's own table
        textures["stipple_tone"] = write_table(
            case_dir,
            "stipple_tone",
            c.reshape(c.shape[0] * c.shape[1], c.shape[2]),
            orientation=(
                f"row a * {c.shape[0]} + b = (t_u, t_v) = (a, b) / {c.shape[0] - 1}; column i = "
                f"y = i / {c.shape[2] - 1}"
            ),
            used_for="uniform stipple: trilinear lookup of the tone CDF G(F | t_u, t_v)",
        )
        params["stipple_tone_shape"] = [int(s) for s in c.shape]
        params["stipple_tone"] = "stipple_tone"  # the texture role of the table
    if style._bump is not None:
        params["bump_source"] = params["bump"]  # the texture refnpr built the pyramid from
        params["bump"] = "bump"  # the texture role of the height pyramid
        textures["bump"] = write_pyramid(
            case_dir,
            "bump",
            style._bump.pyramid.levels,
            filter="linear_mipmap_linear",
            used_for=(
                "bump height pyramid (times bump_height), trilinear at the footprint's GL LOD, "
                "central differences over the pixel (derived texts: threshold_bump)"
            ),
        )
    size = {"width": width, "height": height, "spp": spp}
    return StyleExport(params=params, textures=textures, derived=derived(style, scene, **size))


def unresolved(params: dict[str, Any]) -> list[str]:
    """Key paths of exported params a backend could not use without refnpr: an image source
    whose textured objects lack a pyramid role, or missing resolved tables."""
    out = []
    if params.get("source") == "image" and "object_textures" not in params:
        out.append("object_textures")
    if params.get("source") == "lines" and "layer_schedule" not in params:
        out.append("layer_schedule")
    if "uv_scales" not in params:
        out.append("uv_scales")
    return out

"""The "derived" texts of case.json that every case shares: what a backend computes itself.

Each text is a specification to code from (formula, constants, order of operations, rounding);
none points at refnpr's source (``tests/kit/test_derived.py`` holds every case to that).
"""

from __future__ import annotations

from ..raster.gbuffer import BUILTIN_CHANNELS

__all__ = ["generic_derived", "channel_derived"]

_EMPTY0 = "0 where empty (tri_id < 0)."

_CHANNEL_HOW = {
    "depth": "w = 1 / Q of the visible triangle (= w_clip = -z_eye), Q = 1/w interpolated "
    "linearly in screen space from the exact (unsnapped) vertices; +inf where empty.",
    "ndc_z": "z_clip / w_clip of the visible fragment (z_clip interpolated perspective-"
    "correctly, divided by w), in float64; 1 where empty.",
    "tri_id": "objects[k].first_tri_id + the triangle's index in the .glb index buffer; -1 "
    "where empty (gl_PrimitiveID + first_tri_id of the drawn object).",
    "mesh_id": "objects[k].mesh_id of the visible triangle; -1 where empty.",
    "bary": "perspective-correct barycentrics b_i = lambda_i / Q of the triangle's three "
    "vertices in index order (lambda_i = l_i / w_i, l_i the screen-space barycentrics at the "
    "sample centre, Q = sum lambda_i), from the exact (unsnapped) clip-space vertices; " + _EMPTY0,
    "position": "world position sum_i b_i POSITION_i (b_i as the bary channel); " + _EMPTY0,
    "normal": "m = sum_i b_i NORMAL_i (NORMAL as stored, not renormalized per vertex), then "
    "m * (1 / |m|) per sample (0 where |m| = 0); 0 where empty. Not face-forwarded.",
    "uv": "sum_i b_i TEXCOORD_0_i (= _UV), as stored (no v flip); " + _EMPTY0,
    "duv_dx": "d(uv)/dx per IMAGE pixel, analytic: uv = P / Q with P = sum(lambda_i uv_i), "
    "Q = sum(lambda_i) affine in screen space, so duv/dx = (dP/dx - uv dQ/dx) / Q (quotient "
    "rule) with d/dx per image pixel = n times d/dx per sample-grid pixel, evaluated at the "
    "sample's own centre (see camera.conventions.derivatives); " + _EMPTY0,
    "duv_dy": "as duv_dx with y growing DOWN the image; " + _EMPTY0,
    "lod": "OpenGL 4.x sec. 8.14: rho = max(hypot(du/dx W_t, dv/dx H_t), hypot(du/dy W_t, "
    "dv/dy H_t)) with [W_t, H_t] = raster_options.texture_size and the derivatives as the "
    "duv_dx / duv_dy channels store them (rounded to raster_options.dtype), lod = "
    "log2(max(rho, 2^-64)); 0 where empty.",
    "dyadic_scale": "Veryovka eq. 5: s = clip(-log2(max(hypot(dv/dx, dv/dy), 2^-64)) - "
    "log2(w), -64, 64), (dv/dx, dv/dy) the derivatives per image pixel of the coordinate "
    "raster_options.dyadic_coord (v: the second uv component) as the duv_dx / duv_dy channels "
    "store them (rounded to raster_options.dtype), w = raster_options.line_period; so d = "
    "1 / |grad v| is the pixel distance between the iso-lines v and v + 1; 0 where empty.",
    "coverage": "per PIXEL (W x H, not per sample): k / n^2, k the number of the pixel's "
    "n x n samples with tri_id >= 0 (correctly rounded).",
    "dposition_dx": "d(position)/dx per image pixel by the quotient rule, like duv_dx; " + _EMPTY0,
    "dposition_dy": "d(position)/dy per image pixel (y down), like duv_dy; " + _EMPTY0,
}

#: The rasterization rules every case is rendered with (coverage, depth test, clipping).
RASTERIZATION = (
    "Vertex stage: clip = projection_matrix @ view_matrix @ (x, y, z, 1), each row summed "
    "((m0 x + m1 y) + m2 z) + m3 in float64 from the .glb's float32 POSITION. Clipping: a "
    "triangle with all three vertices outside one plane is dropped; one with a vertex outside "
    "any plane is clipped (Sutherland-Hodgman in homogeneous clip space, planes in the order "
    "near z + w >= 0, far w - z >= 0, then x and y against a guard band |x|, |y| <= G w with G "
    "= min(16, 2^31 / (512 max(n W, n H)) - 1); the intersection of an edge is computed from "
    "its lexicographically smaller (x, y, z, w) endpoint, so shared edges clip identically) "
    "and fan-triangulated from its first vertex; attributes still come from the whole "
    "triangle. Snap: each vertex's continuous IMAGE-pixel position x_px = (x/w + 1) W / 2, "
    "y_px = (1 - y/w) H / 2 (W, H the image size, NOT the n W x n H sample grid) is snapped to "
    "X = floor(256 x_px + 0.5), Y = floor(256 y_px + 0.5) (1/256 image pixel, round half up). "
    "Coverage, exact in 64-bit integers: with the sample grid's coordinates scaled by 512 n, "
    "sample (sx, sy) is at (512 sx + 256, 512 sy + 256) and a vertex at (2 n X, 2 n Y); "
    "triangles of zero snapped area are dropped (cull_backfaces is false: both faces are "
    "drawn); the vertex order is made clockwise on the y-down screen (vertices 1 and 2 "
    "swapped where the doubled signed area (X1 - X0)(Y2 - Y0) - (Y1 - Y0)(X2 - X0) is "
    "negative); each edge a -> b (1 -> 2, 2 -> 0, 0 -> 1) has E(p) = (b_x - a_x)(p_y - a_y) - "
    "(b_y - a_y)(p_x - a_x) and a sample is inside when E >= 0 on all three edges, except that "
    "E = 0 counts only on top-left edges (top-left rule: dy = b_y - a_y < 0, or dy = 0 and "
    "dx = b_x - a_x > 0). Depth test: Q = 1/w at the sample centre, a plane through the exact "
    "float64 clip-space vertices (not the snapped ones); a covered sample whose Q lies outside "
    "[(1 - 1e-6) / far, (1 + 1e-6) / near] is not covered (per-sample near/far clip); the "
    "visible triangle has the largest Q, strictly (on equal Q the lower triangle index, in "
    "tri_id order, stays). Interpolation uses the exact (unsnapped) vertices."
)


def generic_derived() -> dict[str, str]:
    """Texts every case carries: the sample grid, rasterization, compositing and resolve,
    lights."""
    return {
        "sample_grid": "Render the n W x n H sample grid (n = sqrt(spp)) with camera."
        "projection_matrix unchanged (aspect W / H); sample (sx, sy) of pixel (x, y) is grid "
        "pixel (n x + sx, n y + sy) at offset sample_positions[sy * n + sx] = ((sx + 0.5) / n, "
        "(sy + 0.5) / n) image pixels from the pixel's corner. Shade per sample.",
        "rasterization": RASTERIZATION,
        "composite_resolve": "Per sample, the style's straight-alpha output (rgb, a), stored "
        "as float32, then in float64: premultiplied (rgb a, a) + background premultiplied "
        "(bg_rgb bg_a, bg_a) times (1 - a); the n x n samples of each pixel summed sample row "
        "by sample row, left to right, divided by n^2; rgb / alpha where alpha > 0 (else 0); "
        "stored as float32. expected.exr holds that (linear, straight alpha); expected.png is "
        "rint(255 linear_to_srgb(clip(rgb, 0, 1))) and rint(255 clip(alpha, 0, 1)) (alpha stays "
        "linear; rint rounds half to even), with the IEC 61966-2-1 encoding linear_to_srgb(x) = "
        "12.92 x for x <= 0.0031308, else 1.055 x^(1/2.4) - 0.055.",
        "lights": "Shading uses lights[i].direction as given (unit, towards the light) for "
        "directional lights, normalize(position - surface position) for point lights; the view "
        "vector is normalize(camera.eye - surface position). Colours are linear RGB; the "
        "ambient term of every style is material.ambient * case.ambient, per channel.",
    }


def channel_derived(channels: list[str]) -> dict[str, str]:
    """``channel.<name>``: how to compute each G-buffer channel the case uses."""
    out = {}
    for ch in channels:
        desc = BUILTIN_CHANNELS.get(ch, (0, "a vertex attribute interpolated by name"))[1]
        how = _CHANNEL_HOW.get(
            ch,
            "the vertex attribute of that name (glTF _" + ch.upper() + ") interpolated "
            "perspective-correctly, sum_i b_i A_i (b_i as the bary channel); d<name>_dx/_dy by "
            "the quotient rule, like duv_dx; 0 where empty.",
        )
        out[f"channel.{ch}"] = f"{desc}. {how}"
    return out

"""The "derived" texts of case.json that every case shares: what a backend computes itself."""

from __future__ import annotations

from ..raster.gbuffer import BUILTIN_CHANNELS

__all__ = ["generic_derived", "channel_derived"]

_CHANNEL_HOW = {
    "depth": "w_clip of the visible fragment (= -z_eye), per sample; +inf where empty.",
    "ndc_z": "z_clip / w_clip of the visible fragment; 1 where empty.",
    "tri_id": "objects[k].first_tri_id + the triangle's index in the .glb index buffer; -1 "
    "where empty (gl_PrimitiveID + first_tri_id of the drawn object).",
    "mesh_id": "objects[k].mesh_id of the visible triangle; -1 where empty.",
    "bary": "perspective-correct barycentrics of the triangle's vertices in index order.",
    "position": "world position interpolated perspective-correctly (POSITION is world space).",
    "normal": "NORMAL interpolated perspective-correctly, then renormalized per sample; 0 where "
    "empty. Not face-forwarded.",
    "uv": "TEXCOORD_0 (= _UV) interpolated perspective-correctly, as stored (no v flip).",
    "duv_dx": "d(uv)/dx per IMAGE pixel, analytic: uv = P / Q with P = sum(l_i uv_i / w_i), "
    "Q = sum(l_i / w_i) affine in screen space, so duv/dx = (dP/dx - uv dQ/dx) / Q (quotient "
    "rule), evaluated at the sample's own position (see camera.conventions.derivatives).",
    "duv_dy": "as duv_dx with y growing DOWN the image.",
    "lod": "OpenGL 4.x sec. 8.14: rho = max(|duv_dx * size|, |duv_dy * size|) with size = "
    "raster_options.texture_size [W, H] texels, lod = log2(max(rho, 2^-64)).",
    "dyadic_scale": "Veryovka eq. 5: d = 1 / |grad v| (pixels between the iso-lines v and v+1, "
    "grad v = (dv/dx, dv/dy) per image pixel), s = log2(d / w), w = raster_options.line_period "
    "(default 1); raster_options.dyadic_coord names the coordinate (default v).",
    "coverage": "per PIXEL (W x H, not per sample): the fraction of the n x n samples covered.",
    "dposition_dx": "d(position)/dx per image pixel by the quotient rule, like duv_dx.",
    "dposition_dy": "d(position)/dy per image pixel (y down).",
}


def generic_derived() -> dict[str, str]:
    """Texts every case carries: the sample grid, compositing and resolve."""
    return {
        "sample_grid": "Render the n W x n H sample grid (n = sqrt(spp)) with camera."
        "projection_matrix unchanged (aspect W / H); sample (sx, sy) of pixel (x, y) is grid "
        "pixel (n x + sx, n y + sy) at offset sample_positions[sy * n + sx]. Shade per sample.",
        "composite_resolve": "Per sample: straight-alpha style output (rgb, a) -> premultiplied "
        "(rgb a, a) + background_premultiplied (1 - a); box mean over the n x n samples of each "
        "pixel; rgb / alpha where alpha > 0. expected.exr holds that (linear, straight alpha); "
        "expected.png is rint(255 linear_to_srgb(clip(rgb, 0, 1))) (IEC 61966-2-1; rint rounds "
        "half to even) and rint(255 clip(alpha, 0, 1)) (alpha stays linear).",
        "lights": "Shading uses lights[i].direction as given (unit, towards the light) for "
        "directional lights, normalize(position - surface position) for point lights; the view "
        "vector is normalize(camera.eye - surface position).",
    }


def channel_derived(channels: list[str]) -> dict[str, str]:
    """``channel.<name>``: how to compute each G-buffer channel the case uses."""
    out = {}
    for ch in channels:
        desc = BUILTIN_CHANNELS.get(ch, (0, "a vertex attribute interpolated by name"))[1]
        how = _CHANNEL_HOW.get(
            ch,
            "the vertex attribute of that name (glTF _" + ch.upper() + ") interpolated "
            "perspective-correctly; d<name>_dx/_dy by the quotient rule.",
        )
        out[f"channel.{ch}"] = f"{desc}. {how}"
    return out

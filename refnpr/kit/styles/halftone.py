"""Kit export of the ``halftone`` style (Freudenberg, Masuch, Strothotte 2002).

Every parameter is resolved by the style's own code for the case's scene: each object's screen
spec (:meth:`HalftoneStyle.object_specs`), the built screen (:meth:`HalftoneStyle.screen_for`:
engraving ramp, CLAHE dither pyramid or encoded stroke map, each with all its mip levels), the
uv scale actually used (object setting, else the style's, else the material's), the anisotropy
actually used (1 for an engraving ramp), the indication map and the tone-correction tables.

Params layout (``case.json`` ``style.params``)::

    threshold, c, c_mode ("constant" | "fwidth"), centred, specular, ink, paper, lod_bias,
    sample_lod, lod_offset (lod_bias - log2 n when sample_lod, else lod_bias), mip,
    tone_correct, anisotropy, show, luma,
    objects: [per scene object, in mesh_id order:
              {name, screen: {kind, role, normals_role, direction, source_spec},
               uv_scale, anisotropy, indication_role, indication_scale, equalize,
               tone_lut_role, per_level}]

``source_spec`` is informational (the normalized screen spec refnpr built the screen from); what
a backend samples is the texture ``role``.

Textures: ``screen-<i>`` (R, float32, one file per mip level), ``normals-<i>`` (RGB-encoded stroke
normal map, same levels), ``tone-lut-<i>`` ((L, 2048) CDF tables, one row per level),
``indication-<k>`` (the signed indication map of object k, clamp, bilinear).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from refnpr.formulas.lighting import LUMA_709

from .._json import jsonable
from ..textures import ORIENTATION_ROW0_V0, write_pyramid, write_table
from ._export import StyleExport

__all__ = ["export", "DERIVED"]

_BILINEAR = (
    "B_k(s) = the GL_LINEAR / GL_REPEAT sample of level k (cols_k x rows_k): x = (s_u - "
    "floor(s_u)) cols_k - 0.5, y = (s_v - floor(s_v)) rows_k - 0.5, i = floor(x), j = "
    "floor(y), f_x = x - i, f_y = y - j, columns i, i + 1 and rows j, j + 1 taken modulo "
    "cols_k / rows_k, weights (1 - f_x)(1 - f_y), f_x (1 - f_y), (1 - f_x) f_y, f_x f_y summed "
    "in that order"
)

DERIVED = {
    "halftone-intensity": (
        "Target intensity per covered sample of object o (mesh_id = o; m = objects[o].material of "
        "case.json), in float64 (Freudenberg sec. 3 with the lighting of Veryovka eq. 1): N = the "
        "normal channel, P = the position channel, L_i = lights[i].direction (directional) or "
        "normalize(lights[i].position - P) (point), V = normalize(camera.eye - P), normalize(v) = "
        "v / |v| (zero stays zero); f_d,i = min(max(normalize(N) . normalize(L_i), 0), 1); f_s,i "
        "= min(max(normalize(N) . normalize(normalize(L_i) + V), 0), 1)^m.shininess where "
        "normalize(N) . normalize(L_i) > 0 and m.shininess > 0, else 0 (Blinn-Phong). rgb = "
        "m.ambient * ambient, then for each light i in order rgb += m.diffuse f_d,i "
        "lights[i].color and, when params.specular, rgb += m.specular f_s,i lights[i].color; I = "
        "clip((rgb_r 0.2126 + rgb_g 0.7152) + rgb_b 0.0722, 0, 1) (Rec. 709, params.luma). Stroke "
        "lighting (sec. 5.2), for a screen with a normal map "
        "(params.objects[o].screen.normals_role not null): where the tangent frame is valid, "
        "f_d,i is replaced by clip(normalize(2 nm - 1) . normalize((L_i . T, L_i . B, L_i . N)), "
        "0, 1), nm the RGB of the normals role looked up exactly as the screen "
        "(halftone-screen-lookup: the same coordinates, LOD and probes; trilinear, never per "
        "level). Tangent frame from the UNSCALED uv derivatives (du/dx, dv/dx) = duv_dx, (du/dy, "
        "dv/dy) = duv_dy and N as stored: det = du/dx dv/dy - du/dy dv/dx, dP/du = (dP/dx dv/dy - "
        "dP/dy dv/dx) / det, dP/dv = (dP/dy du/dx - dP/dx du/dy) / det (dP/dx = dposition_dx, "
        "dP/dy = dposition_dy), T = normalize(dP/du - (dP/du . N) N), B = normalize(dP/dv - "
        "(dP/dv . N) N - (dP/dv . T) T) (Gram-Schmidt, T first); valid where |det| > 1e-20 and "
        "both lengths before normalizing > 1e-30. Indication map (sec. 5.1, "
        "params.objects[o].indication_role not null): I = clip(I + ind(u * "
        "params.objects[o].indication_scale[0], v * params.objects[o].indication_scale[1]), 0, 1) "
        "with (u, v) the UNSCALED uv and ind the bilinear clamp-to-edge lookup of that role (rows "
        "x cols, row 0 at v = 0): x = clip(u cols - 0.5, 0, cols - 1), y = clip(v rows - 0.5, 0, "
        "rows - 1), x0 = min(floor(x), cols - 1), x1 = min(x0 + 1, cols - 1), y0, y1 alike, f_x = "
        "x - x0, f_y = y - y0, ind = (t[y0][x0] (1 - f_x) + t[y0][x1] f_x) (1 - f_y) + (t[y1][x0] "
        "(1 - f_x) + t[y1][x1] f_x) f_y."
    ),
    "halftone-screen-lookup": (
        "Screen lookup of object o (texture role params.objects[o].screen.role, its levels 0 .. L "
        "- 1 as exported: do not regenerate them; level 0 cols x rows texels): s = (u su, v sv) "
        "with (su, sv) = params.objects[o].uv_scale, screen derivatives ds/dx = (du/dx su, dv/dx "
        "sv) and ds/dy = (du/dy su, dv/dy sv) from the duv_dx / duv_dy channels, per IMAGE pixel "
        "(NOT divided by n = params.samples_per_axis). Engraving screens "
        "(params.objects[o].screen.direction = (d_0, d_1) not null): s = (s . direction, 0.5), "
        "ds/dx = (ds/dx . direction, 0), ds/dy likewise. LOD (OpenGL 4.6 sec. 8.14): P_x = "
        "sqrt((ds_u/dx cols)^2 + (ds_v/dx rows)^2) (GLSL length), P_y likewise with d/dy; with A = "
        "params.objects[o].anisotropy: A = 1: lod = log2(max(max(P_x, P_y), 2^-64)), one probe at "
        "s; A > 1: probes q = min(max(ceil(P_max / max(P_min, 2^-64) - 1e-9), 1), A), lod = "
        "log2(max(P_max / q, 2^-64)), axis = ds/dx if P_x >= P_y else ds/dy, probe j at s + axis "
        "((j + 0.5) / q - 0.5), j = 0 .. q - 1, the probes' values summed in order and divided by "
        "q. Then lod += params.lod_offset (= params.lod_bias, minus log2(n) when "
        "params.sample_lod: each sample then has its own footprint, as a render at n times the "
        "resolution; else every sample of a pixel has the pixel's lod). Levels: lod clamped to "
        "[0, L - 1], k0 = floor(lod), k1 = min(k0 + 1, L - 1), w = lod - k0; " + _BILINEAR + ". "
        "params.objects[o].per_level false (params.mip 'trilinear' and no tone correction): per "
        "probe S = (1 - w) B_k0 + w B_k1 (the second term only where w > 0), then the probe mean. "
        "params.objects[o].per_level true (params.mip 'per_level', or "
        "params.objects[o].equalize): the two level values S0 = B_k0 and S1 = B_k1 (each a probe "
        "mean) are thresholded apart (halftone-threshold); with params.objects[o].equalize "
        "(params.tone_correct, never for stroke screens) each is first mapped through its level's "
        "row of the role params.objects[o].tone_lut_role: S_k = interp(S_k, linspace(0, 1, C), "
        "row k) (C columns; piecewise linear, clamped at the ends)."
    ),
    "halftone-threshold": (
        "Threshold (Freudenberg sec. 3) of a screen value S and the intensity I: binary "
        "(params.threshold 'binary', sec. 3.1): out = 1 if S + (I - 0.5) > 0.5 else 0; smooth "
        "(sec. 3.2): out = clip(top - (1 - S - I) c, 0, 1) with top = 0.5 when params.centred or "
        "params.c_mode is 'fwidth', else 1, and c = params.c (c_mode 'constant') or, c_mode "
        "'fwidth', per sample c = 1 / max(fw, 1e-6), fw = sum over d in (ds/dx / n, ds/dy / n) (n "
        "= params.samples_per_axis; the screen derivatives of halftone-screen-lookup) of |S3(s + "
        "d) - S3(s - d)| / 2, S3 the trilinear probe-mean lookup at the sample's lod (whatever "
        "params.mip). params.objects[o].per_level: out = (1 - w) out(S0) + w out(S1); else "
        "out(S). Colour (params.show 'color'): rgb = clip(out paper + (1 - out) ink, 0, 1) per "
        "channel (params.paper, params.ink), alpha 1; samples outside every object (mesh_id < 0): "
        "(0, 0, 0, 0). params.show 'screen', 'intensity', 'normals': the value x (the trilinear "
        "probe-mean S3 / I after the indication map / the normal map's RGB, (0.5, 0.5, 1) without "
        "a normal map) as the grey srgb_to_linear(clip(x, 0, 1)) per channel, srgb_to_linear(x) = "
        "x / 12.92 for x <= 0.04045, else ((x + 0.055) / 1.055)^2.4 (the displayed sRGB grey is "
        "x), alpha 1 on covered samples, (0, 0, 0, 0) elsewhere."
    ),
}


def export(style: Any, scene: Any, case_dir: Path, *, width: int, height: int, spp: int):
    """Resolved params and texture files of a ``halftone`` style for ``scene`` (the layout in
    the module docstring)."""
    if getattr(style, "name", None) != "halftone":
        raise TypeError(f"style: expected a halftone style, got {type(style).__name__}")
    n_axis = int(round(math.sqrt(spp)))
    if n_axis * n_axis != spp:
        raise ValueError(f"spp: expected a square number n * n, got {spp!r}")
    from refnpr.styles.halftone.params import PARAMS

    p = style.p
    case_dir = Path(case_dir)
    specs = style.object_specs(scene)
    textures: dict[str, dict] = {}
    roles: dict[str, int] = {}
    objects = []
    per_level = p.mip == "per_level"
    for k, obj in enumerate(scene.objects):
        spec = specs[k]
        key = json.dumps(spec, sort_keys=True) + "|" + str(obj.material.texture)
        screen = style.screen_for(spec, obj.material.texture)
        equalize = bool(p.tone_correct and screen.kind != "strokes")
        if key not in roles:
            i = roles[key] = len(roles)
            textures[f"screen-{i}"] = write_pyramid(
                case_dir,
                f"screen-{i}",
                screen.pyramid.levels,
                filter="per_level" if (per_level or equalize) else "linear_mipmap_linear",
                used_for=f"halftone screen ({screen.kind}) of object(s) using spec {spec}",
            )
            if screen.normals is not None:
                textures[f"normals-{i}"] = write_pyramid(
                    case_dir,
                    f"normals-{i}",
                    screen.normals.levels,
                    filter="linear_mipmap_linear",
                    used_for="RGB-encoded stroke normal map (sec. 5.2 DOT3 stroke lighting)",
                )
            if equalize:
                textures[f"tone-lut-{i}"] = write_table(
                    case_dir,
                    f"tone-lut-{i}",
                    style._luts(screen),
                    orientation=(
                        "row k = mip level k; column j = CDF at x = j / (cols - 1); apply by "
                        "linear interpolation (numpy.interp)"
                    ),
                    used_for="tone_correct: per-level CDF of the bilinearly sampled screen",
                )
        i = roles[key]
        settings = style.objects.get(obj.name, {})
        scale = settings.get("uv_scale") or style.uv_scale or obj.material.uv_scale
        imap = settings.get("indication", style.indication)
        ind_role = None
        if imap is not None:
            ind_role = f"indication-{k}"
            textures[ind_role] = write_table(
                case_dir,
                ind_role,
                imap,
                filter="linear",
                orientation=ORIENTATION_ROW0_V0,
                used_for=f"signed indication map of object {obj.name!r} (sec. 5.1), added to I",
            )
        objects.append(
            {
                "name": obj.name,
                "screen": {
                    "kind": screen.kind,
                    "role": f"screen-{i}",
                    "normals_role": f"normals-{i}" if screen.normals is not None else None,
                    "direction": None
                    if screen.direction is None
                    else [float(x) for x in screen.direction],
                    "source_spec": spec,
                },
                "uv_scale": [float(s) for s in scale],
                "anisotropy": int(p.anisotropy if screen.direction is None else 1),
                "indication_role": ind_role,
                "indication_scale": [float(s) for s in settings.get("indication_scale") or (1, 1)],
                "equalize": equalize,
                "tone_lut_role": f"tone-lut-{i}" if equalize else None,
                "per_level": bool(per_level or equalize),
            }
        )
    auto = p.c == "auto"
    resolved = PARAMS.resolved(p)  # the declared values (None where the modes do not read them)
    params: dict[str, Any] = {
        "threshold": resolved["threshold"],
        "c": None if auto else float(p.c),
        "c_mode": "fwidth" if auto else "constant",
        "centred": bool(p.centred or auto),
        **{k: resolved[k] for k in ("specular", "ink", "paper", "lod_bias", "sample_lod")},
        "lod_offset": float(p.lod_bias - (math.log2(n_axis) if p.sample_lod else 0.0)),
        "samples_per_axis": n_axis,
        **{k: resolved[k] for k in ("mip", "tone_correct", "anisotropy", "show")},
        "luma": [float(x) for x in LUMA_709],
        "objects": objects,
    }
    params = jsonable(params, where="style 'halftone' params")
    return StyleExport(params=params, textures=textures, derived=dict(DERIVED))

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

__all__ = ["export"]

_DERIVED = {
    "halftone-intensity": (
        "Target intensity per sample (Freudenberg sec. 3, lighting of Veryovka eq. 1): "
        "I = clip(luma . (m_a l_a + sum_i m_d f_d l_i + sum_i m_s f_s l_i), 0, 1) with luma = "
        "params.luma (Rec. 709), f_d = min(max(N.L, 0), 1) with N the G-buffer normal and L the unit "
        "direction towards the light (point lights: normalize(position - P)), f_s Blinn-Phong "
        "max(N.H, 0)^shininess clipped to [0, 1] with H = normalize(L + V), V = normalize(eye - "
        "P), and f_s = 0 where N.L <= 0; the specular sum only when params.specular. With a stroke "
        "normal map (screen.normals_role) f_d is replaced, where the tangent frame is valid, by "
        "clip(normalize(2 nmap - 1) . normalize(L.T, L.B, L.N), 0, 1) (sec. 5.2), nmap the "
        "filtered normal map at the screen coordinates and LOD. T, B: dP/du = (dP/dx dv/dy - "
        "dP/dy dv/dx) / det, dP/dv = (dP/dy du/dx - dP/dx du/dy) / det with det = du/dx dv/dy - "
        "du/dy dv/dx of the UNSCALED uv derivatives, then Gram-Schmidt against N (T first, B "
        "against N and T); invalid where |det| <= 1e-20 or a tangent length <= 1e-30 "
        "(refnpr/styles/halftone/shading.py)."
    ),
    "halftone-screen-lookup": (
        "Screen coordinates: s = uv * uv_scale (engraving: (s . direction, 0.5), derivatives "
        "(ds/dx . direction, 0) and likewise for y). LOD: P = |d/dx * size|, |d/dy * size| in "
        "level-0 texels ((cols, rows)); anisotropy 1: lod = log2(max(P)); N > 1: probes = "
        "clip(ceil(Pmax/Pmin - 1e-9), 1, N), lod = log2(Pmax / probes), the mean of probes "
        "trilinear samples at s + axis ((j + 1/2)/probes - 1/2), axis = the longer derivative "
        "vector (dx on ties). Then lod += lod_offset. Trilinear: lod clamped to [0, L-1], "
        "k0 = floor, k1 = min(k0 + 1, L-1), bilinear GL_REPEAT with texel centres at (i + 0.5)/"
        "size on each level, weight frac(lod). per_level: threshold the two level samples "
        "separately and blend the results with frac(lod); equalize: first map each level "
        "sample v through its level's tone LUT row (linear interpolation at v * 2047, clamped)."
    ),
    "halftone-threshold": (
        "binary: white where screen + (I - 0.5) > 0.5 (sec. 3.1); smooth: clip(top - c (1 - "
        "screen - I), 0, 1), top = 0.5 when centred else 1 (sec. 3.2); c_mode fwidth: c = 1 / "
        "max(fw, 1e-6), fw = sum over d in (ds/dx / n, ds/dy / n) of |S(s + d) - S(s - d)| / 2 "
        "(S the filtered screen, n samples per pixel axis), top = 0.5. I first gets the "
        "indication map: I = clip(I + ind(uv * indication_scale), 0, 1), ind bilinear clamp-to-"
        "edge with texel centres at (i + 0.5)/size. Output colour: paper * t + ink * (1 - t); "
        "show screen / intensity: the raw value x as the linear grey whose sRGB encoding is x; "
        "show normals: the normal map's RGB the same way ((0.5, 0.5, 1) without a normal map)."
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
    return StyleExport(params=params, textures=textures, derived=dict(_DERIVED))

"""Kit export of the ``xtoon`` style (Barla, Thollot, Markosian 2006).

Every parameter is resolved by the style's own code: the 2D toon texture (preset, recipe, image
or array) is :attr:`XToonStyle.texture`, exported as the texture ``toon``; the frame-dependent
defaults of the attribute map (z_min, r, and z_c of the focus map) come from
:func:`refnpr.styles.xtoon.detail.style_record` for the case's camera; the abstracted normals of
the shape (smoothed, ellipsoid, cylinder, sphere) from the style's own evaluation path
(:func:`refnpr.styles.xtoon.evaluation._abstract`), exported per vertex as ``_ABSTRACT_NORMAL``.

Params layout (``case.json`` ``style.params``): every parameter of the style's declaration
(:data:`refnpr.styles.xtoon.params.PARAMS`, ``Params.resolved``) in its order, null where the
detail map does not read it, with ``texture`` the role "toon", z_min and r resolved for the
frame, ``prev_camera`` as {eye, target, up, fov_y, near, far, view_matrix, projection_matrix},
``detail_map`` a role, ``shape_weight`` {kind: global | detail | texture | map, value, texture
(role), uv_scale} (and no ``prev_transforms``: a kit moves cameras, not objects); then
texture_spec (what the scene file said, for reference), z_focus,
flow_behind, tiny and abstract_normal_attribute.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from .._json import jsonable
from ..camera import camera_entry
from ..textures import ORIENTATION_ROW0_TOP, write_pyramid, write_table
from . import _generic
from ._export import StyleExport

__all__ = ["export", "derived", "unresolved", "DERIVED"]

#: The name of the per-vertex abstracted normal attribute (glTF ``_ABSTRACT_NORMAL``).
ABSTRACT_NORMAL = "abstract_normal"

DERIVED = {
    "xtoon-tone": (
        "Tone (X-Toon sec. 3), per covered sample (mesh_id >= 0), in float64: tone = clip(n . "
        "l, 0, 1) (params.tone 'clamped') or (n . l + 1) / 2 ('half_lambert', not clipped: the "
        "lookup clips it), n the unit shading normal (without shape abstraction n = "
        "normalize(the normal channel), a zero normal staying zero; else xtoon-shape), l the "
        "unit direction towards the light case.lights[params.light]: its direction "
        "(directional) or normalize(light.position - P) (point; P the position channel), "
        "normalize(v) = v / |v|."
    ),
    "xtoon-detail": (
        "Detail D of params.detail (sec. 3.1, 3.2, 5), each clamped to [0, 1], from a point P "
        "with unit normal n (per sample: the position channel and the shading normal; per "
        "vertex in xtoon-vertex-mode). 'depth': z = the view-axis distance (params.distance "
        "'axis': the depth channel per sample, -(row 2 of view_matrix . (P, 1)) per vertex) or "
        "|P - camera.eye| ('eye'), z = max(z, params.tiny), D = clip(1 - ln(z / params.z_min) / "
        "ln(params.r), 0, 1) (z_min and r resolved for this frame). 'focus': the same z, z_c = "
        "params.z_focus: z < z_c: D = clip(1 - ln(z / (z_c - z_min)) / ln((z_c - r z_min) / (z_c "
        "- z_min)), 0, 1), else D = clip(1 - ln(z / (z_c + z_min)) / ln((z_c + r z_min) / (z_c + "
        "z_min)), 0, 1). 'orientation': v = (camera.eye - P) / max(|camera.eye - P|, "
        "params.tiny), D = min(|clip(n . v, -1, 1)|, 1)^params.r. 'highlight': l as in "
        "xtoon-tone, refl = 2 (n . l) n - l, x = clip(v . refl, -1, 1), D = min(|x|, 1)^params.s "
        "(params.one_sided: max(x, 0)^params.s). 'flow': f = pix(P, camera) - pix(P, "
        "params.prev_camera), pix the continuous pixel position of P through projection_matrix "
        "@ view_matrix of the W x H IMAGE (x = (x_c / w + 1) W / 2, y = (1 - y_c / w) H / 2; not "
        "the sample grid); f = (params.flow_behind, 0) where w <= 0 for either camera; D = 1 - "
        "clip((|f| - params.flow_min) / (params.flow_max - params.flow_min), 0, 1). 'map': D = "
        "the texture role params.detail_map at the pixel (an H x W map) or the sample (an n H x "
        "n W map), nearest (texelFetch). 'none': D = 1."
    ),
    "xtoon-vertex-mode": (
        "params.detail_mode 'vertex' (the paper's vertex shader; the maps 'map' and 'none' stay "
        "per sample): D (for 'flow': the displacement f) is evaluated at each vertex V_k of the "
        "sample's triangle (tri_id -> object via first_tri_id, V_0, V_1, V_2 in index-buffer "
        "order) from its POSITION and its unit normal (NORMAL / |NORMAL|, zero staying zero; "
        "with shape abstraction the vertex-blended normal of xtoon-shape, normalized), with the "
        "light direction at that vertex (a point light gives each vertex its own l). Each "
        "vertex's D_k is clamped to [0, 1] BEFORE the interpolation (every map of xtoon-detail "
        "clamps); then D_s = clip(sum_k bary_k D_k, 0, 1) with the bary channel. 'flow': f_s = "
        "sum_k bary_k f_k (f_k = (params.flow_behind, 0) for a vertex behind either camera) and "
        "D_s = 1 - clip((|f_s| - params.flow_min) / (params.flow_max - params.flow_min), 0, 1)."
    ),
    "xtoon-shape": (
        "Shape abstraction (sec. 4), params.shape not null: n_abs = the vertex attribute "
        "_ABSTRACT_NORMAL (unit; objects outside params.shape_objects carry their own unit "
        "normals), n_v = NORMAL / |NORMAL|, normalize(v) = v / |v|. params.shape_blend "
        "'vertex': per vertex m = (1 - w) normalize(n_v) + w normalize(n_abs) with w = "
        "params.shape_weight.value (kind 'global'), w = 1 - D at the vertex with n_v (kind "
        "'detail', D of xtoon-detail per vertex), w = 0 (kinds 'texture' and 'map', per-sample "
        "weights); n = normalize(sum_k bary_k m_k) per sample. params.shape_blend 'pixel': n0 = "
        "normalize(the normal channel), na = sum_k bary_k n_abs(V_k); where |na| = 0: na = n0; "
        "where |n0| = 0: n0 = na, or n0 = na = (0, 0, 1) if |na| = 0 too; w per sample: the value "
        "(kind 'global'), 1 - D(n0) (kind 'detail', D of xtoon-detail per sample with n0), "
        "clip(B(uv * params.shape_weight.uv_scale), 0, 1) (kind 'texture': B the GL_LINEAR / "
        "GL_REPEAT sample of level 0 of the role params.shape_weight.texture: x = (u - floor(u)) "
        "cols - 0.5, y = (v - floor(v)) rows - 0.5, four texels modulo the size, weights (1 - "
        "f_x)(1 - f_y), f_x (1 - f_y), (1 - f_x) f_y, f_x f_y), or the map's value at the "
        "pixel / sample (kind 'map', nearest); m = (1 - w) normalize(n0) + w normalize(na), n = "
        "m / |m| where |m| > 2.2250738585072014e-308, else normalize(n0) if w < 0.5 else "
        "normalize(na). n is the shading normal of xtoon-tone and of the per-sample detail maps."
    ),
    "xtoon-lookup": (
        "Colour: the toon texture (role 'toon', rows x cols texels of RGBA, rows grow with D, "
        "columns with tone) sampled bilinearly with clamp-to-edge: x = clip(clip(tone, 0, 1) cols "
        "- 0.5, 0, cols - 1), y = clip(clip(D, 0, 1) rows - 0.5, 0, rows - 1), j0 = min(floor(x), "
        "max(cols - 2, 0)), i0 = min(floor(y), max(rows - 2, 0)), j1 = min(j0 + 1, cols - 1), i1 "
        "= min(i0 + 1, rows - 1), f_x = x - j0, f_y = y - i0, value = (t[i0][j0] (1 - f_x) + "
        "t[i0][j1] f_x) (1 - f_y) + (t[i1][j0] (1 - f_x) + t[i1][j1] f_x) f_y per channel. Output "
        "straight-alpha RGBA: rgb = clip(value_rgb (times objects[mesh_id].material.diffuse when "
        "params.modulate), 0, 1), alpha = clip(value_a, 0, 1); empty samples (mesh_id < 0) are "
        "(0, 0, 0, 0). params.show 'detail' | 'inverse_detail' | 'tone': opaque grey g = "
        "clip(srgb_to_linear(clip(x, 0, 1)), 0, 1) with x = D, 1 - D or the tone "
        "(srgb_to_linear(x) = x / 12.92 for x <= 0.04045, else ((x + 0.055) / 1.055)^2.4: the "
        "displayed sRGB grey is x)."
    ),
}

#: The texts a case carries per what it uses (the others are left out).
_ALWAYS = ("xtoon-tone", "xtoon-detail", "xtoon-lookup")


def derived(style: Any, scene: Any, *, width: int, height: int, spp: int) -> dict[str, str]:
    """The derived texts of an ``xtoon`` case: tone, detail and lookup, and the vertex mode
    and the shape abstraction where the case uses them."""
    p = style._cfg.p
    names = list(_ALWAYS)
    if p.detail_mode == "vertex":
        names.append("xtoon-vertex-mode")
    if p.shape is not None:
        names.append("xtoon-shape")
    return {k: DERIVED[k] for k in DERIVED if k in names}


def _map(case_dir: Path, role: str, array: Any, used_for: str) -> dict[str, Any]:
    """A per-pixel or per-sample map (texelFetch) as one clamped float32 level."""
    rows = " (image rows: (H, W) per pixel or (nH, nW) per sample)"
    return write_table(
        case_dir, role, array, orientation=ORIENTATION_ROW0_TOP + rows, used_for=used_for
    )


def _weight(cfg: Any, case_dir: Path, textures: dict[str, Any]) -> dict[str, Any]:
    w = cfg.p.shape_weight
    out: dict[str, Any] = {"kind": w.kind, "value": None, "texture": None, "uv_scale": None}
    if w.kind == "global":
        out["value"] = float(w.value)
    elif w.kind == "texture":
        textures["shape_weight"] = write_pyramid(
            case_dir,
            "shape_weight",
            cfg.weight_pyramid.levels[:1],
            filter="linear",
            used_for="X-Toon shape weight w at uv * uv_scale (bilinear GL_REPEAT, level 0 only)",
        )
        out["texture"] = "shape_weight"
        out["uv_scale"] = [float(s) for s in w.uv_scale]
    elif w.kind == "map":
        textures["shape_weight"] = _map(
            case_dir,
            "shape_weight",
            w.texture,
            "X-Toon shape weight w per pixel or per sample (texelFetch)",
        )
        out["texture"] = "shape_weight"
    return out


def export(
    style: Any, scene: Any, case_dir: Path, *, width: int, height: int, spp: int
) -> StyleExport:
    """params, textures (``toon``; ``detail_map`` and ``shape_weight`` where used), derived
    texts, ``_ABSTRACT_NORMAL`` per object when the style abstracts the shape, and both frames'
    cameras of a flow case (see the module docstring)."""
    from refnpr.styles.xtoon.detail import FLOW_BEHIND, TINY, style_record
    from refnpr.styles.xtoon.evaluation import _abstract, plan
    from refnpr.styles.xtoon.params import PARAMS
    from refnpr.styles.xtoon.shape import unit_rows

    if style.name != "xtoon":
        raise TypeError(f"style: expected an xtoon style, got {style.name!r}")
    cfg = style._cfg
    p = cfg.p
    # a flow style without prev_camera is frame 0 of a sequence: zero flow (the current camera)
    prev_camera = p.prev_camera if p.prev_camera is not None else scene.camera
    moved = getattr(p, "prev_transforms", None)
    if p.detail == "flow" and moved is not None:
        now = np.array([o.transform for o in scene.objects], dtype=np.float64)
        if not np.array_equal(np.asarray(moved, dtype=np.float64), now):
            raise ValueError(
                "prev_transforms: the conformance kit carries one camera per frame but no object "
                "transforms, so an X-Toon flow case with moving objects cannot be exported; move "
                "the camera instead (prev_camera), or leave the case out of the kit suite"
            )
    case_dir = Path(case_dir)
    plan(cfg, scene)  # validates the light index against the scene (clear error)
    record = style_record(p, cfg.texture, scene, scene.camera)  # the frame's z_min, r and z_c
    textures: dict[str, Any] = {}
    textures["toon"] = write_table(
        case_dir,
        "toon",
        cfg.texture,
        filter="linear",
        orientation=(
            "row i = detail D at (i + 0.5) / rows (row 0: D = 0, most abstract; rows grow with "
            "D), column j = tone at (j + 0.5) / cols (column 0 darkest); array[i, j], no flip"
        ),
        used_for="X-Toon 2D toon texture, bilinear clamp-to-edge lookup at (tone, D)",
    )
    kind = p.detail
    if kind == "map":
        textures["detail_map"] = _map(
            case_dir,
            "detail_map",
            p.detail_map,
            "X-Toon user detail map D per pixel or per sample (texelFetch)",
        )
    shaped = p.shape is not None
    spec = style.params().get("texture")
    prev_entry = camera_entry(prev_camera, width, height)
    params = PARAMS.resolved(  # every parameter, None where the detail map does not read it
        p,
        texture="toon",
        z_min=float(record.z_min),
        r=float(record.r),
        prev_camera={k: v for k, v in prev_entry.items() if k != "conventions"},
        detail_map="detail_map" if kind == "map" else None,
        shape_weight=_weight(cfg, case_dir, textures) if shaped else None,
        texture_spec=spec if isinstance(spec, (str, dict)) else str(spec),
        z_focus=float(record.focus[0]) if kind == "focus" else None,
        flow_behind=float(FLOW_BEHIND),
        tiny=float(TINY),
        abstract_normal_attribute="_" + ABSTRACT_NORMAL.upper() if shaped else None,
    )
    del params["prev_transforms"]  # the kit has no object transforms per frame (checked above)
    vertex_attributes: dict[int, dict[str, np.ndarray]] = {}
    if shaped:
        parts = _abstract(cfg, scene)
        for k, (mesh, n_abs) in enumerate(zip(scene.world_meshes(), parts, strict=True)):
            if n_abs is None:
                n_abs = unit_rows(mesh.normals)  # objects outside shape_objects keep their own
            vertex_attributes[k] = {ABSTRACT_NORMAL: np.asarray(n_abs, dtype=np.float32)}
    frames = None
    if kind == "flow":  # every frame's camera: the flow detail reads the previous one (Fig. 6)
        frames = [
            {"frame": 0, "camera": prev_entry},
            {"frame": 1, "camera": camera_entry(scene.camera, width, height)},
        ]
    return StyleExport(
        params=jsonable(params, where="style 'xtoon' params"),
        textures=textures,
        derived=derived(style, scene, width=width, height=height, spp=spp),
        vertex_attributes=vertex_attributes,
        frames=frames,
    )


def unresolved(params: dict[str, Any]) -> list[str]:
    """Key paths of exported xtoon params that only refnpr could resolve (none when exported by
    :func:`export`; ``texture_spec`` is informative only: the texture itself is ``toon``)."""
    out = _generic.unresolved({k: v for k, v in params.items() if k != "texture_spec"})
    if params.get("texture") != "toon":
        out.append(f"params.texture = {params.get('texture')!r} (expected the role 'toon')")
    return out
